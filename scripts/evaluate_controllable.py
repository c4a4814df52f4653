"""Controllable generation scored like the SGMD paper's Table III, on the M2D test windows.

    python scripts/evaluate_controllable.py CHECKPOINT [--steps 20] [--guidance 2] [--tasks trajectory ...]
    python scripts/evaluate_controllable.py --generator graph [--path-cost 4] [--key-cost 4]

For every 5 s test window the real motion supplies the constraints of each task (a root path,
the first two frames, the first and last frames, a random 70 % of frames, the lower body, the upper
body); the model fills in the rest from the window's music and genre. Besides the dance metrics
against the train windows it reports the error at constrained values (joints whose position is
fully fixed by known root and rotations), the root-path error, and the jerk on frames next to a
border between given and generated frames relative to the real motion's jerk there.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from choreo import load_backend
from choreo.constraints import Constraints
from choreo.datasets import load_dataset
from choreo.metrics import Dance
from choreo.metrics.protocol import ScoringSet, fmt, generate_window_motions, music_beats, score
from choreo.skeleton import LOWER_BODY_JOINTS, PARENTS, UPPER_BODY_JOINTS

REPO = Path(__file__).resolve().parents[1]
INPAINT_KEEP = 0.7  # the paper gives 70 % of the real frames


def task_constraints(task: str, motion, rng: np.random.Generator) -> Constraints:
    c = Constraints.none(motion.num_frames, motion.fps)
    if task == "trajectory":
        return c.fix_root_path(motion.root_positions[:, [0, 2]])
    if task == "seed motion":
        return c.fix_motion(motion.slice_frames(0, 2))
    if task == "in-betweening":
        return c.fix_motion(motion.slice_frames(0, 1)).fix_motion(motion.slice_frames(-1, None), at=motion.num_frames - 1)
    if task == "inpainting":
        return c.fix_motion(motion, frames=rng.random(motion.num_frames) < INPAINT_KEEP)
    if task == "upper-body generation":
        return c.fix_motion(motion, joints=LOWER_BODY_JOINTS, root=True)
    if task == "lower-body generation":
        return c.fix_motion(motion, joints=UPPER_BODY_JOINTS, root=False)
    raise ValueError(task)


TASKS = ("trajectory", "seed motion", "in-betweening", "inpainting", "upper-body generation", "lower-body generation")


def determined_joints(c: Constraints) -> np.ndarray:
    """(T, 24) joints whose world position the constraints fix: root known and every ancestor's rotation."""
    known = c.root_known.all(1)[:, None] & np.ones_like(c.joints_known)
    for joint, parent in enumerate(PARENTS):
        if parent >= 0:
            known[:, joint] = known[:, parent] & c.joints_known[:, parent]
    return known


def jerk(positions: np.ndarray, fps: float) -> np.ndarray:
    """(T,) mean joint jerk magnitude (m/s^3), aligned to frames 1..T-3 of the third difference."""
    third = np.diff(positions, n=3, axis=0) * fps**3
    out = np.full(len(positions), np.nan)
    out[1:-2] = np.linalg.norm(third, axis=-1).mean(-1)
    return out


def border_frames(c: Constraints, reach: int = 2) -> np.ndarray:
    full = c.joints_known.all(1)
    borders = np.flatnonzero(np.diff(full.astype(int)) != 0)
    frames = {f for b in borders for f in range(b - reach + 1, b + reach + 1)}
    return np.array(sorted(f for f in frames if 1 <= f < len(full) - 2), dtype=int)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint", nargs="?", help="default: the backend's bundled one")
    parser.add_argument("--generator", default="sgmd", choices=("sgmd", "graph"))
    parser.add_argument("--path-cost", type=float, default=None, help="graph: GraphConfig.path_cost")
    parser.add_argument("--key-cost", type=float, default=None, help="graph: GraphConfig.key_cost")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--guidance", type=float, default=2.0)
    parser.add_argument("--style-guidance", type=float, default=None, help="sgmd: guidance on the style (default: the sampler's)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--resample", type=int, default=1, help="RePaint resampling: runs of each masked step")
    parser.add_argument("--tasks", nargs="+", default=list(TASKS), choices=TASKS)
    parser.add_argument("--limit", type=int, default=None, help="score only the first N windows (smoke tests)")
    args = parser.parse_args()
    generator = load_backend(args.generator, args.checkpoint)
    scoring = ScoringSet.from_clips(load_dataset(args.data))
    windows, train = scoring.windows[: args.limit], scoring.reference
    real = [w.motion for w in windows]
    if args.generator == "sgmd":
        options = {"steps": args.steps, "guidance": args.guidance, "resample": args.resample}
        setting = f"{generator.checkpoint.name} (step {generator.trained_steps}), DDIM {args.steps}, w = {args.guidance:g}"
        if args.style_guidance is not None:
            options["style_guidance"] = args.style_guidance
            setting += f", style w = {args.style_guidance:g}"
    else:
        options = {k: v for k, v in (("path_cost", args.path_cost), ("key_cost", args.key_cost)) if v is not None}
        setting = f"graph {generator.checkpoint_name} + {generator.repertoire_name}, {options or 'default costs'}"
    log_mels = scoring.log_mels() if generator.listens_to_spectrum else None
    print(f"{setting}, {len(windows)} M2D test windows\n")
    print("| task | BeatAlign | PFC | FID_k | FID_g | Div_k | Div_g | max error at fixed joints (cm) | "
          "root path error (cm) | border jerk / real |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for task in args.tasks:
        started = time.time()
        rng = np.random.default_rng(args.seed)
        constraints = [task_constraints(task, m, rng) for m in real]
        motions = generate_window_motions(generator, windows, seed=args.seed, constraints=constraints, options=options,
                                          log_mels=log_mels)
        errors, path_errors, jerk_gen, jerk_real = [], [], [], []
        dances = []
        for window, motion, truth, c in zip(windows, motions, real, constraints):
            positions, target = motion.joint_positions(), truth.joint_positions()
            dances.append(Dance(f"{window.clip}@{window.start_frame}", positions, music_beats(window.features)))
            fixed = determined_joints(c)
            if fixed.any():
                errors.append(np.linalg.norm(positions - target, axis=-1)[fixed].max())
            if c.root_known[:, [0, 2]].all():
                path_errors.append(np.linalg.norm(motion.root_positions[:, [0, 2]] - truth.root_positions[:, [0, 2]], axis=-1).mean())
            frames = border_frames(c)
            if len(frames):
                jerk_gen.append(jerk(positions, motion.fps)[frames])
                jerk_real.append(jerk(target, truth.fps)[frames])
        report = score(dances, train)
        ratio = np.nanmean(np.concatenate(jerk_gen)) / np.nanmean(np.concatenate(jerk_real)) if jerk_gen else None
        values = (report.beat_align, report.pfc, report.fid_k, report.fid_g, report.div_k, report.div_g,
                  100 * max(errors) if errors else None, 100 * np.mean(path_errors) if path_errors else None, ratio)
        walked = [m.metadata.get("walk_root_error_m") for m in motions]
        walked = [w for w in walked if w is not None]
        note = f", walk's own root error {100 * np.mean(walked):.1f} cm" if walked else ""
        print(f"| {task} | " + " | ".join(fmt(v) for v in values) + f" | <!-- {time.time() - started:.0f} s{note} -->",
              flush=True)


if __name__ == "__main__":
    main()
