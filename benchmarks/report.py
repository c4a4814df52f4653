"""The quality, style-adherence, speed and memory report of both generators, in one command.

    python benchmarks/report.py [--out docs/dev/report.md] [--edge generators/choreo_sgmd/weights/sgmd-edge-m2d.pt] [--quick]

On the M2D test split (213 windows of 5 s, scored against the train split as the reference row):
ground truth; a nearest-neighbour retrieval baseline (the train window whose music features are
closest, its motion played as is); SGMD without style (a model trained without any style input,
the EDGE-equivalent ablation); the bundled SGMD without guidance, with guidance on the music only,
and with its default guidance (music and style); ChoreoGraph with the bundled
models and a repertoire cut from the M2D train split. Style adherence: a genre classifier trained
on real train windows, its accuracy on real test windows, then the share of each method's windows
it recognises as the genre asked for. Beat-rate lock on songs from outside M2D whose tempo is
known (LMMS's demo songs, benchmarks/beat_lock.py; skipped with a note where LMMS is not
installed). Then speed and peak memory of both generators for 10 s, 60 s and 10 min songs.
Writes the markdown report and its plots (``--out`` folder + report/).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from choreo.datasets import TEST, TRAIN, load_dataset
from choreo.generator import GenerationRequest
from choreo.metrics import Dance
from choreo.metrics.genre import GenreClassifier
from choreo.metrics.protocol import (TABLE_HEADER, ScoringSet, music_beats, score, score_generator, scoring_windows,
                                     table_row, windows_as_dances)
from choreo.music import Music

from beat_lock import dance_outside_songs, m2d_dancers, markdown as beat_lock_table
from common import REPO, cli_peak_rss, write_song

EDGE_CHECKPOINT = REPO / "generators" / "choreo_sgmd" / "weights" / "sgmd-edge-m2d.pt"


def retrieval_dances(train_windows, test_windows) -> list[Dance]:
    """For each test window, the train window with the closest music (standardised 35-d features)."""
    train_music = np.stack([w.features.reshape(-1) for w in train_windows])
    mean, std = train_music.mean(0), train_music.std(0) + 1e-6
    bank = (train_music - mean) / std
    dances = []
    for w in test_windows:
        nearest = int(np.argmin(np.square(bank - (w.features.reshape(-1) - mean) / std).sum(1)))
        dances.append(Dance(f"{w.clip}@{w.start_frame}", train_windows[nearest].motion.joint_positions(),
                            music_beats(w.features)))
    return dances


SGMD_GUIDANCE_ROWS = {  # label: sampling options (the rest: the defaults)
    "SGMD bundled, no guidance": {"guidance": 1.0, "style_guidance": 1.0},
    "SGMD bundled, guidance 2 on the music only (the default until 2026-12-04)": {"guidance": 2.0, "style_guidance": 1.0},
    "SGMD bundled, default (guidance 2.5 on the music, t/T <= 0.6, and 2 on the style)": {},
}


def sgmd_dances(checkpoint: Path, scoring: ScoringSet, options: dict, with_style: bool) -> list[Dance]:
    from choreo import load_backend

    return score_generator(load_backend("sgmd", checkpoint), scoring, with_style=with_style, options=options)[1]


def graph_dances(train_clips, scoring: ScoringSet) -> list[Dance]:
    from choreo_graph import dataset_generator

    generator = dataset_generator(train_clips, 60, "M2D train")  # a repertoire cut from the train split, not the bundled one
    return score_generator(generator, scoring, with_style=False)[1]


def speed_and_memory(durations: list[float], folder: Path) -> list[tuple]:
    """(generator, song seconds, generation seconds, peak RSS MiB of the whole CLI run) per case."""
    from choreo import load_backend

    generators = {"sgmd": load_backend("sgmd"), "graph": load_backend("graph")}  # the bundled models
    rows = []
    for seconds in durations:
        song = write_song(folder, seconds)
        music = Music.from_file(song)
        for name, generator in generators.items():
            started = time.perf_counter()
            generator.generate(GenerationRequest(music, style="cha-cha" if name == "sgmd" else None))
            took = time.perf_counter() - started
            command = ["generate", song, "-o", folder / "out.npz", "--style", "cha-cha"] if name == "sgmd" else \
                ["graph", song, "-o", folder / "out.npz"]
            rss, wall = cli_peak_rss(command)
            rows.append((name, seconds, took, rss, wall))
            print(f"  {name} {seconds:g} s: {took:.2f} s, {rss:.0f} MiB", flush=True)
    return rows


def plot_quality(rows: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(rows)
    figure, axes = plt.subplots(1, 3, figsize=(13, 3.6), dpi=110)
    for ax, (metric, label) in zip(axes, [("fid_k", "FID_k (lower is better)"), ("fid_g", "FID_g (lower is better)"),
                                          ("beat_align", "BeatAlign (real = dashed)")]):
        values = [getattr(rows[n], metric) for n in names]
        ax.barh(names, values, color=["#888" if n.startswith("real") else "#3a6fd8" for n in names])
        ax.set_title(label, fontsize=10)
        if metric == "beat_align":
            ax.axvline(getattr(rows[names[0]], metric), color="#eb802a", linestyle="--")
        ax.invert_yaxis()
        if ax is not axes[0]:
            ax.set_yticklabels([])
    figure.tight_layout()
    figure.savefig(path)
    plt.close(figure)


def plot_speed(rows: list[tuple], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 2, figsize=(10, 3.4), dpi=110)
    for name, color in (("sgmd", "#3a6fd8"), ("graph", "#eb802a")):
        mine = [r for r in rows if r[0] == name]
        axes[0].plot([r[1] / 60 for r in mine], [r[2] for r in mine], "o-", color=color, label=name)
        axes[1].plot([r[1] / 60 for r in mine], [r[3] for r in mine], "o-", color=color, label=name)
    axes[0].set(xlabel="song (min)", ylabel="generation (s)", title="time to dance")
    axes[1].set(xlabel="song (min)", ylabel="peak RSS (MiB)", title="memory of a whole CLI run")
    for ax in axes:
        ax.legend()
        ax.grid(alpha=0.3)
    figure.tight_layout()
    figure.savefig(path)
    plt.close(figure)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "dev" / "report.md")
    parser.add_argument("--edge", type=Path, default=EDGE_CHECKPOINT)
    parser.add_argument("--durations", type=float, nargs="+", default=[10, 60, 600])
    args = parser.parse_args()
    import choreo_sgmd

    torch.manual_seed(0)
    started = time.perf_counter()
    clips = load_dataset(args.data)
    train = [c for c in clips if c.split == TRAIN]
    test = [c for c in clips if c.split == TEST]
    scoring = ScoringSet.from_clips(clips)
    windows, train_windows, reference = scoring.windows, scoring_windows(train), scoring.reference
    genres = [w.genre for w in windows]

    print("quality...", flush=True)
    sets = {"real test motion (the reference)": windows_as_dances(test),
            "retrieval baseline (nearest train music)": retrieval_dances(train_windows, windows)}
    if args.edge.is_file():
        sets["SGMD without style (EDGE-equivalent ablation: 6,000 steps of the earlier recipe; the bundled model has 12,000)"] = sgmd_dances(args.edge, scoring, {"guidance": 2.0}, False)
    for label, options in SGMD_GUIDANCE_ROWS.items():
        sets[label] = sgmd_dances(choreo_sgmd.DEFAULT_CHECKPOINT, scoring, options, True)
    sets["ChoreoGraph bundled models, M2D-train repertoire"] = graph_dances(train, scoring)
    reports = {name: score(dances, reference) for name, dances in sets.items()}

    print("style adherence...", flush=True)
    classifier = GenreClassifier.fit([w.motion.joint_positions() for w in train_windows], [w.genre for w in train_windows])
    adherence = {name: classifier.agreement([d.positions for d in dances], genres) for name, dances in sets.items()}

    print("beat-rate lock on outside songs...", flush=True)
    outside = dance_outside_songs(60.0)
    lock_lines = (beat_lock_table(outside, m2d_dancers(clips)) if outside else
                  ["Not measured in this run: LMMS is not installed (`apt-get install lmms`, then run again)."])

    print("speed and memory...", flush=True)
    with tempfile.TemporaryDirectory() as folder:
        speed_rows = speed_and_memory(args.durations, Path(folder))

    plots = args.out.parent / "report"
    plots.mkdir(parents=True, exist_ok=True)
    plot_quality(reports, plots / "quality.png")
    plot_speed(speed_rows, plots / "speed.png")
    lines = [
        "# Report: both generators on M2D, side by side",
        "",
        f"Generated by `python benchmarks/report.py` in {time.perf_counter() - started:.0f} s on this machine "
        f"({torch.get_num_threads()} threads); every number below comes from that run.",
        "",
        "## Quality (M2D test split, 5 s windows every 2.5 s, 30 fps, scored against the train split)",
        "",
        TABLE_HEADER.format(label="method"),
        *(table_row(name, report) for name, report in reports.items()),
        "",
        "FID is measured against the train split, as the reference row is: the retrieval baseline replays",
        "train windows, so its FID can fall below the real test motion's own. Read it with the diversity",
        "and style-adherence columns.",
        "",
        "![FID and BeatAlign per method](report/quality.png)",
        "",
        "## Style adherence (genre classifier on motion)",
        "",
        f"A logistic-regression classifier on the FID features of real M2D train windows "
        f"({len(train_windows)} windows, genres {', '.join(classifier.genres)}). Share of windows recognised as "
        "the genre of the test clip they were danced for (the genre each method was asked for):",
        "",
        "| method | recognised as the requested genre |",
        "| --- | ---: |",
        *(f"| {name} | {100 * value:.1f} % |" for name, value in adherence.items()),
        "",
        "The first row is the classifier's accuracy on real test windows: the ceiling the others are read against.",
        "",
        "## Beat-rate lock on songs from outside M2D",
        "",
        "The demo songs Debian's LMMS package ships (their project files state the tempo), rendered with",
        "LMMS, a minute of each from 10 s in, danced by both bundled generators with their defaults.",
        "Salience: the normalised autocorrelation of the dance's motion beats at one or two beat periods",
        "(`choreo.metrics.tempo_salience`); the lock measure and its reference are in benchmarks/beat_lock.py.",
        "",
        *lock_lines,
        "",
        "## Speed and memory",
        "",
        "Songs are the example loop tiled to length. Generation: seconds inside one process after the music",
        "analysis; peak RSS: a whole `choreo generate` / `choreo graph` run in a fresh process.",
        "",
        "| generator | song | generation (s) | peak RSS (MiB) | whole CLI run (s) |",
        "| --- | ---: | ---: | ---: | ---: |",
        *(f"| {name} | {seconds:g} s | {took:.2f} | {rss:.0f} | {wall:.1f} |" for name, seconds, took, rss, wall in speed_rows),
        "",
        "![time and memory against song length](report/speed.png)",
        "",
    ]
    args.out.write_text("\n".join(lines))
    print(f"wrote {args.out} and {plots}/")


if __name__ == "__main__":
    main()
