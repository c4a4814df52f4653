"""The `Motion` type, foot contacts and the 151-d frame vector."""

from .augment import mirrored, stretched, turned
from .beats import mean_joint_speed, motion_beats
from .contacts import CONTACT_SPEED_THRESHOLD, foot_contacts
from .motion import DEFAULT_FPS, Motion, positions_at, source_name
from .vector import FRAME_DIM, motion_to_vector, vector_to_motion

__all__ = [
    "CONTACT_SPEED_THRESHOLD", "DEFAULT_FPS", "FRAME_DIM", "Motion", "foot_contacts", "source_name",
    "mean_joint_speed", "mirrored", "motion_beats", "motion_to_vector", "positions_at", "stretched", "turned",
    "vector_to_motion",
]  # fmt: skip
