"""The whole-song protocol: every song of a split danced whole, as `choreo generate` / `choreo graph`
would dance it, scored per song against the real dancer to the same music.

    python scripts/evaluate_whole_songs.py --generator sgmd --split validation --seeds 0 1 2
    python scripts/evaluate_whole_songs.py --generator graph --split test --no-style
    python scripts/evaluate_whole_songs.py --generator sgmd --option guidance=1.5 --finishing root_smoothing=0

Each clip's song is cut from its audio where the dance starts, for as long as the dance, analysed
once and danced through `choreo.dance` (the CLI's defaults, the clip's genre as the style unless
--no-style) for each seed. Per song (mean over seeds): pace along the ground track, its reach
from the start, planted, foot~root, slide, median jerk (whole body, root path, body relative to
the pelvis), BeatAlign, the beat dip and the legs (feet speed around the pelvis, ankle lift,
pelvis speed, foot jerk; choreo.metrics.whole_song), with the real dancer's row beside. The
classifier test against the real dancers, pooled over the Latin songs and over all. Then FID_k / FID_g of the 5 s windows cut from all the whole dances (2.5 s apart), pooled
over songs and seeds, against the train split's windows, with 95 % bootstrap intervals over
windows; the real dances' own windows get the same. --json writes every figure.

Splits: "validation" is m2d_split.json's validation clips (train clips, so only a model trained
with `--hold-out-validation` has not heard them), "test" the test split. The bundled model trained
on the validation clips, so for it the test split is what settings are chosen on.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import choreo
import choreo.finishing
from choreo.datasets import TRAIN, load_dataset, select_split
from choreo.form.options import FormOptions
from choreo.finishing import AccentConfig, Finishing, FootstepsConfig, PaceConfig, RootPathConfig
from choreo.metrics.fid import motion_features
from choreo.metrics.protocol import scoring_windows
from choreo.metrics.songs import (COLUMNS, FPS, classifier_tests, figures, mean_rows, song_of, split_clips,
                                  target_failures, window_fids)
from choreo.music import Music

REPO = Path(__file__).resolve().parents[1]


def parse_pairs(pairs: list[str]) -> dict:
    out = {}
    for pair in pairs:
        key, _, value = pair.partition("=")
        out[key] = json.loads(value) if value not in ("true", "false") else value == "true"
    return out


def fmt(value: float) -> str:
    return "-" if value is None or not np.isfinite(value) else (f"{value:.0f}" if abs(value) >= 20 else f"{value:.3f}")


def print_rows(per_song: dict, real: dict) -> None:
    print("| song | who | " + " | ".join(COLUMNS) + " |")
    print("| --- | --- |" + " ---: |" * len(COLUMNS))
    for name in per_song:
        for who, row in (("real", real[name]), ("generated", per_song[name])):
            print(f"| {name} | {who} | " + " | ".join(fmt(row[c]) for c in COLUMNS) + " |")


def report(paths: list[str]) -> None:
    """Side by side: each saved run's means over songs, FIDs and target misses."""
    print("| run | " + " | ".join(COLUMNS) + " | FID_k | FID_g | misses |")
    print("| --- |" + " ---: |" * (len(COLUMNS) + 3))
    for path in paths:
        run = json.loads(Path(path).read_text())
        songs = run["songs"]
        mean = mean_rows([mean_rows(v["seeds"]) for v in songs.values()])
        fid = lambda f: f"{f[0]:.1f} [{f[1]:.1f}, {f[2]:.1f}]"  # noqa: E731
        print(f"| {Path(path).stem} | " + " | ".join(fmt(mean[c]) for c in COLUMNS)
              + f" | {fid(run['fid']['fid_k'])} | {fid(run['fid']['fid_g'])} | {len(target_failures(songs))} |")
    real = mean_rows([v["real"] for v in songs.values()])
    print("| real | " + " | ".join(fmt(real[c]) for c in COLUMNS)
          + f" | {run['real_fid']['fid_k'][0]:.1f} | {run['real_fid']['fid_g'][0]:.1f} | |")
    for path in paths:
        print(f"\n{Path(path).stem} misses:", *target_failures(json.loads(Path(path).read_text())["songs"]), sep="\n  ")


CONFIGS = {"accent": AccentConfig, "footsteps": FootstepsConfig, "pace": PaceConfig, "root_path": RootPathConfig}


