"""Regenerate the results tables in docs/results.md and README.md from the runs saved in docs/results/.

    python scripts/results_tables.py            # rewrite every generated table in place
    python scripts/results_tables.py --check    # exit 1 if a table differs from its data (writes nothing)

A generated table sits between two marker lines:

    <!-- table: whole-songs-summary (scripts/results_tables.py) -->
    | ... |

    <!-- end table -->

(indented as the markers are, inside a list item) and is built by the function of that name in TABLES from the JSON files that
`scripts/evaluate_whole_songs.py --json` wrote (docs/results/whole_songs/). To change a figure, rerun
the evaluation, save its JSON there and run this script: never edit a generated table by hand.
Tables without markers are hand-written (their runs' data is not kept).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from functools import cache, partial
from pathlib import Path

import numpy as np

from choreo.metrics.songs import mean_rows, target_failures

REPO = Path(__file__).resolve().parents[1]
RUNS = REPO / "docs" / "results" / "whole_songs"
FILES = [REPO / "docs" / "results.md", REPO / "docs" / "results" / "validation.md", REPO / "README.md"]
MARKED = re.compile(r"^( *)(<!-- table: ([\w-]+) \(scripts/results_tables\.py\) -->\n)(.*?)^( *<!-- end table -->)",
                    re.S | re.M)

# Whole-song summary rows: label, run file (docs/results/whole_songs/NAME.json), columns shown in bold.
SUMMARY = [
    ("SGMD before", "sgmd-before-2026-12-05", ()),
    ("SGMD, the base model (until 2026-12-07)", "sgmd", ()),
    ("**SGMD now** (the legs' fine-tune)", "sgmd-legs", ()),
    ("ChoreoGraph before", "graph-before-2026-12-05", ()),
    ("ChoreoGraph, the base model's repertoire (until 2026-12-07)", "graph", ()),
    ("**ChoreoGraph now** (a repertoire from the legs' fine-tune)", "graph-legs", ()),
    ("SGMD before, no style", "sgmd-no-style-before-2026-12-05", ()),
    ("SGMD, the base model, no style", "sgmd-no-style", ()),
    ("SGMD now, no style", "sgmd-legs-no-style", ()),
    ("ChoreoGraph before, no style", "graph-no-style-before-2026-12-05", ()),
    ("ChoreoGraph, the base model's repertoire, no style", "graph-no-style", ()),
    ("ChoreoGraph now, no style", "graph-legs-no-style", ()),
]
README = [
    ("**SGMD, bundled model, as `choreo generate` writes it** (DDIM 10, guidance 2 on the music and 2 on "
     "the style, the travel unguided in waltz; speed limit, root path, pace, accent, footsteps, beat lock)", "sgmd-legs"),
    ("**ChoreoGraph, bundled models and repertoire, as `choreo graph` writes it** (K = 512, each seed a "
     "take, a 3 m floor; the same passes)", "graph-legs"),
    ("SGMD with the defaults until 2026-12-04 (guidance 2.5, no root path, pace or accent pass)", "sgmd-before-2026-12-05"),
]
GUIDANCE = [("1", "sgmd-guidance-1-seed-1"), ("1.5 (seeds 0-2)", "sgmd-guidance-1.5-no-pace"),
            ("2 (seeds 0-2)", "sgmd-guidance-2-no-pace"), ("2.5 (before)", "sgmd-guidance-2.5-seed-1")]
OUTSIDE = [("SGMD", "sgmd-legs"), ("ChoreoGraph", "graph-legs")]
VALIDATION = [("1.5", "validation-step10000-guidance-1.5"), ("2 (the default)", "validation-step10000-guidance-2"),
              ("2.5", "validation-step10000-guidance-2.5"),
              ("1.5, seeds 3-5", "validation-step10000-guidance-1.5-seeds-3-5"),
              ("2, seeds 3-5", "validation-step10000-guidance-2-seeds-3-5"),
              ("1.5, step 12,000", "validation-step12000-guidance-1.5"), ("2, step 12,000", "validation-step12000-guidance-2"),
              ("1.5, step 12,000, with the accent", "validation-step12000-guidance-1.5-accent"),
              ("2, step 12,000, with the accent", "validation-step12000-accent-0.2"),
              ("1.5, training seed 1, step 10,000, with the accent", "validation-seed1-step10000-guidance-1.5"),
              ("2, training seed 1, step 10,000, with the accent", "validation-seed1-step10000-guidance-2"),
              ("1.5, training seed 1, step 12,000, with the accent", "validation-seed1-step12000-guidance-1.5"),
              ("2, training seed 1, step 12,000, with the accent", "validation-seed1-step12000-guidance-2")]
VALIDATION_FINISHING = [("the defaults (3 Hz, 0.65, 1.25)", "validation-step12000-guidance-2"),
                        ("root path 2 Hz", "validation-step12000-root-path-2hz"),
                        ("root path 4 Hz", "validation-step12000-root-path-4hz"),
                        ("footsteps 0.5", "validation-step12000-footsteps-0.5"),
                        ("footsteps 0.8", "validation-step12000-footsteps-0.8"),
                        ("pace within 1.15 x", "validation-step12000-pace-1.15"),
                        ("pace within 1.4 x", "validation-step12000-pace-1.4"),
                        ("the defaults, seeds 3-5", "validation-step12000-baseline-seeds-3-5"),
                        ("root path 2 Hz, seeds 3-5", "validation-step12000-root-path-2hz-seeds-3-5"),
                        ("root path 4 Hz, seeds 3-5", "validation-step12000-root-path-4hz-seeds-3-5"),
                        ("footsteps 0.5, seeds 3-5", "validation-step12000-footsteps-0.5-seeds-3-5"),
                        ("footsteps 0.8, seeds 3-5", "validation-step12000-footsteps-0.8-seeds-3-5"),
                        ("pace within 1.15 x, seeds 3-5", "validation-step12000-pace-1.15-seeds-3-5"),
                        ("pace within 1.4 x, seeds 3-5", "validation-step12000-pace-1.4-seeds-3-5")]
VALIDATION_ACCENT = [("none (the defaults until now)", "validation-step12000-guidance-2"),
                     ("0.1", "validation-step12000-accent-0.1"), ("0.2 (the default)", "validation-step12000-accent-0.2"),
                     ("0.2, footsteps 0.75 in cha-cha and rumba (the defaults now)", "validation-step12000-latin-0.75"),
                     ("0.3", "validation-step12000-accent-0.3"),
                     ("none, seeds 3-5", "validation-step12000-baseline-seeds-3-5"),
                     ("0.2, seeds 3-5", "validation-step12000-accent-0.2-seeds-3-5")]
VALIDATION_GRAPH = [("no floor (the defaults until now)", "validation-graph-no-floor"),
                    ("floor 3 m (the default)", "validation-graph-floor-3"), ("floor 2 m", "validation-graph-floor-2"),
                    ("floor 3 m, accent 0.2", "validation-graph-floor-3-accent"),
                    ("floor 3 m, accent 0.2, footsteps 0.75 in cha-cha and rumba (the defaults now)",
                     "validation-graph-latin-0.75")]
VALIDATION_LATIN = [("SGMD, 0.65 (the default until now)", "validation-latin-footsteps-0.65"),
                    ("SGMD, 0.75 (the default now)", "validation-latin-footsteps-0.75"),
                    ("SGMD, 0.85", "validation-latin-footsteps-0.85"), ("SGMD, 1", "validation-latin-footsteps-1"),
                    ("SGMD, 0.65, seeds 3-5", "validation-latin-footsteps-0.65-seeds-3-5"),
                    ("SGMD, 0.75, seeds 3-5", "validation-latin-footsteps-0.75-seeds-3-5"),
                    ("ChoreoGraph, 0.65", "validation-graph-latin-footsteps-0.65"),
                    ("ChoreoGraph, 0.75", "validation-graph-latin-footsteps-0.75"),
                    ("ChoreoGraph, 0.85", "validation-graph-latin-footsteps-0.85")]
VALIDATION_TRAVEL = [("1, every genre (the default until now)", "validation-travel-guided"),
                     ("0.5, every genre", "validation-travel-0.5"), ("0, every genre", "validation-travel-0"),
                     ("0.5 in waltz, 1 in cha-cha and rumba", "validation-travel-0.5-waltz"),
                     ("0 in waltz, 1 in cha-cha and rumba (the default now)", "validation-travel-0-waltz"),
                     ("1, seeds 3-5", "validation-travel-guided-seeds-3-5"),
                     ("0.5, seeds 3-5", "validation-travel-0.5-seeds-3-5"), ("0, seeds 3-5", "validation-travel-0-seeds-3-5"),
                     ("0.5 in waltz, seeds 3-5", "validation-travel-0.5-waltz-seeds-3-5"),
                     ("0 in waltz, seeds 3-5", "validation-travel-0-waltz-seeds-3-5"),
                     ("1, training seed 1", "validation-seed1-travel-guided"),
                     ("0.5 in waltz, training seed 1", "validation-seed1-travel-0.5-waltz"),
                     ("0 in waltz, training seed 1", "validation-seed1-travel-0-waltz")]


@cache
def run(name: str) -> dict:
    """A saved run of scripts/evaluate_whole_songs.py."""
    return json.loads((RUNS / f"{name}.json").read_text())


def run_means(name: str) -> dict:
    """The run's figures: per song the mean over seeds, then the mean over songs."""
    return mean_rows([mean_rows(song["seeds"]) for song in run(name)["songs"].values()])


