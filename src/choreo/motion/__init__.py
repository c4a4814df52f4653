"""The `Motion` type, foot contacts and the 151-d frame vector (each name loads its module on
first use: choreo.lazy)."""

from ..lazy import lazy_exports

_HOMES = {
    ".augment": ("mirrored", "stretched", "turned"),
    ".beats": ("mean_joint_speed", "motion_beats"),
    ".contacts": ("CONTACT_SPEED_THRESHOLD", "foot_contacts"),
    ".motion": ("DEFAULT_FPS", "Motion", "positions_at", "source_name"),
    ".vector": ("FRAME_DIM", "motion_to_vector", "vector_to_motion"),
}
_EXPORTS = {name: module for module, names in _HOMES.items() for name in names}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
