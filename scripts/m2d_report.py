"""Regenerate the M2D conversion report from the data: docs/m2d.md's generated sections and the offsets.

    PYTHONPATH=src python scripts/m2d_report.py [--data ../shared/data/m2d] [--keep-offsets] [--time-load]

Writes src/choreo/datasets/m2d_offsets.json (unless --keep-offsets), src/choreo/datasets/m2d_split.json
(deterministic, see choreo.datasets.m2d.make_split) and every block of docs/m2d.md between
``<!-- generated:NAME -->`` and ``<!-- /generated:NAME -->``; the prose around them is left alone.
--time-load also times a cold and a warm ``load_m2d`` of every clip in a throw-away cache folder.
Fits and song features go to the usual cache (``$CHOREO_CACHE_DIR`` or ~/.cache/choreo).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import tempfile
import time
from dataclasses import asdict
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from scipy.sparse.csgraph import minimum_spanning_tree

from choreo.datasets.cache import cache_dir, cached_music
from choreo.datasets.m2d import (
    GENRES, MARKER_NAMES, SMPL_TARGETS, SOURCE_FPS, UPSTREAM_FPS, OffsetSearch,
    clip_folders, estimate_music_offset, genre_of, load_fit, load_m2d, make_split, make_validation, read_recording,
)  # fmt: skip
from choreo.skeleton import JOINT_NAMES

REPO = Path(__file__).resolve().parents[1]
DOC = REPO / "docs" / "m2d.md"
PACKAGE = REPO / "src" / "choreo" / "datasets"


# -- raw data -----------------------------------------------------------------------------------

def read_raw(folder: Path) -> dict:
    """skeletons.json (cm, relative to center) and config.json of one clip, as arrays."""
    data = json.loads((folder / "skeletons.json").read_text())
    config = json.loads((folder / "config.json").read_text())
    return {"skeleton": np.asarray(data["skeletons"], float), "center": np.asarray(data["center"], float),
            "start": config["start_position"], "end": config["end_position"], "genre": genre_of(folder.name)}


def body_frame(skeleton: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rows x, y, z: x horizontal from marker 7 to marker 16, y up, z = x cross y."""
    x = skeleton[:, 16] - skeleton[:, 7]
    x[:, 1] = 0.0
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.broadcast_to([0.0, 1.0, 0.0], x.shape)
    return np.stack([x, y, np.cross(x, y)], axis=1)


def table(header: list[str], rows: list[list], align: str | None = None) -> str:
    align = align or "l" + "r" * (len(header) - 1)
    rule = ["---:" if a == "r" else "---" for a in align]
    lines = [header, rule, *[[str(c) for c in row] for row in rows]]
    return "\n".join("| " + " | ".join(line) + " |" for line in lines)


def pairwise(points: np.ndarray) -> np.ndarray:
    """(T, N, N) distances between every pair of points per frame."""
    return np.linalg.norm(points[:, :, None] - points[:, None], axis=-1)


# -- evidence sections --------------------------------------------------------------------------

def layout_section(raw: dict[str, dict]) -> str:
    """Median marker positions in the hip frame, constant-distance pairs, what ``center`` is."""
    skeletons = [r["skeleton"] for r in raw.values()]
    pooled = np.concatenate(skeletons)
    body = np.einsum("tij,tkj->tki", body_frame(pooled), pooled)
    median = np.median(body, axis=0)
    smpl_of = {m: JOINT_NAMES[j] for j, ms in SMPL_TARGETS.items() for m in ms}
    rows = [[i, MARKER_NAMES[i], f"{median[i, 0]:.1f}", f"{median[i, 1]:.1f}", f"{median[i, 2]:.1f}",
             smpl_of.get(i, "-") + (" (mean of 0, 1)" if i in (0, 1) else "")] for i in range(23)]
    header = ["index", "marker", "x (left +)", "y (up)", "z (forward)", "SMPL-24 target"]
    out = [table(header, rows, "rlrrrl")]

    spreads = np.median([pairwise(s).std(axis=0) for s in skeletons], axis=0)
    lengths = np.median(pairwise(pooled), axis=0)
    np.fill_diagonal(spreads, 0.0)
    tree = minimum_spanning_tree(spreads).toarray()
    edges = sorted((min(i, j), max(i, j)) for i, j in zip(*np.nonzero(tree)))
    rows = [[f"{i}-{j}", f"{MARKER_NAMES[i]} - {MARKER_NAMES[j]}", f"{lengths[i, j]:.1f}",
             f"{spreads[i, j]:.2f}"] for i, j in edges]
    out += ["", "Pairs that keep the most constant distance (minimum spanning tree of the per-clip standard "
            "deviation of every pairwise distance, median over clips; centimetres):", "",
            table(["pair", "markers", "median distance", "std within a clip"], rows, "llrr")]

    toe_ahead = np.mean(np.concatenate([body[:, 11, 2] > body[:, 10, 2], body[:, 20, 2] > body[:, 19, 2]]))
    head_pair = body[:, 1] - body[:, 0]
    centroid = np.concatenate([s[:, :21].mean(axis=1) for s in skeletons])
    facts = [
        f"- toes ahead of heels along +z in {toe_ahead * 100:.0f} % of frames (so z = x cross y is forward "
        "and the +x side, marker 16's, is the body's left as in SMPL);",
        f"- markers 0 and 1 sit at the same height (median y {median[0, 1]:.1f} / {median[1, 1]:.1f} cm) "
        f"{np.median(np.linalg.norm(head_pair, axis=-1)):.1f} cm apart, 1 on the left "
        f"(median x of 1 - 0: {np.median(head_pair[:, 0]):.1f} cm): two head markers, not neck and head;",
        f"- `center` is the horizontal centroid of markers 0-20 (x, z standard deviation "
        f"{centroid[:, 0].std():.2f} / {centroid[:, 2].std():.2f} cm) about "
        f"{-np.median(centroid[:, 1]):.1f} cm above their mean height, not a joint; the hip markers are "
        f"{np.median(np.linalg.norm(pooled[:, 16] - pooled[:, 7], axis=-1)):.1f} cm apart "
        "(SMPL's hip joints 11.9 cm).",
    ]
    return "\n".join(out + ["", *facts])


