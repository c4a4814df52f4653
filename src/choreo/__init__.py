"""choreo: music-to-dance generation, editing and evaluation.

The core package holds what every generator shares: the SMPL-24 skeleton and kinematics,
:class:`~choreo.motion.Motion`, music loading and features, motion file formats, datasets and the
generator registry. Backends live in separate plugin packages registered through entry points.
"""

__version__ = "0.1.0"

from .errors import ChoreoError  # noqa: E402

__all__ = ["ChoreoError", "__version__", "dance", "load_backend"]


def __getattr__(name: str):
    """``choreo.dance`` and ``choreo.load_backend`` without importing torch or librosa until used."""
    if name in ("dance", "load_backend"):
        from . import pipeline

        return getattr(pipeline, name)
    raise AttributeError(f"module 'choreo' has no attribute {name!r}")
