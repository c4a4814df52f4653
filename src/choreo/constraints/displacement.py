"""Meeting constraints without a jump: a displacement map instead of a hard overwrite.

Overwriting the given frames of a generated sequence makes them exact but leaves a step wherever
the model's own frames disagree with them. Here the disagreement at each given value becomes an
offset that is interpolated along time between given frames and fades out within ``reach``
frames of the nearest one, then added to the whole sequence: given values come out exact and the
frames around them bend smoothly towards them (classic motion editing's displacement mapping).
"""

from __future__ import annotations

import numpy as np

REACH_FRAMES = 15  # half a second at 30 fps


def displace_to_constraints(frames: np.ndarray, values: np.ndarray, mask: np.ndarray,
                            reach: int = REACH_FRAMES) -> np.ndarray:
    """(..., T, D) ``frames`` moved onto ``values`` where ``mask`` is set, smoothly around them."""
    out = np.array(frames, dtype=np.float64, copy=True)
    flat_out = out.reshape(-1, *out.shape[-2:])
    flat_values = np.broadcast_to(values, frames.shape).reshape(flat_out.shape)
    flat_mask = np.broadcast_to(mask, frames.shape).reshape(flat_out.shape)
    time = np.arange(out.shape[-2])
    for sequence, given, known in zip(flat_out, flat_values, flat_mask):
        for channel in np.flatnonzero(known.any(0)):
            at = np.flatnonzero(known[:, channel])
            if reach > 0:  # reach 0: only the given frames move (a plain overwrite)
                anchors, offsets = offset_anchors(at, given[at, channel] - sequence[at, channel], reach)
                sequence[:, channel] += np.interp(time, anchors, offsets)
            sequence[at, channel] = given[at, channel]
    return out


def offset_anchors(at: np.ndarray, offset: np.ndarray, reach: int) -> tuple[np.ndarray, np.ndarray]:
    """Interpolation anchors for the offset curve: the given frames, plus zeros ``reach`` frames
    outside every run of given frames (so offsets bridge gaps up to 2 x reach and fade beyond)."""
    gaps = np.flatnonzero(np.diff(at) > 2 * reach)
    zeros = np.concatenate([[at[0] - reach], at[gaps] + reach, at[gaps + 1] - reach, [at[-1] + reach]])
    anchors = np.concatenate([at, zeros]).astype(np.float64)
    values = np.concatenate([offset, np.zeros(len(zeros))])
    order = np.argsort(anchors, kind="stable")
    return anchors[order], values[order]


def displace_motion(motion, constraints, reach: int = REACH_FRAMES, root_reach: int | None = None):
    """``motion`` bent onto ``constraints`` (a :class:`~choreo.constraints.Constraints` of its
    length): given rotations and root axes exact, their neighbours bent smoothly towards them.

    ``root_reach`` (default ``reach``) lets the root's offsets bridge longer gaps: a dance placed
    roughly where the given root is then drifts onto it slowly instead of sliding within 0.5 s.
    """
    from ..motion import motion_to_vector, vector_to_motion
    from ..motion.vector import ROOT_SLICE
    from .mask import as_smpl

    if motion.num_frames != constraints.num_frames:
        raise ValueError(f"constraints cover {constraints.num_frames} frames, the motion {motion.num_frames}")
    values, mask = constraints.frame_vectors()
    vectors = motion_to_vector(as_smpl(motion, constraints.fps))
    joints = mask.copy()
    joints[:, ROOT_SLICE] = False
    moved = displace_to_constraints(vectors, values, joints, reach)
    root = np.zeros_like(mask)
    root[:, ROOT_SLICE] = mask[:, ROOT_SLICE]
    moved = displace_to_constraints(moved, values, root, reach if root_reach is None else root_reach)
    bent, _ = vector_to_motion(moved, fps=constraints.fps, skeleton=motion.skeleton)
    bent.metadata = dict(motion.metadata)
    return bent