def linear_frames(world: np.ndarray) -> np.ndarray:
    """(T,) True where a frame lies (within 0.5 mm) on the straight line between its neighbours."""
    flags = np.zeros(len(world), bool)
    flags[1:-1] = np.abs(np.diff(world, 2, axis=0)).max(axis=(1, 2)) < 5e-4
    return flags


def framerate_section(raw: dict[str, dict]) -> str:
    """Span/length ratios, interpolated frames, speeds and accelerations per genre and frame rate."""
    rows = []
    for genre in GENRES.values():
        clips = [r for r in raw.values() if r["genre"] == genre]
        ratios = [(r["end"] - r["start"]) / len(r["skeleton"]) for r in clips]
        for fps in sorted({UPSTREAM_FPS, SOURCE_FPS[genre]}, reverse=True):
            speeds, accels, linear = [], [], []
            for r in clips:
                world = (r["skeleton"] + r["center"][:, None]) / 100.0
                flags = linear_frames(world)
                measured = ~flags[1:-1]
                speed = np.linalg.norm(np.diff(r["center"][:, [0, 2]], axis=0), axis=-1) / 100.0 * fps
                accel = np.linalg.norm(np.diff(world, 2, axis=0), axis=-1).mean(axis=-1) * fps**2
                speeds.append(speed[1:][measured])
                accels.append(accel[measured])
                linear.append(flags.mean())
            speeds, accels = np.concatenate(speeds), np.concatenate(accels)
            rows.append([genre, len(clips), f"{np.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f})",
                         f"{np.mean(linear) * 100:.0f} %", f"{fps:.2f}", f"{np.median(speeds):.2f}",
                         f"{np.percentile(speeds, 99):.2f}", f"{np.median(accels):.1f}",
                         f"{np.percentile(accels, 99):.1f}"])
    header = ["genre", "clips", "(end - start) / length", "interpolated frames", "fps assumed",
              "centre speed p50 (m/s)", "p99", "mean joint accel. p50 (m/s^2)", "p99"]
    return table(header, rows, "lrrrrrrrr") + (
        "\n\nInterpolated frames: frames lying within 0.5 mm on the straight line between their neighbours "
        "(not measured); speeds and accelerations are over the other frames.")


# -- per clip ------------------------------------------------------------------------------------

def estimate_offsets(folders: list[Path]) -> tuple[dict, dict]:
    """Offset estimates per clip (and, for waltz, the same search at 25 fps for comparison)."""
    search = OffsetSearch()
    chosen, at_25 = {}, {}
    for folder in folders:
        recording = read_recording(folder)
        song = cached_music(folder / "audio.mp3")
        chosen[folder.name] = estimate_music_offset(recording, song.beat_times, song.duration, search)
        if recording.fps != UPSTREAM_FPS:
            at_25[folder.name] = estimate_music_offset(recording, song.beat_times, song.duration, search,
                                                       fps=UPSTREAM_FPS)
        estimate = chosen[folder.name]
        print(f"{folder.name}: offset {estimate.offset:.2f} s (p = {estimate.p_value:.3f})", flush=True)
    return chosen, at_25


