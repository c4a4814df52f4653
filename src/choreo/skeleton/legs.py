"""The legs of SMPL-24 reaching given ankle positions: two-bone IK (hip and knee), each foot
keeping its world orientation. The footsteps pass plants the feet with it (choreo.finishing.footsteps),
a loop's seam moves them with it (choreo.motion.seam)."""

from __future__ import annotations

import numpy as np

from . import rotations as rot
from .kinematics import global_rotations

LEGS = ((1, 4, 7), (2, 5, 8))  # (hip, knee, ankle) of the left and the right leg in SMPL-24
TURNED_JOINTS = tuple(joint for leg in LEGS for joint in leg)  # the only rotations the legs' IK changes


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, 3, 3) shortest rotations taking directions ``a`` onto ``b`` (N, 3)."""
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    axis = np.cross(a, b)
    sin = np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = np.arctan2(sin[:, 0], (a * b).sum(-1))
    axis = np.where(sin > 1e-9, axis / np.maximum(sin, 1e-12), [1.0, 0.0, 0.0])
    return rot.axis_angle_to_matrix(axis * angle[:, None])


def two_bone_ik(globals_: np.ndarray, positions: np.ndarray, leg: tuple[int, int, int],
                targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """New world rotations (T, 3, 3) of the hip and the knee that put the ankle at ``targets``
    (as near as the leg reaches): the knee bends in its own plane to the right hip-ankle distance,
    then the hip turns the leg onto the target."""
    hip, knee, ankle = leg
    h, k, a = positions[:, hip], positions[:, knee], positions[:, ankle]
    upper, lower = np.linalg.norm(k - h, axis=-1), np.linalg.norm(a - k, axis=-1)
    reach = np.clip(np.linalg.norm(targets - h, axis=-1), np.abs(upper - lower) + 1e-4, upper + lower - 1e-4)
    wanted_angle = np.arccos(np.clip((upper**2 + lower**2 - reach**2) / (2 * upper * lower), -1.0, 1.0))
    current_angle = np.arccos(np.clip(((h - k) * (a - k)).sum(-1) / (upper * lower), -1.0, 1.0))
    normal = np.cross(h - k, a - k)
    size = np.linalg.norm(normal, axis=-1, keepdims=True)
    lateral = globals_[:, knee, :, 0]  # a straight leg has no plane: bend about the knee's own x axis
    normal = np.where(size > 1e-6, normal / np.maximum(size, 1e-12), lateral)
    bend = rot.axis_angle_to_matrix(normal * (wanted_angle - current_angle)[:, None])  # opens the angle at the knee
    knee_world = bend @ globals_[:, knee]
    bent_ankle = k + np.einsum("tij,tj->ti", bend, a - k)
    turn = rotation_between(bent_ankle - h, targets - h)
    return turn @ globals_[:, hip], turn @ knee_world


def legs_reaching(quaternions: np.ndarray, positions: np.ndarray, targets: np.ndarray, parents) -> np.ndarray:
    """(T, J, 4) local rotations with each leg's hip, knee and ankle turned so its ankle reaches
    ``targets`` (T, 2, 3), every foot keeping its world orientation."""
    local = rot.quaternion_to_matrix(quaternions)
    world = global_rotations(local, parents)
    for side, (hip, knee, ankle) in enumerate(LEGS):
        hip_world, knee_world = two_bone_ik(world, positions, (hip, knee, ankle), targets[:, side])
        local[:, hip] = np.swapaxes(world[:, parents[hip]], -1, -2) @ hip_world
        local[:, knee] = np.swapaxes(hip_world, -1, -2) @ knee_world
        local[:, ankle] = np.swapaxes(knee_world, -1, -2) @ world[:, ankle]  # the foot keeps its orientation
    out = quaternions.copy()
    legs = list(TURNED_JOINTS)
    turned = rot.matrix_to_quaternion(local[:, legs])
    same_side = np.sign((turned * quaternions[:, legs]).sum(-1, keepdims=True) + 1e-12)  # q and -q: keep the input's sign
    out[:, legs] = turned * same_side
    return out