def real_means() -> dict:
    """The real dancers' figures, mean over the songs (the same songs in every run)."""
    return mean_rows([song["real"] for song in run("sgmd")["songs"].values()])


def fid(figure: list[float], interval: bool = True) -> str:
    """An FID to one decimal, with its 95 % bootstrap interval."""
    return f"{figure[0]:.1f} [{figure[1]:.1f}, {figure[2]:.1f}]" if interval else f"{figure[0]:.1f}"


def table(header: list[str], align: list[str], rows: list[list[str]]) -> str:
    """A Markdown table; align holds '---' or '---:' per column."""
    lines = [header, align, *rows]
    return "".join("| " + " | ".join(cells) + " |\n" for cells in lines)


def bolded(cells: dict, bold: tuple) -> dict:
    return {key: f"**{value}**" if key in bold else value for key, value in cells.items()}


def summary_cells(means: dict, fids: dict, misses: str) -> dict:
    """One summary row's cells by column."""
    return {"pace": f"{means['pace']:.3f}", "reach": f"{means['reach']:.2f}", "planted": f"{means['planted']:.3f}",
            "foot_root": f"{means['foot_root']:.3f}", "jerk": f"{means['jerk']:.0f}",
            "root_jerk": f"{means['root_jerk']:.0f}", "body_jerk": f"{means['body_jerk']:.0f}",
            "beat_dip": f"{means['beat_dip']:.3f}", "fid_k": fid(fids["fid_k"]), "fid_g": fid(fids["fid_g"]),
            "misses": misses}