def write_offsets(estimates: dict) -> None:
    payload = {
        "description": "Seconds into each clip's audio.mp3 at which motion frame 0 happens, estimated by "
                       "choreo.datasets.m2d.estimate_music_offset (BeatAlign over a window around "
                       "start_position / 25; the peak is used when random beats reach it with p < 0.05, "
                       "else start_position / 25). Regenerate with scripts/m2d_report.py; see docs/m2d.md.",
        "search": asdict(OffsetSearch()),
        "clips": {name: {key: (round(v, 4) if isinstance(v, float) else v) for key, v in asdict(e).items()}
                  for name, e in estimates.items()},
    }
    (PACKAGE / "m2d_offsets.json").write_text(json.dumps(payload, indent=1) + "\n")


def load_offsets() -> dict:
    clips = json.loads((PACKAGE / "m2d_offsets.json").read_text())["clips"]
    return {name: SimpleNamespace(**entry) for name, entry in clips.items()}


def write_split(names: list[str]) -> dict[str, str]:
    split = make_split(names)
    description = ("Fixed M2D train/test split by clip (never by window): per genre in the order C, R, T, W "
                   "with clips in numeric order, numpy default_rng(2018) draws round(20 %) of the clips (at "
                   "least one) for test; tango has a single clip, which stays in train. See "
                   "choreo.datasets.m2d.make_split and docs/m2d.md. 'validation' is drawn the same way from "
                   "train with default_rng(2019): train clips a model can be trained without "
                   "(choreo train sgmd --hold-out-validation) to choose settings on (make_validation).")
    payload = {"description": description, "splits": split, "validation": make_validation(split["train"])}
    (PACKAGE / "m2d_split.json").write_text(json.dumps(payload, indent=1) + "\n")
    return {n: s for s, members in split.items() for n in members}


def clip_rows(folders, estimates, splits, fits) -> list[dict]:
    rows = []
    for folder in folders:
        recording, fit, e = read_recording(folder), fits[folder.name], estimates[folder.name]
        frames = recording.num_frames
        rows.append({"clip": folder.name, "genre": recording.genre, "split": splits[folder.name],
                     "frames": frames, "frames30": int(round(frames * 30 / recording.fps)),
                     "fps": recording.fps, "seconds": recording.duration, "nominal": e.nominal,
                     "offset": e.offset, "peak": e.peak_offset, "p": e.p_value, "significant": e.significant,
                     "score": e.score, "score_start": e.score_at_start, "chance": e.chance,
                     "fit": float(fit["fit_error"]) * 100, "standard": float(fit["standard_error"]) * 100})
    return rows


def clips_section(rows: list[dict]) -> str:
    def offset(r: dict) -> str:
        return f"**{r['offset']:.2f}**" if r["significant"] else f"{r['offset']:.2f}"

    body = [[r["clip"], r["genre"], r["split"], f"{r['frames']} / {r['frames30']}", f"{r['fps']:.2f}",
             f"{r['seconds']:.1f}", f"{r['nominal']:.2f}", offset(r),
             f"{r['peak'] - r['nominal']:+.2f} (p {r['p']:.3f})", f"{r['score']:.3f}",
             f"{r['score_start']:.3f}", f"{r['chance']:.3f}", f"{r['fit']:.2f}", f"{r['standard']:.2f}"]
            for r in rows]
    header = ["clip", "genre", "split", "frames (source / 30 fps)", "source fps", "seconds", "start/25 (s)",
              "offset (s)", "peak shift (s)", "BeatAlign at offset", "at start/25", "random beats",
              "IK error (cm)", "on standard SMPL bones (cm)"]
    return table(header, body, "lllrrrrrrrrrrr") + (
        "\n\nBold offsets: the alignment peak beat random beats (p < 0.05) and is used; the others keep "
        "start_position / 25. IK error: mean per-joint distance to the raw (floor-normalised) markers over "
        "the 16 targets, on the performer's fitted bones; last column: same rotations and root on the "
        "standard SMPL-24 bones.")


