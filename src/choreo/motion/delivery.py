"""What a file gets after the finishing passes: another frame rate, or the travel taken out.

Both run on the finished dance, so beats and steps keep their times and places. Film works at 24
fps, games at 60, mocap pipelines at 120; a game engine that moves the character itself wants the
dance in place.
"""

from __future__ import annotations

import numpy as np

from .filters import low_pass
from .motion import Motion
from .travel import FLOOR_AXES, ground_track

MIN_DELIVERY_FPS, MAX_DELIVERY_FPS = 10.0, 240.0  # the rates --fps takes (film 24 to mocap 120, and a margin)
ALIASING_MARGIN = 0.8  # share of the new Nyquist frequency kept when the rate falls
IN_PLACE_REACH = 0.02  # metres the ground track of an in-place dance may stray from its start
IN_PLACE_ROUNDS = 3


def delivered(motion: Motion, fps: float | None = None, without_travel: bool = False) -> Motion:
    """The finished ``motion`` as a file gets it: in place (``without_travel``), then at ``fps``."""
    motion = in_place(motion) if without_travel else motion
    return at_fps(motion, fps) if fps is not None else motion


def check_fps(fps: float) -> None:
    """Refuse, in one line, a frame rate a file is not written at."""
    from ..errors import ParameterError

    if not MIN_DELIVERY_FPS <= fps <= MAX_DELIVERY_FPS:
        raise ParameterError(f"--fps must be {MIN_DELIVERY_FPS:g} to {MAX_DELIVERY_FPS:g}, got {fps:g}")


def at_fps(motion: Motion, fps: float) -> Motion:
    """``motion`` at ``fps``: frame i at i / fps seconds, rotations slerped, the root interpolated.

    No frame lies past the last source frame, so none repeats (a plain resample holds the last
    frame). When the rate falls, every channel is low-passed below the new rate's Nyquist
    frequency first: picking every other frame of a fast turn would alias it into a slower one.
    """
    if np.isclose(fps, motion.fps):
        return motion
    if fps < motion.fps:
        motion = low_passed(motion, ALIASING_MARGIN * fps / 2)
    count = int(np.floor((motion.num_frames - 1) * fps / motion.fps + 1e-9)) + 1
    return motion.sample_frames(np.arange(count) * motion.fps / fps).replace(fps=float(fps))


def low_passed(motion: Motion, cutoff_hz: float) -> Motion:
    """Every joint's rotation (as quaternions kept in one hemisphere from frame to frame, then
    renormalised) and the root's position, low-passed at ``cutoff_hz``."""
    quaternions = motion.rotations.astype(np.float64)
    flips = np.cumprod(np.where((quaternions[1:] * quaternions[:-1]).sum(-1) < 0, -1.0, 1.0), axis=0)
    quaternions[1:] *= flips[..., None]
    smooth = low_pass(quaternions, motion.fps, cutoff_hz)
    smooth /= np.linalg.norm(smooth, axis=-1, keepdims=True)
    root = low_pass(motion.root_positions, motion.fps, cutoff_hz)
    return motion.replace(rotations=smooth.astype(motion.rotations.dtype),
                          root_positions=root.astype(motion.root_positions.dtype), metadata=dict(motion.metadata))


def in_place(motion: Motion) -> Motion:
    """``motion`` without its travel: the ground track (choreo.motion.travel) taken out of the root,
    so the dancer stays where it started. The sway and weight shifts around the track stay, and so
    do height and facing: a spinning dancer still spins. The track's low-pass also passes part of
    the sway near its cut-off, so taking it out once leaves a little travel: it is taken out again
    (at most IN_PLACE_ROUNDS times) until the track stays within IN_PLACE_REACH of the start, each
    round also taking a little of the slowest sway (docs/guide.md, "Game engines")."""
    root = motion.root_positions.astype(np.float64)
    for _ in range(IN_PLACE_ROUNDS):
        track = ground_track(root, motion.fps)
        offsets = track - track[:1]
        if np.linalg.norm(offsets, axis=-1).max() <= IN_PLACE_REACH:
            break
        root[:, list(FLOOR_AXES)] -= offsets
    return motion.replace(root_positions=root.astype(motion.root_positions.dtype), metadata=dict(motion.metadata))
