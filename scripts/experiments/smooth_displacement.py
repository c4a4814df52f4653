"""Would a smoother displacement map calm the borders of constrained dances? (Measured: no.)

    python scripts/experiments/smooth_displacement.py {linear,quintic,matched} CHECKPOINT --steps 10 --guidance 2 \
        --tasks "seed motion" in-betweening inpainting

Runs scripts/evaluate_controllable.py with SGMD's final displacement map (``choreo.constraints.
displace_to_constraints``: offsets interpolated linearly between given frames and fading linearly
to zero within 15 frames) replaced by a quintic Hermite curve: ``quintic`` fades each offset with
zero slope and curvature at both ends (C2 where the fade meets the untouched frames); ``matched``
also starts each fade and bridge with the offset's own slope and curvature inside the given run
(so the dance leaves given frames at the given motion's velocity, as inertialization does);
``linear`` is the shipped map. The border-jerk column is the one to read.
"""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]


def hermite5(x0, v0, a0, x1, v1, a1, n: int) -> np.ndarray:
    """Values at u = 1 .. n-1 of the quintic on [0, n] with value, slope and curvature (per frame) given at both ends."""
    s = (np.arange(1, n) / n)[:, None]
    basis = [1 - 10 * s**3 + 15 * s**4 - 6 * s**5, s - 6 * s**3 + 8 * s**4 - 3 * s**5,
             0.5 * s**2 - 1.5 * s**3 + 1.5 * s**4 - 0.5 * s**5, 0.5 * s**3 - s**4 + 0.5 * s**5,
             -4 * s**3 + 7 * s**4 - 3 * s**5, 10 * s**3 - 15 * s**4 + 6 * s**5]
    return x0 * basis[0] + v0 * n * basis[1] + a0 * n * n * basis[2] + a1 * n * n * basis[3] + v1 * n * basis[4] + x1 * basis[5]


def edge_state(offset: np.ndarray, length: int, at: int, step: int, matched: bool):
    """Offset value, slope and curvature at a run's edge frame ``at``, looking outward by ``step``."""
    x = offset[at]
    zero = np.zeros_like(x)
    if not matched:
        return x, zero, zero
    v = x - offset[at - step] if length >= 2 else zero
    a = x - 2 * offset[at - step] + offset[at - 2 * step] if length >= 3 else zero
    return x, v, a


def offset_curve(offset: np.ndarray, known: np.ndarray, reach: int, matched: bool) -> np.ndarray:
    """(T, C) offsets: exact on given frames, quintic bridges across gaps up to 2 x reach, quintic fades elsewhere."""
    curve = np.zeros_like(offset)
    curve[known] = offset[known]
    edges = np.flatnonzero(np.diff(np.r_[0, known.astype(np.int8), 0]))
    starts, ends = edges[0::2], edges[1::2] - 1
    zero = np.zeros(offset.shape[1:])

    def fade(run: int, step: int) -> None:
        at = ends[run] if step > 0 else starts[run]
        x, v, a = edge_state(offset, ends[run] - starts[run] + 1, at, step, matched)
        frames = at + step * np.arange(1, reach)
        inside = (frames >= 0) & (frames < len(known))
        curve[frames[inside]] = hermite5(x, v, a, zero, zero, zero, reach)[inside]

    if starts[0] > 0:
        fade(0, -1)
    for run in range(len(starts) - 1):
        end, start = ends[run], starts[run + 1]
        if start - end <= 2 * reach:
            x0, v0, a0 = edge_state(offset, end - starts[run] + 1, end, +1, matched)
            x1, v1, a1 = edge_state(offset, ends[run + 1] - start + 1, start, -1, matched)
            curve[end + 1:start] = hermite5(x0, v0, a0, x1, -v1, a1, start - end)
        else:
            fade(run, +1)
            fade(run + 1, -1)
    if ends[-1] < len(known) - 1:
        fade(len(starts) - 1, +1)
    return curve


def smooth_displacement(matched: bool):
    def displace(frames, values, mask, reach: int = 15):
        out = np.array(frames, dtype=np.float64, copy=True)
        flat = out.reshape(-1, *out.shape[-2:])
        given_all = np.broadcast_to(values, frames.shape).reshape(flat.shape)
        known_all = np.broadcast_to(mask, frames.shape).reshape(flat.shape)
        for sequence, given, known in zip(flat, given_all, known_all):
            columns = np.flatnonzero(known.any(0))
            if not len(columns):
                continue
            patterns, inverse = np.unique(known[:, columns].T, axis=0, return_inverse=True)
            for p, pattern in enumerate(patterns):  # channels given on the same frames share runs and gaps
                channels = columns[inverse.ravel() == p]
                sequence[:, channels] += offset_curve(given[:, channels] - sequence[:, channels], pattern, reach, matched)
                rows = np.flatnonzero(pattern)
                sequence[np.ix_(rows, channels)] = given[np.ix_(rows, channels)]
        return out
    return displace


def main() -> None:
    if len(sys.argv) < 2 or sys.argv[1] not in ("linear", "quintic", "matched"):
        raise SystemExit(__doc__)
    variant = sys.argv[1]
    if variant != "linear":
        import choreo_sgmd.sampling

        choreo_sgmd.sampling.displace_to_constraints = smooth_displacement(matched=variant == "matched")
    sys.argv = ["evaluate_controllable.py", *sys.argv[2:]]
    runpy.run_path(str(REPO / "scripts" / "evaluate_controllable.py"), run_name="__main__")


if __name__ == "__main__":
    main()