def whole_songs_summary() -> str:
    """docs/results.md, "Whole songs": means over the test songs of each run, FIDs, targets missed."""
    header = ["dancer", "pace m/s", "reach m", "planted", "foot~root", "jerk", "root jerk", "body jerk", "beat dip",
              "FID_k", "FID_g", "targets missed"]
    rows = [["real dancers to the same songs", *summary_cells(real_means(), run("sgmd")["real_fid"], "").values()]]
    for i, (label, name, bold) in enumerate(SUMMARY):
        songs = run(name)["songs"]
        misses = f"{len(target_failures(songs))}" + (f" of {6 * len(songs)}" if i == 0 else "")
        rows.append([label, *bolded(summary_cells(run_means(name), run(name)["fid"], misses), bold).values()])
    return table(header, ["---"] + ["---:"] * 8 + ["---"] * 2 + ["---:"], rows)


def first_takes(runs: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """The runs of seeds 0-2 on the first training seed: the rest (the same settings again) live in
    docs/results/validation.md's full tables."""
    return [(label, name) for label, name in runs if "seeds 3-5" not in label and "training seed" not in label]


def validation_table(title: str, runs: list[tuple[str, str]], full: bool = False) -> str:
    """Runs on the validation clips, real dancers first: means over songs, FIDs, targets missed."""
    runs = runs if full else first_takes(runs)
    header = [title, "pace m/s", "reach m", "planted", "foot~root", "jerk", "root jerk", "body jerk",
              "beat dip", "FID_k", "FID_g", "targets missed"]
    first = run(runs[0][1])
    real = mean_rows([song["real"] for song in first["songs"].values()])
    rows = [["real dancers to the same songs", *summary_cells(real, first["real_fid"], "").values()]]
    for label, name in runs:
        songs = run(name)["songs"]
        misses = f"{len(target_failures(songs))} of {6 * len(songs)}"
        rows.append([label, *summary_cells(run_means(name), run(name)["fid"], misses).values()])
    return table(header, ["---"] + ["---:"] * 8 + ["---"] * 2 + ["---:"], rows)


def readme_results() -> str:
    """README.md, "Results": the whole-song summary's main rows, fewer columns."""
    columns = ["pace", "planted", "foot_root", "jerk", "beat_dip"]
    real = summary_cells(real_means(), run("sgmd")["real_fid"], "")
    rows = [["real dancers to the same songs (the reference)", *(real[c] for c in columns),
             fid(run("sgmd")["real_fid"]["fid_k"], False), fid(run("sgmd")["real_fid"]["fid_g"], False)]]
    for label, name in README:
        cells = summary_cells(run_means(name), run(name)["fid"], "")
        rows.append([label, *(cells[c] for c in columns), cells["fid_k"], cells["fid_g"]])
    header = ["dancer", "pace", "planted", "foot~root", "jerk", "beat dip", "FID_k", "FID_g"]
    return table(header, ["---"] + ["---:"] * 5 + ["---"] * 2, rows)


def per_song_cells(mean: dict, real: dict, waltz: bool) -> list[str]:
    """One generator's cells for a song: generated / real (real waltz jerk left out: 5.9 fps keyframes)."""
    pair = lambda key, f: f"{mean[key]:{f}} / {real[key]:{f}}"  # noqa: E731
    return [f"{mean['pace']:.2f} ({mean['pace'] / real['pace']:.2f})", pair("reach", ".1f"), pair("planted", ".2f"),
            pair("foot_root", ".2f"), f"{mean['jerk']:.0f}" if waltz else pair("jerk", ".0f"), pair("beat_dip", ".2f")]


def whole_songs_per_song() -> str:
    """docs/results.md, "Whole songs": each test song, SGMD's and the graph's figures beside the real dancer's."""
    sgmd, graph = run("sgmd-legs")["songs"], run("graph-legs")["songs"]
    rows = [[name, *per_song_cells(mean_rows(entry["seeds"]), entry["real"], entry["genre"] == "waltz"),
             *per_song_cells(mean_rows(graph[name]["seeds"]), entry["real"], entry["genre"] == "waltz")]
            for name, entry in sgmd.items()]
    cells = ["reach m", "planted", "foot~root", "jerk", "beat dip"]
    return table(["song", "SGMD pace (x real)", *cells, "graph pace (x real)", *cells], ["---"] * 13, rows)


def whole_songs_outside() -> str:
    """docs/results.md, "Whole songs": the outside song, each style (mean over seeds)."""
    targets = json.loads((RUNS / "outside-song-target-paces.json").read_text())
    rows = []
    for generator, name in OUTSIDE:
        for style, seeds in next(iter(run(name)["outside"].values())).items():
            m = mean_rows(seeds)
            rows.append([f"{generator}, {'no style' if style == 'none' else style}", f"{targets[style]:.3f}",
                         f"{np.mean([s['model_pace'] for s in seeds]):.3f}", f"{m['pace']:.3f}", f"{m['reach']:.1f}",
                         f"{m['planted']:.3f}", f"{m['foot_root']:.3f}", f"{m['jerk']:.0f}", f"{m['beat_dip']:.3f}"])
    header = ["dancer, style", "real pace", "model's own pace", "pace", "reach m", "planted", "foot~root", "jerk",
              "beat dip"]
    return table(header, ["---"] + ["---:"] * 8, rows)


def whole_songs_guidance() -> str:
    """docs/results.md, "Sampler and guidance": music guidance on whole songs."""
    rows = []
    for label, name in GUIDANCE:
        means, fids = run_means(name), run(name)["fid"]
        rows.append([label, f"{means['pace']:.3f}", f"{means['planted']:.3f}", fid(fids["fid_k"]), fid(fids["fid_g"]),
                     f"{len(target_failures(run(name)['songs']))}"])
    header = ["music guidance", f"pace m/s (real {real_means()['pace']:.3f})", "planted", "FID_k", "FID_g",
              "targets missed"]
    return table(header, ["---:"] * 3 + ["---"] * 2 + ["---:"], rows)


# The legs issue's table: label, run file. Ratios to the real dancer of each song (foot jerk: a waltz against
# the Latin songs' mean, as the whole-song jerk target does, since real waltz is captured at 5.9 fps).
LEGS = [("SGMD, the base model (until 2026-12-07)", "sgmd-base-legs-measures"),
        ("SGMD, the base model alone (every finishing pass off)", "sgmd-base-raw"),
        ("**SGMD now**, as `choreo generate` writes it", "sgmd-legs"), ("SGMD now, no style", "sgmd-legs-no-style"),
        ("SGMD now, the model alone", "sgmd-legs-raw"),
        ("ChoreoGraph, the base model's repertoire", "graph-base-legs-measures"),
        ("**ChoreoGraph now**, as `choreo graph` writes it", "graph-legs"), ("ChoreoGraph now, no style", "graph-legs-no-style"),
        ("ChoreoGraph now, its clips alone (every finishing pass off)", "graph-legs-raw")]


def legs_ratios(name: str, column: str) -> list[float]:
    """Per song, the mean over seeds of ``column`` over the real dancer's (foot jerk: see LEGS)."""
    songs = run(name)["songs"]
    latin = float(np.mean([v["real"][column] for v in songs.values() if v["genre"] != "waltz"]))
    return [mean_rows(v["seeds"])[column] / (latin if column == "foot_jerk" and v["genre"] == "waltz" else v["real"][column])
            for v in songs.values()]


def whole_songs_legs() -> str:
    """The legs measures per run: mean over songs of each song's ratio to real, and the worst song."""
    rows = []
    for label, name in LEGS:
        cells = [label]
        for column, worst in (("feet_speed", min), ("ankle_lift", min), ("pelvis_speed", max), ("foot_jerk", max)):
            ratios = legs_ratios(name, column)
            cells.append(f"{np.mean(ratios):.2f} ({worst(ratios):.2f})")
        margins = [mean_rows(v["seeds"])["foot_root"] - v["real"]["foot_root"] for v in run(name)["songs"].values()]
        classifier = run(name).get("classifier", {}).get("latin", {}).get("accuracy", float("nan"))
        cells += [f"{np.mean(margins):+.3f} ({max(margins):+.3f})", f"{run_means(name)['slide']:.3f}", f"{classifier:.2f}"]
        rows.append(cells)
    header = ["dancer", "feet speed x real (worst song)", "ankle lift x real (worst)", "pelvis speed x real (worst)",
              "foot jerk x real (worst)", "foot~root - real (worst)", "slide", "classifier, Latin"]
    return table(header, ["---"] + ["---:"] * 7, rows)

# Tables of runs on the validation clips (validation_table): name -> (first column's title, runs). Each stands in
# docs/results.md under the default it decided ("Sampler and guidance", "The travel's guidance", "Finishing passes",
# "Accent", "Feet", "The graph's floor") or, not kept, in the journal.
VALIDATION_TABLES = {
    "whole-songs-validation": ("music guidance", VALIDATION),
    "whole-songs-validation-finishing": ("finishing (root path cut-off, footsteps strength, pace bound)", VALIDATION_FINISHING),
    "whole-songs-validation-accent": ("accent depth", VALIDATION_ACCENT),
    "whole-songs-validation-graph": ("ChoreoGraph", VALIDATION_GRAPH),
    "whole-songs-validation-latin": ("footsteps strength, cha-cha and rumba", VALIDATION_LATIN),
    "whole-songs-validation-travel": ("guidance on the travel (share)", VALIDATION_TRAVEL),
}
TABLES = {"whole-songs-summary": whole_songs_summary, "whole-songs-per-song": whole_songs_per_song,
          "whole-songs-outside": whole_songs_outside, "whole-songs-guidance": whole_songs_guidance,
          "readme-results": readme_results, "whole-songs-legs": whole_songs_legs,
          **{name: partial(validation_table, *table) for name, table in VALIDATION_TABLES.items()},
          **{f"{name}-full": partial(validation_table, *table, full=True) for name, table in VALIDATION_TABLES.items()}}


def regenerated(text: str) -> str:
    """The file's text with every marked table rebuilt (an unknown table name is an error)."""
    def rebuild(match: re.Match) -> str:
        indent, start, name, _, end = match.groups()
        if name not in TABLES:
            raise SystemExit(f"results_tables: no table named {name!r}")
        rows = "".join(indent + line for line in TABLES[name]().splitlines(keepends=True))
        return indent + start + rows + "\n" + end  # a blank line ends the table before the marker
    return MARKED.sub(rebuild, text)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only report tables that differ; exit 1 if any")
    args = parser.parse_args()
    stale = []
    for path in FILES:
        text = path.read_text()
        new = regenerated(text)
        if new != text:
            stale.append(path.relative_to(REPO))
            if not args.check:
                path.write_text(new)
    verb = "differ from their data" if args.check else "rewritten"
    print(f"{', '.join(map(str, stale))}: tables {verb}" if stale else "every generated table is up to date")
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
