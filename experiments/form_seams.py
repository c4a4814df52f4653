"""How should a return's joins be made: how long a bend, and should the feet be planted again?

    python -m experiments.form_seams [--split validation] [--seeds 0 1 2] [--generators sgmd graph]
                                     [--joins 0.5 1.0] [--cache fresh.pkl]

Each song of known form (benchmarks/form_songs.json) is danced once per generator and seed with
the form off (--returns 0), as the CLI finishes it; its returns are then pasted in
(choreo.form.returns) with each bend length, and once more with the footsteps pass run on the
joins only (what `choreo generate` does). Per variant, over songs x seeds: the seams at every join
(the step into the join frame and the change of velocity around it, each over the dance's own 95th
percentile; choreo.metrics.form.seam_steps) as the share within 1 and the worst, the return ratio
(target <= 0.35) and the whole-song figures a join could spoil (planted share, slide, reach).
The fresh dance's row gives its own frames at the same places.
"""

import argparse
import os
import pickle

import numpy as np

from benchmarks.form_returns import form_text, genre_of
from benchmarks.form_songs import form_songs

FIGURES = ("planted", "slide", "reach", "jerk")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--split", default="validation")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--generators", nargs="+", default=["sgmd", "graph"])
    parser.add_argument("--joins", type=float, nargs="+", default=[0.5, 1.0])
    parser.add_argument("--cache", help="keep the fresh dances in this pickle (and read them from it)")
    args = parser.parse_args()

    from choreo.finishing import footsteps
    from choreo.form.options import FormOptions
    from choreo.form.returns import away_from_joins, plan_returns, with_returns
    from choreo.metrics.form import return_ratio, seam_steps
    from choreo.metrics.songs import figures
    from choreo.music import Music
    from choreo.music.form import parse_form
    from choreo.pipeline import Backend, DanceRequest

    cache = pickle.load(open(args.cache, "rb")) if args.cache and os.path.exists(args.cache) else {}
    rows: dict = {}
    for generator in args.generators:
        backend = Backend(generator)
        for song in form_songs(args.split):
            style = genre_of(song.name)
            music = cache.get(song.name) or Music.from_file(song.path, log_mel=True, timbre=True)
            cache[song.name] = music
            form = parse_form(form_text(song.sections), music.duration)
            for seed in args.seeds:
                key = (generator, song.name, seed)
                fresh = cache.get(key) or DanceRequest(backend=backend, style=style, seed=seed, threads=1,
                                                       form=FormOptions(returns=0)).dance(music)
                cache[key] = fresh
                for join in args.joins:
                    plan = plan_returns(form, music.beat_times, fresh.fps, fresh.num_frames, join_seconds=join)
                    pasted = with_returns(fresh, plan, join_seconds=join)
                    replanted = footsteps(pasted, away_from_joins(plan, fresh.num_frames, fresh.fps, join))
                    joins = sorted({f for r in plan for f in (r.start, r.stop) if 1 <= f < fresh.num_frames - 2})
                    for name, dance in (("fresh", fresh), ("paste", pasted), ("paste + footsteps", replanted)):
                        positions = dance.joint_positions()
                        row = rows.setdefault((generator, join, name), {"seams": [], "ratio": [], "figures": []})
                        row["seams"] += seam_steps(positions, joins)
                        row["ratio"] += return_ratio(positions, dance.fps, form, music.beat_times)
                        row["figures"].append(figures(positions, music, style))
            print(f"{generator} {song.name} done", flush=True)
    if args.cache:
        pickle.dump(cache, open(args.cache, "wb"))
    print(f"\n{'generator':9} {'join s':>6} {'variant':18} {'seams <= 1':>10} {'worst pose/vel':>15} {'ratio':>6} "
          + " ".join(f"{name:>8}" for name in FIGURES))
    for (generator, join, name), row in rows.items():
        seams = np.asarray(row["seams"], dtype=float).reshape(-1, 2)
        within = np.mean((seams[:, 0] <= 1) & (seams[:, 1] <= 1))
        worst = f"{seams[:, 0].max():.2f}/{seams[:, 1].max():.2f}"
        means = " ".join(f"{np.nanmean([f[c] for f in row['figures']]):8.3f}" for c in FIGURES)
        print(f"{generator:9} {join:6.2f} {name:18} {within:10.2f} {worst:>15} {np.nanmean(row['ratio']):6.3f} {means}")


if __name__ == "__main__":
    main()
