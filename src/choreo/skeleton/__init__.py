"""Skeletons, forward kinematics and rotation conversions."""

from .kinematics import forward_kinematics, forward_kinematics_torch, global_rotations
from .rotations import *  # noqa: F401,F403
from .rotations import __all__ as _rotation_names
from .smpl import (
    FOOT_JOINTS,
    JOINT_NAMES,
    LEFT_ANKLE_FOOT,
    RIGHT_ANKLE_FOOT,
    LOWER_BODY_JOINTS,
    PARENTS,
    SMPL24,
    UPPER_BODY_JOINTS,
    Skeleton,
)

__all__ = [
    "FOOT_JOINTS", "JOINT_NAMES", "LEFT_ANKLE_FOOT", "RIGHT_ANKLE_FOOT", "LOWER_BODY_JOINTS", "PARENTS", "SMPL24", "UPPER_BODY_JOINTS",
    "Skeleton", "forward_kinematics", "forward_kinematics_torch", "global_rotations",
    *_rotation_names,
]  # fmt: skip
