"""Putting pieces of motion side by side: facing, local frames, rigid placement and cross-fades.

Clip-based synthesis (ChoreoGraph's motion graph, seed motions) takes pieces danced anywhere in a
room; before two pieces can be compared or joined they must be expressed where and how the dancer
stands, and joined without a jump. Y is up; the SMPL body faces +z, its left hip towards +x.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import rotations as rot
from .motion import Motion

LEFT_HIP, RIGHT_HIP = 1, 2


def facing_yaw(joint_positions: np.ndarray) -> np.ndarray:
    """(...,) heading about +y of every frame, from the hips (0 = facing +z)."""
    return heading_of(joint_positions[..., LEFT_HIP, :] - joint_positions[..., RIGHT_HIP, :])


def heading_of(across: np.ndarray) -> np.ndarray:
    """(...,) heading about +y of a body whose right-to-left hip vector is ``across`` (..., 3)."""
    # forward = across x up, with up = +y: (-across_z, 0, across_x)
    return np.arctan2(-across[..., 2], across[..., 0])


def rotate_about_y(points: np.ndarray, angle) -> np.ndarray:
    """Rotate (..., 3) points by ``angle`` radians about +y (broadcast over leading dims)."""
    cos, sin = np.cos(angle), np.sin(angle)
    x, y, z = points[..., 0], points[..., 1], points[..., 2]
    return np.stack([cos * x + sin * z, y, -sin * x + cos * z], axis=-1)


def local_positions(joint_positions: np.ndarray) -> np.ndarray:
    """(T, J, 3) positions seen from the first frame: its root over the origin, facing +z.

    Turning and travelling within the excerpt are kept (they are part of a style); where in the
    room and which way the excerpt started are removed.
    """
    origin = joint_positions[0, 0] * np.array([1.0, 0.0, 1.0])
    yaw = facing_yaw(joint_positions[0])
    return rotate_about_y(joint_positions - origin, -yaw)


def frame_local_positions(joint_positions: np.ndarray) -> np.ndarray:
    """(..., J, 3) every frame on its own: root over the origin, facing +z (poses to compare)."""
    origin = joint_positions[..., :1, :] * np.array([1.0, 0.0, 1.0])
    yaw = facing_yaw(joint_positions)[..., None]
    return rotate_about_y(joint_positions - origin, -yaw)


def turned_and_moved(motion: Motion, angle: float, offset: np.ndarray) -> Motion:
    """``motion`` turned by ``angle`` about the vertical through the origin, then shifted by ``offset``."""
    half = angle / 2
    turn = np.array([np.cos(half), 0.0, np.sin(half), 0.0])
    rotations = motion.rotations.copy()
    rotations[:, 0] = rot.quaternion_multiply(np.broadcast_to(turn, rotations[:, 0].shape).copy(), rotations[:, 0])
    root = rotate_about_y(motion.root_positions, angle) + np.asarray(offset, dtype=np.float64)
    return motion.replace(root_positions=root, rotations=rotations, metadata=dict(motion.metadata))


def placement_onto(piece: Motion, target_root: np.ndarray, target_yaw: float) -> tuple[float, np.ndarray]:
    """The (angle, offset) that puts ``piece``'s first frame at ``target_root`` (x, z), facing ``target_yaw``.

    Height is never changed: a piece keeps its own relation to the floor.
    """
    first = piece.slice_frames(0, 1).joint_positions()[0]
    angle = float(target_yaw - facing_yaw(first))
    turned_root = rotate_about_y(piece.root_positions[0], angle)
    offset = np.array([target_root[0] - turned_root[0], 0.0, target_root[2] - turned_root[2]])
    return angle, offset


def crossfade(outgoing: Motion, incoming: Motion) -> Motion:
    """``incoming`` with its first frames blended from ``outgoing`` (same length): a linear ramp.

    Frame k takes weight (k + 1) / (n + 1) from ``incoming``: never all of either side, so the
    seam leaves neither piece unchanged at the joint.
    """
    frames = min(outgoing.num_frames, incoming.num_frames)
    weight = (np.arange(frames) + 1.0) / (frames + 1.0)
    root = incoming.root_positions.copy()
    root[:frames] = (1 - weight)[:, None] * outgoing.root_positions[:frames] + weight[:, None] * root[:frames]
    rotations = incoming.rotations.copy()
    joints = incoming.num_joints
    rotations[:frames] = rot.quaternion_slerp(outgoing.rotations[:frames], rotations[:frames],
                                              np.broadcast_to(weight[:, None], (frames, joints)).copy())
    return incoming.replace(root_positions=root, rotations=rotations)
