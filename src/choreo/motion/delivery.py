"""What a file gets after the finishing passes: another frame rate, the travel taken out, or the
travel moved onto a root bone.

All run on the finished dance, so beats and steps keep their times and places. Film works at 24
fps, games at 60, mocap pipelines at 120; a game engine that moves the character itself wants the
dance in place, one that takes root motion wants the travel on a bone at floor level.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import MotionFormatError
from ..skeleton import Skeleton, quaternion_conjugate, quaternion_multiply, quaternion_to_matrix
from .filters import low_pass
from .motion import Motion, frame_chunks
from .seam import CLOSING_SECONDS, closed, next_cycle
from .stitch import rotate_about_y
from .travel import FLOOR_AXES, TRACK_CUTOFF_HZ, ground_track

ALIASING_MARGIN = 0.8  # share of the new Nyquist frequency kept when the rate falls
IN_PLACE_REACH = 0.02  # metres the ground track of an in-place dance may stray from its start
IN_PLACE_ROUNDS = 3
ROOT_BONE = "root"  # the name Unreal's and Unity's root motion look for first
ROOT_BONE_CUTOFF_HZ = 0.4  # the root bone's path and facing: slower than the 1 Hz ground track, so it is smooth to
# the centimetre where the 1 Hz track itself still carries a little of the steps (docs/guide.md, "Game engines")


def delivered(motion: Motion, fps: float | None = None, without_travel: bool = False) -> Motion:
    """The finished ``motion`` as a file gets it: in place (``without_travel``), then at ``fps``
    (a loop stays a loop: :func:`delivered_loop`)."""
    if "loop" in motion.metadata:
        return delivered_loop(motion, fps, without_travel)
    motion = in_place(motion) if without_travel else motion
    return at_fps(motion, fps) if fps is not None else motion


def delivered_loop(motion: Motion, fps: float | None = None, without_travel: bool = False) -> Motion:
    """A loop in place (its per-cycle travel then only the turn about where it started) and at
    ``fps``, still a loop: resampled over whole cycles, so ``fps`` times its length, rounded,
    frames play one cycle (its tempo off by under half a frame per cycle), then closed again."""
    changed = without_travel or (fps is not None and not np.isclose(fps, motion.fps))
    if without_travel:
        track = ground_track(motion.root_positions, motion.fps)[0]  # in place keeps the track's start
        start = np.array([track[0], 0.0, track[1]])
        motion = in_place(motion)
        travel = start - rotate_about_y(start, np.radians(motion.metadata["loop"]["turn_degrees"]))
        motion.metadata = dict(motion.metadata, loop=dict(motion.metadata["loop"], travel_m=[travel[0], travel[2]]))
    if fps is not None and not np.isclose(fps, motion.fps):
        count = max(2, int(round(motion.num_frames * fps / motion.fps)))
        around = Motion.concatenate([motion, next_cycle(motion, 1)])
        around = low_passed(around, ALIASING_MARGIN * fps / 2) if fps < motion.fps else around
        loop = dict(motion.metadata["loop"], seconds=round(count / fps, 4))
        motion = around.sample_frames(np.arange(count) * motion.num_frames / count).replace(
            fps=float(fps), metadata=dict(motion.metadata, loop=loop))
    return closed(motion, int(round(CLOSING_SECONDS * motion.fps))) if changed else motion


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


class RootBoneDance(NamedTuple):
    """A dance under a root bone: ``motion``'s joint 0 is the root bone, joint 1 the dance's own
    root (pelvis or Hips), which also moves relative to it by ``hips_positions``."""

    motion: Motion
    hips_positions: np.ndarray  # (T, 3) the dance's root in the root bone's frame


def with_root_bone(motion: Motion) -> RootBoneDance:
    """``motion`` under a root bone for game engines' root motion: the bone stays at floor level
    (:func:`floor_height`), carries the ground track (choreo.motion.travel) and the facing low-passed
    as much, and the dance's root moves relative to it. So an engine's capsule travels and turns
    with the dancer without inheriting the hips' sway, twist and jitter. In the rest pose the
    dance's root stands above the bone at its own height, the lowest joint on the floor. The path
    and facing are low-passed at ROOT_BONE_CUTOFF_HZ."""
    if ROOT_BONE in motion.skeleton.names:
        raise MotionFormatError(f"the skeleton already has a joint named {ROOT_BONE!r}: it cannot gain a root bone")
    track = ground_track(motion.root_positions, motion.fps, ROOT_BONE_CUTOFF_HZ)
    positions = np.zeros((motion.num_frames, 3))
    positions[:, list(FLOOR_AXES)] = track
    positions[:, 1] = floor_height(motion)
    facing = facing_quaternions(motion, ROOT_BONE_CUTOFF_HZ)
    turned_back = quaternion_conjugate(facing)
    hips_positions = np.einsum("tij,tj->ti", quaternion_to_matrix(turned_back), motion.root_positions - positions)
    rotations = np.concatenate([facing[:, None], motion.rotations], axis=1)
    rotations[:, 1] = quaternion_multiply(turned_back, motion.rotations[:, 0])
    skeleton = motion.skeleton
    standing = -skeleton.rest_positions()[:, 1].min()
    offsets = np.concatenate([[[0.0, 0.0, 0.0], [0.0, standing, 0.0]], skeleton.offsets[1:]])
    parents = (-1, 0, *(p + 1 for p in skeleton.parents[1:]))
    under = Skeleton((ROOT_BONE, *skeleton.names), parents, offsets)
    return RootBoneDance(motion.replace(root_positions=positions, rotations=rotations, skeleton=under,
                                        metadata=dict(motion.metadata)), hips_positions)


def floor_height(motion: Motion) -> float:
    """Where the floor is: the lowest joint's height, over the frames, at its median. A foot is down
    in most frames of a dance, and the lowest joint stands on the floor as the rest pose does."""
    if motion.num_frames == 0:
        return 0.0
    lowest = [motion[frames].joint_positions()[..., 1].min(axis=1) for frames in frame_chunks(motion.num_frames)]
    return float(np.median(np.concatenate(lowest)))


def facing_quaternions(motion: Motion, cutoff_hz: float = TRACK_CUTOFF_HZ) -> np.ndarray:
    """(T, 4) turns about Y: the root joint's heading (its twist about the vertical, which holds
    even where the body leans or tips), unwrapped and low-passed at ``cutoff_hz``."""
    w, y = motion.rotations[:, 0, 0], motion.rotations[:, 0, 2]
    heading = np.unwrap(2.0 * np.arctan2(y, w))
    heading = low_pass(heading, motion.fps, cutoff_hz) if motion.num_frames else heading
    facing = np.zeros((motion.num_frames, 4))
    facing[:, 0], facing[:, 2] = np.cos(heading / 2.0), np.sin(heading / 2.0)
    return facing