def pass_configs(pairs: list[str]) -> dict:
    """{pass: its config} from PASS.FIELD=VALUE pairs (--settings footsteps.strength=0.8)."""
    by_pass: dict[str, dict] = {}
    for key, value in parse_pairs(pairs).items():
        name, _, field = key.partition(".")
        by_pass.setdefault(name, {})[field] = value
    return {name: CONFIGS[name](**fields) for name, fields in by_pass.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--generator", default="sgmd")
    parser.add_argument("--checkpoint", default=None)
    parser.add_argument("--repertoire", default=None, help="ChoreoGraph: this repertoire instead of the bundled one")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--split", default="test", choices=["validation", "test"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--no-style", action="store_true", help="dance without a style (default: the clip's genre)")
    parser.add_argument("--option", nargs="*", default=[], help="backend options KEY=JSON, e.g. guidance=1.5")
    parser.add_argument("--finishing", nargs="*", default=[], help="Finishing fields KEY=JSON, e.g. footsteps=false")
    parser.add_argument("--settings", nargs="*", default=[],
                        help="finishing passes' settings PASS.FIELD=JSON: footsteps.strength=0.8, pace.tolerance=0, "
                             "root_path.cutoff_hz=4")
    parser.add_argument("--songs", nargs="*", default=None, help="only these clips")
    parser.add_argument("--form", default=None, help="--form (auto: the analysed form; default: off)")
    parser.add_argument("--returns", type=float, default=FormOptions.returns, help="--returns, with --form")
    parser.add_argument("--outside", nargs="*", default=[], help="also these songs from outside M2D, danced whole "
                                                                    "with each of --outside-styles (no real dancer)")
    parser.add_argument("--outside-styles", nargs="*", default=["cha-cha", "rumba", "waltz", "none"])
    parser.add_argument("--json", default=None, help="write every figure here")
    parser.add_argument("--report", nargs="+", default=None, help="only compare runs saved with --json")
    args = parser.parse_args()
    if args.report:
        return report(args.report)

    clips = load_dataset(args.data)
    songs = [c for c in split_clips(clips, args.split) if args.songs is None or c.name in args.songs]
    reference_windows = scoring_windows(select_split(clips, TRAIN))
    reference = [motion_features(w.motion.joint_positions()) for w in reference_windows]
    reference = (np.stack([k for k, _ in reference]), np.stack([g for _, g in reference]))
    backend = choreo.load_backend(args.generator, args.checkpoint,
                                  **({"repertoire": args.repertoire} if args.repertoire else {}))
    options = parse_pairs(args.option)
    finishing = replace(Finishing(), **parse_pairs(args.finishing), configs=pass_configs(args.settings))
    started = time.time()
    per_song, real, dances, real_dances, log = {}, {}, [], [], {}
    genres, real_genres, groups = [], [], []
    for clip in songs:
        music = song_of(clip)
        truth = clip.motion.joint_positions()[: len(music.features)]
        real[clip.name] = figures(truth, music, clip.genre)
        real_dances.append(truth)
        real_genres.append(clip.genre)
        rows = []
        for seed in args.seeds:
            motion = choreo.dance(music, backend, style=None if args.no_style else clip.genre, seed=seed,
                                  options=options, finishing=finishing, form=args.form,
                                  returns=args.returns)
            positions = motion.joint_positions()
            rows.append({**figures(positions, music, clip.genre), "model_pace": motion.metadata.get("pace", {}).get("model")})
            dances.append(positions)
            genres.append(clip.genre)
            groups.append(f"{clip.name} seed {seed}")
        per_song[clip.name] = mean_rows(rows)
        log[clip.name] = {"genre": clip.genre, "real": real[clip.name], "seeds": rows}
        print(f"{clip.name}: {len(music.features) / FPS:.0f} s, {time.time() - started:.0f} s so far", flush=True)
    print_rows(per_song, real)
    fids, real_fids = window_fids(dances, reference), window_fids(real_dances, reference)
    for who, f in (("generated", fids), ("real", real_fids)):
        print(f"{who}: {f['windows']} windows, FID_k {f['fid_k'][0]:.2f} [{f['fid_k'][1]:.2f}, {f['fid_k'][2]:.2f}], "
              f"FID_g {f['fid_g'][0]:.2f} [{f['fid_g'][1]:.2f}, {f['fid_g'][2]:.2f}]")
    classifier = classifier_tests(dances, real_dances, genres, real_genres, groups)
    for name, result in classifier.items():
        print(f"classifier test, {name} songs: balanced accuracy {result['accuracy']:.3f} ({result['windows']} windows "
              f"against {result['reference_windows']} real, {result['folds']} folds)")
    outside = {song: dance_outside(song, backend, args, options, finishing) for song in args.outside}
    if args.json:  # an outside song's file by its hash: LMMS renders a song differently each time
        heard = {song: hashlib.sha256(Path(song).read_bytes()).hexdigest() for song in args.outside}
        Path(args.json).write_text(json.dumps({"args": vars(args), "songs": log, "fid": fids, "real_fid": real_fids,
                                               "classifier": classifier, "outside": outside, "outside_sha256": heard}, indent=1, default=float))


def dance_outside(song: str, backend, args, options: dict, finishing: Finishing) -> dict:
    """A song without a real dancer: each style's figures (mean over seeds), the model's own pace
    beside the finished one, and the pace real dancers of that genre keep (choreo.finishing.pace)."""
    from choreo.finishing.pace import target_pace

    music = Music.from_file(song, log_mel=True, timbre=True)
    print(f"\n{Path(song).name}, {music.duration:.0f} s:")
    print("| style | real pace | model pace | " + " | ".join(COLUMNS) + " |")
    print("| --- |" + " ---: |" * (len(COLUMNS) + 2))
    rows = {}
    for style in args.outside_styles:
        genre = None if style == "none" else style
        danced = [choreo.dance(music, backend, style=genre, seed=seed, options=options, finishing=finishing,
                               form=args.form, returns=args.returns)
                  for seed in args.seeds]
        seeds = [{**figures(m.joint_positions(), music, genre), "model_pace": m.metadata.get("pace", {}).get("model")}
                 for m in danced]
        mean = mean_rows(seeds)
        model_pace = np.mean([r["model_pace"] for r in seeds]) if all(r["model_pace"] for r in seeds) else float("nan")
        print(f"| {style} | {fmt(target_pace(genre) or float('nan'))} | {fmt(model_pace)} | "
              + " | ".join(fmt(mean[c]) for c in COLUMNS) + " |", flush=True)
        rows[style] = seeds
    return rows


if __name__ == "__main__":
    main()
