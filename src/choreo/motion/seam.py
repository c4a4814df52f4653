"""A loop's seam: the end of a looped dance run into its next cycle's opening as into its own next
frame. The end is bent by a smooth displacement (:func:`bent_into`), each foot then taking its
share while it moves (:func:`stepping_into`); the next cycle is the opening turned and moved by the
per-cycle turn and travel in the metadata (:func:`next_cycle`). Where loops are planned and danced:
choreo.looping."""

from __future__ import annotations

import numpy as np

from ..skeleton import axis_angle_to_quaternion, quaternion_conjugate, quaternion_multiply, quaternion_to_axis_angle
from ..skeleton.legs import LEGS, legs_reaching
from .motion import Motion
from .stitch import turned_and_moved

CLOSING_SECONDS = 0.5  # the end of the loop bent into the next cycle's opening, pose and velocity


def closed(motion: Motion, frames: int) -> Motion:
    """A looped ``motion`` that runs into its next cycle (:func:`next_cycle`) as into its own next
    frame: its last ``frames`` bent by :func:`bent_into`, each ankle then moved while its foot
    moves (:func:`stepping_into`)."""
    return stepping_into(motion, bent_into(motion, next_cycle(motion, 2), motion.num_frames, frames), frames)


def stepping_into(motion: Motion, bent: Motion, frames: int) -> Motion:
    """``bent`` (``motion`` with its end bent) with each ankle's share of the bend taken while that
    foot moves in ``motion``, in proportion to its speed, not evenly over the frames: a bend over
    a standing foot would slide it. The legs reach the ankles by two-bone IK (choreo.skeleton.legs)."""
    frames = min(frames, motion.num_frames - 1)
    if frames < 2:
        return bent
    tail = slice(motion.num_frames - frames, motion.num_frames)
    ankles = [leg[2] for leg in LEGS]
    before = motion.slice_frames(tail.start - 1).joint_positions()[:, ankles]  # one frame before, for speeds
    after = bent.slice_frames(tail.start).joint_positions()
    moved = after[:, ankles] - before[1:]  # what the bend did to each ankle
    speed = np.linalg.norm(np.diff(before, axis=0), axis=-1)  # (frames, 2)
    share = np.cumsum(speed, axis=0) / np.maximum(speed.sum(axis=0), 1e-9)
    share = np.where(speed.sum(axis=0) > 1e-6, share, np.linspace(1 / frames, 1, frames)[:, None])
    targets = before[1:] + share[..., None] * moved[-1]
    rotations = bent.rotations.copy()
    rotations[tail] = legs_reaching(bent.rotations[tail], after, targets, bent.skeleton.parents)
    return bent.replace(rotations=rotations, metadata=dict(bent.metadata))


def bent_into(motion: Motion, after: Motion, end: int, frames: int) -> Motion:
    """``motion`` with the ``frames`` before frame ``end`` bent so that they run into ``after``'s
    two frames as into their own next ones: the extrapolated pose and the velocity at ``end``
    meet them. The bend is a cubic (Hermite) displacement, zero and flat where it starts, on the
    root's position and on each joint's rotation (in its own frame); frames from ``end`` on stay."""
    frames = min(frames, end - 2)
    if frames < 2:
        return motion
    root, rotations = motion.root_positions.copy(), motion.rotations.copy()
    last, before = end - 1, end - 2
    step = root[last] - root[before]
    root_error = (after.root_positions[0] - (root[last] + step), after.root_positions[1] - after.root_positions[0] - step)
    turn = quaternion_multiply(quaternion_conjugate(rotations[before]), rotations[last])  # each joint's last step
    ahead = quaternion_multiply(rotations[last], turn)
    turn_after = quaternion_multiply(quaternion_conjugate(after.rotations[0]), after.rotations[1])
    rotation_error = (quaternion_to_axis_angle(quaternion_multiply(quaternion_conjugate(ahead), after.rotations[0])),
                      quaternion_to_axis_angle(quaternion_multiply(quaternion_conjugate(turn), turn_after)))
    s = np.arange(frames) / frames  # 0 where the bend starts; 1 would be ``after``'s first frame
    reach, slope = 3 * s**2 - 2 * s**3, (s**3 - s**2) * frames  # Hermite: value and slope at the end
    tail = slice(end - frames, end)
    root[tail] += reach[:, None] * root_error[0] + slope[:, None] * root_error[1]
    bend = reach[:, None, None] * rotation_error[0] + slope[:, None, None] * rotation_error[1]
    rotations[tail] = quaternion_multiply(rotations[tail], axis_angle_to_quaternion(bend))
    return motion.replace(root_positions=root, rotations=rotations, metadata=dict(motion.metadata))


def next_cycle(motion: Motion, frames: int = 1) -> Motion:
    """The first ``frames`` of a looped ``motion`` as they come again after its end: turned and
    moved by the per-cycle turn and travel its metadata carries."""
    loop = motion.metadata["loop"]
    travel = loop["travel_m"]
    return turned_and_moved(motion.slice_frames(0, frames), np.radians(loop["turn_degrees"]),
                            np.array([travel[0], 0.0, travel[1]]))
