"""JSON: one self-describing document for game engines and web viewers.

``{"format": "choreo-motion", "version": 1, "fps", "joint_names", "parents", "offsets",
"root_positions" (T x 3), "rotations" (T x 24 x 3 axis-angle, radians), "joint_positions"
(T x 24 x 3), "metadata"}``; metres, Y up.
"""

from __future__ import annotations

import json

import numpy as np

from ..errors import MotionFormatError, ParameterError
from ..motion import Motion
from ..skeleton import SMPL24, Skeleton

FORMAT_NAME, VERSION = "choreo-motion", 1


def write_json(motion: Motion, handle) -> None:
    document = {
        "format": FORMAT_NAME, "version": VERSION, "fps": motion.fps,
        "joint_names": list(motion.skeleton.names), "parents": list(motion.skeleton.parents),
        "offsets": np.round(motion.skeleton.offsets, 6).tolist(),
        "root_positions": np.round(motion.root_positions, 6).tolist(),
        "rotations": np.round(motion.axis_angle(), 7).tolist(),
        "joint_positions": np.round(motion.joint_positions(), 5).tolist(),
        "metadata": motion.metadata,
    }  # fmt: skip
    handle.write(json.dumps(document, default=str).encode())


def read_json(path) -> Motion:
    try:
        with open(path, encoding="utf-8") as handle:
            document = json.load(handle)
        if document.get("format") != FORMAT_NAME:
            raise MotionFormatError(f"{path}: not a choreo motion JSON (format field missing)")
        skeleton = Skeleton(tuple(document["joint_names"]), tuple(document["parents"]), np.array(document["offsets"]))
        if skeleton.same_topology(SMPL24):
            skeleton = SMPL24.with_offsets(skeleton.offsets)
        return Motion.from_axis_angle(np.array(document["root_positions"], dtype=np.float64),
                                      np.array(document["rotations"], dtype=np.float64),
                                      fps=float(document["fps"]), skeleton=skeleton,
                                      metadata=dict(document.get("metadata") or {}))
    except MotionFormatError:
        raise
    except (OSError, ValueError, KeyError, TypeError, AttributeError, OverflowError) as error:
        raise MotionFormatError(f"{path}: malformed motion JSON ({type(error).__name__})") from None
    except ParameterError as error:  # values a motion cannot have (NaN, an fps outside 1-1000)
        raise MotionFormatError(f"{path}: {error}") from None
