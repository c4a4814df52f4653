"""JSON: one self-describing document for game engines and web viewers.

``{"format": "choreo-motion", "version": 1, "fps", "joint_names", "parents", "offsets",
"root_positions" (T x 3), "rotations" (T x 24 x 3 axis-angle, radians), "joint_positions"
(T x 24 x 3), "metadata"}``; metres, Y up.
"""

from __future__ import annotations

import json

import numpy as np

from ..errors import MotionFormatError, ParameterError
from ..fileio import json_safe
from ..motion import Motion, source_name
from ..motion.motion import file_metadata
from ..skeleton import SMPL24, Skeleton
from . import json_arrays

FORMAT_NAME, VERSION = "choreo-motion", 1
BULK_ARRAYS = ("root_positions", "rotations", "joint_positions")  # read straight into numpy


CHUNK_FRAMES = 2048  # frames of a bulk array turned to text at once


def write_json(motion: Motion, handle) -> None:
    """The document, its bulk arrays written a block of frames at a time, byte for byte what one
    ``json.dumps`` of it gives: that built every number as a Python float and the whole text in
    memory (20 minutes at 120 fps peaked at 4 GB); this holds the motion's arrays and one block."""
    head = {"format": FORMAT_NAME, "version": VERSION, "fps": motion.fps, "joint_names": list(motion.skeleton.names),
            "parents": list(motion.skeleton.parents), "offsets": np.round(motion.skeleton.offsets, 6).tolist()}
    bulk = {"root_positions": (motion.root_positions, 6), "rotations": (motion.axis_angle(), 7),
            "joint_positions": (motion.joint_positions(), 5)}
    handle.write(json.dumps(json_safe(head))[:-1].encode())
    for name, (values, decimals) in bulk.items():
        handle.write(f", {json.dumps(name)}: [".encode())
        for start in range(0, len(values), CHUNK_FRAMES):
            block = json.dumps(np.round(values[start:start + CHUNK_FRAMES], decimals).tolist())[1:-1]
            handle.write(((", " if start else "") + block).encode())
        handle.write(b"]")
    handle.write(f', "metadata": {json.dumps(json_safe(motion.metadata), default=str)}}}'.encode())


def _metadata(document: dict, path) -> dict:
    """The file's metadata, its source reduced to a file name (older files hold absolute paths)."""
    stored = document.get("metadata") or {}
    metadata = file_metadata(dict(stored))  # a list of pairs too, as before
    metadata["source"] = source_name(str(metadata.get("source") or path))
    return metadata


def _joint_names(document: dict, path) -> tuple[str, ...]:
    """The file's joint names, refused unless a list of strings (writers and `info` treat them as text)."""
    names = document["joint_names"]
    if not (isinstance(names, list) and all(isinstance(name, str) for name in names)):
        raise MotionFormatError(f"{path}: joint_names must be a list of strings")
    return tuple(names)


def _parents(document: dict, path) -> tuple[int, ...]:
    """The parent indices, refused unless whole numbers (they index the joints)."""
    parents = document["parents"]
    if not (isinstance(parents, list) and all(type(p) is int for p in parents)):
        raise MotionFormatError(f"{path}: parents must be a list of joint indices")
    return tuple(parents)


def read_json(path) -> Motion:
    try:
        with open(path, encoding="utf-8") as handle:
            document = json_arrays.loads(handle.read(), arrays_at=BULK_ARRAYS)
        if document.get("format") != FORMAT_NAME:
            raise MotionFormatError(f"{path}: not a choreo motion JSON (format field missing)")
        skeleton = Skeleton(_joint_names(document, path), _parents(document, path), np.array(document["offsets"]))
        if skeleton.same_topology(SMPL24):
            skeleton = SMPL24.with_offsets(skeleton.offsets)
        return Motion.from_axis_angle(np.array(document["root_positions"], dtype=np.float64),
                                      np.array(document["rotations"], dtype=np.float64),
                                      fps=float(document["fps"]), skeleton=skeleton,
                                      metadata=_metadata(document, path))
    except MotionFormatError:
        raise
    except (OSError, ValueError, KeyError, TypeError, AttributeError, OverflowError, IndexError) as error:
        raise MotionFormatError(f"{path}: malformed motion JSON ({type(error).__name__})") from None
    except ParameterError as error:  # values a motion cannot have (NaN, an fps outside 1-1000)
        raise MotionFormatError(f"{path}: {error}") from None
