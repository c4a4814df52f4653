"""Do the dances return when the music does? Both generators on the songs of known form
(benchmarks/form_songs.json), each danced with its known form given (--form) at two --returns
values, as `choreo generate` dances them (the genre as the style): one dance per song and seed,
finished, then its returns danced as DanceRequest.dance does after finishing.

    python benchmarks/form_returns.py [--split validation|test|all] [--seeds 0 1 2] [--generators sgmd graph]
                                      [--returns 0 1] [--mirror] [--json out.json]

Per dance: the return ratio of each returning section (choreo.metrics.form.return_ratio: its
distance to its first occurrence over its distance to the nearest other section; target <= 0.35,
afresh 0.5-1.3), the seams at the joins into and out of each copied phrase (pose step and velocity
change over the dance's own 95th percentile; target <= 1) and the form score. Printed: the mean
over songs x seeds with a 95 % interval (t), per generator and --returns.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from form_songs import form_songs  # noqa: E402

GENRES = {"C": "cha-cha", "R": "rumba", "T": "tango", "W": "waltz"}


def genre_of(name: str) -> str | None:
    """The style a spliced song is danced in: its source clip's genre (DANCE_W_4-AABA: waltz)."""
    parts = name.split("_")
    return GENRES.get(parts[1]) if name.startswith("DANCE_") and len(parts) > 2 else None


def form_text(sections) -> str:
    return ",".join(f"{start:.3f}={label}" for start, label in sections)


def measure(motion, music, form, beats_per_bar: int, mirrored: bool) -> dict:
    """The form figures of one dance (30 fps positions)."""
    from choreo.metrics.form import dance_form_score, return_ratio, seam_steps
    from choreo.music.form import music_self_similarity

    positions = motion.joint_positions()
    fps = motion.fps
    ratios = return_ratio(positions, fps, form, music.beat_times, mirrored=mirrored)
    joins = sorted({int(round(t * fps)) for entry in motion.metadata.get("returns", []) for t in entry["seconds"]})
    joins = [f for f in joins if 1 <= f < len(positions) - 2]
    seams = seam_steps(positions, joins) if joins else []
    lines, alike = music_self_similarity(music, beats_per_bar)
    return {"return_ratio": [float(r) for r in ratios],
            "seam_pose": [float(a) for a, _ in seams], "seam_velocity": [float(b) for _, b in seams],
            "form_score": dance_form_score(positions, lines * fps, alike),
            "returns_danced": len(motion.metadata.get("returns", []))}


def interval(values) -> tuple[float, float]:
    """(mean, half-width of its 95 % t interval)."""
    from scipy import stats

    values = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=np.float64)
    if len(values) < 2:
        return (float(values.mean()) if len(values) else float("nan"), float("nan"))
    return float(values.mean()), float(stats.t.ppf(0.975, len(values) - 1) * values.std(ddof=1) / np.sqrt(len(values)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--split", default="validation", choices=("validation", "test", "all"))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--generators", nargs="+", default=["sgmd", "graph"])
    parser.add_argument("--returns", type=float, nargs="+", default=[0.0, 1.0])
    parser.add_argument("--mirror", action="store_true", help="every other return mirrored (--mirror-returns)")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()

    from choreo.form.options import FormOptions
    from choreo.music import Music
    from choreo.music.form import parse_form
    from choreo.pipeline import Backend, DanceRequest

    songs = form_songs(args.split)
    rows = []
    for generator in args.generators:
        backend = Backend(generator)
        for song in songs:
            style = genre_of(song.name)
            music = Music.from_file(song.path, log_mel=True, timbre=True)  # timbre: the form score
            form = parse_form(form_text(song.sections), music.duration)
            for seed in args.seeds:
                fresh = DanceRequest(backend=backend, style=style, seed=seed, threads=1,
                                     form=FormOptions(returns=0)).dance(music)
                for returns in args.returns:  # what DanceRequest.dance does after finishing, on one dance
                    options = FormOptions(form=form_text(song.sections), returns=returns, mirror_returns=args.mirror)
                    request = DanceRequest(backend=backend, style=style, seed=seed, threads=1, form=options)
                    motion = request.returned(fresh, music, form)
                    row = {"song": song.name, "generator": generator, "seed": seed, "returns": returns,
                           **measure(motion, music, form, song.beats_per_bar, args.mirror)}
                    rows.append(row)
                    print(f"{generator} {song.name} seed {seed} returns {returns:g}: ratio "
                          f"{np.round(row['return_ratio'], 2).tolist()} seams {np.round(row['seam_pose'], 2).tolist()} "
                          f"form {row['form_score']:.3f}", flush=True)
    print()
    print(f"{'generator':9} {'returns':>7} {'return ratio (each return)':>28} {'share <= 0.35':>13} "
          f"{'worst seam pose/vel':>20} {'form score':>16}")
    for generator in args.generators:
        for returns in args.returns:
            chosen = [r for r in rows if r["generator"] == generator and r["returns"] == returns]
            ratios = [x for r in chosen for x in r["return_ratio"]]
            ratio, ratio_ci = interval(ratios)
            share = np.mean([x <= 0.35 for x in ratios if math.isfinite(x)]) if ratios else float("nan")
            poses = [x for r in chosen for x in r["seam_pose"]]
            velocities = [x for r in chosen for x in r["seam_velocity"]]
            form, form_ci = interval([r["form_score"] for r in chosen])
            worst = f"{max(poses, default=float('nan')):.2f}/{max(velocities, default=float('nan')):.2f}"
            print(f"{generator:9} {returns:7g} {ratio:20.2f} ± {ratio_ci:4.2f} {share:13.2f} {worst:>20} "
                  f"{form:9.3f} ± {form_ci:.3f}")
    if args.json:
        args.json.write_text(json.dumps({"split": args.split, "mirror": args.mirror, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