def genre_section(rows: list[dict], at_25: dict) -> str:
    body = []
    for genre in [*GENRES.values(), "all"]:
        group = [r for r in rows if genre in ("all", r["genre"])]

        def mean(key: str) -> float:
            return float(np.mean([r[key] for r in group]))

        body.append([genre, len(group), f"{sum(r['seconds'] for r in group) / 60:.1f}",
                     sum(r["significant"] for r in group), f"{mean('score'):.3f}",
                     f"{mean('score_start'):.3f}", f"{mean('chance'):.3f}", f"{mean('fit'):.2f}",
                     f"{max(r['fit'] for r in group):.2f}", f"{mean('standard'):.2f}"])
    header = ["genre", "clips", "minutes", "significant peaks", "BeatAlign at offset", "at start/25",
              "random beats", "IK error (cm)", "worst clip (cm)", "on standard bones (cm)"]
    out = table(header, body, "lrrrrrrrrr")
    if at_25:
        sig = sum(e.significant for e in at_25.values())
        out += ("\n\nThe same search with the waltz clips read at 25 fps: "
                f"{sig} of {len(at_25)} significant peaks, BeatAlign at the peak "
                f"{np.mean([e.peak_score for e in at_25.values()]):.3f}, at start/25 "
                f"{np.mean([e.score_at_start for e in at_25.values()]):.3f}, random beats "
                f"{np.mean([e.chance for e in at_25.values()]):.3f}; median peak shift "
                f"{np.median([e.peak_offset - e.nominal for e in at_25.values()]):+.2f} s.")
    return out


def split_section(rows: list[dict]) -> str:
    body = []
    total = sum(r["seconds"] for r in rows)
    for split in ("train", "test"):
        group = [r for r in rows if r["split"] == split]
        seconds = sum(r["seconds"] for r in group)
        counts = [sum(r["genre"] == g for r in group) for g in GENRES.values()]
        body.append([split, *counts, len(group), f"{seconds / 60:.1f}", f"{seconds / total * 100:.0f} %"])
    test = ", ".join(r["clip"] for r in rows if r["split"] == "test")
    header = ["split", *GENRES.values(), "clips", "minutes", "share of duration"]
    return table(header, body) + f"\n\nTest clips: {test}."


def time_loads(data: Path) -> str:
    """Cold and warm load_m2d of every clip in a fresh cache folder (fits + excerpt features)."""
    previous = os.environ.get("CHOREO_CACHE_DIR")
    with tempfile.TemporaryDirectory() as folder:
        os.environ["CHOREO_CACHE_DIR"] = folder
        try:
            started = time.time()
            clips = load_m2d(data)
            cold = time.time() - started
            started = time.time()
            load_m2d(data)
            warm = time.time() - started
        finally:
            if previous is None:
                os.environ.pop("CHOREO_CACHE_DIR", None)
            else:
                os.environ["CHOREO_CACHE_DIR"] = previous
    minutes = sum(c.motion.duration for c in clips) / 60
    return (f"`load_m2d` of all {len(clips)} clips ({minutes:.1f} minutes at 30 fps) in an empty cache: "
            f"{cold:.0f} s (IK fits and music features); again with the cache warm: {warm:.1f} s.")


# -- the document --------------------------------------------------------------------------------

def replace_block(text: str, name: str, content: str) -> str:
    pattern = re.compile(rf"(<!-- generated:{name} -->\n).*?(<!-- /generated:{name} -->)", re.S)
    if not pattern.search(text):
        raise SystemExit(f"{DOC} has no generated:{name} block")
    return pattern.sub(lambda m: m.group(1) + content + "\n" + m.group(2), text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data" / "m2d")
    parser.add_argument("--keep-offsets", action="store_true", help="use the committed m2d_offsets.json")
    parser.add_argument("--time-load", action="store_true", help="time cold and warm load_m2d (slow)")
    args = parser.parse_args()
    started = time.time()
    folders = clip_folders(args.data)
    cold = not (cache_dir() / "m2d").is_dir()
    raw = {f.name: read_raw(f) for f in folders}
    fits = {}
    for folder in folders:
        fits[folder.name] = load_fit(folder, read_recording(folder))
        print(f"{folder.name}: IK error {float(fits[folder.name]['fit_error']) * 100:.2f} cm", flush=True)
    if args.keep_offsets:
        estimates, at_25 = load_offsets(), {}
    else:
        estimates, at_25 = estimate_offsets(folders)
        write_offsets(estimates)
    splits = write_split([f.name for f in folders])
    rows = clip_rows(folders, estimates, splits, fits)
    sections = {"layout": layout_section(raw), "framerate": framerate_section(raw),
                "genres": genre_section(rows, at_25), "split": split_section(rows), "clips": clips_section(rows)}
    elapsed = time.time() - started
    flags = " --keep-offsets" if args.keep_offsets else ""
    timing = (f"Last run: `PYTHONPATH=src python scripts/m2d_report.py{flags}` "
              f"took {elapsed:.0f} s on a 2-core CPU shared with other jobs ({len(folders)} clips; "
              f"{'cold cache' if cold else 'fits and song features from the cache'}).")
    if args.time_load:
        timing += " " + time_loads(args.data)
    sections["timing"] = timing
    text = DOC.read_text()
    for name, content in sections.items():
        text = replace_block(text, name, content)
    DOC.write_text(text)
    print(timing)


if __name__ == "__main__":
    main()
