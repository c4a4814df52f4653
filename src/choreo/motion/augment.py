"""Honest ways to multiply dance data: a mirrored dancer, a dance at another pace, and the same
dance facing another way.

The same steps danced faster or slower are motion a real dancer could perform; the music
features are stretched with the motion by :func:`choreo.music.stretch_features`, so beats stay on
beats. The mirror image (left and right swapped, the path reflected) is one only for styles
without a handedness: ballroom's hold, line of dance and turns are chiral, and mirrored M2D
dances are far from real ones by FID (docs/sgmd.md). Turning the whole dance about the vertical
axis keeps its handedness (a rotation, not a reflection): the same dance started facing another
wall of the room.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .motion import Motion

MIRROR_AXIS = 0  # reflect x (+X is the body's left in SMPL), keep y (up) and z (forward)


def mirror_joint_order(names: tuple[str, ...]) -> np.ndarray:
    """For each joint, the index of its mirror twin (l_* <-> r_*; centre joints map to themselves)."""
    twin = {"l_": "r_", "r_": "l_"}
    order = []
    for name in names:
        other = twin[name[:2]] + name[2:] if name[:2] in twin else name
        if other not in names:
            raise ParameterError(f"joint {name!r} has no mirror twin {other!r} in the skeleton")
        order.append(names.index(other))
    return np.asarray(order)


def mirrored(motion: Motion) -> Motion:
    """The dance reflected in the body's sagittal plane: x negated, left and right joints swapped.

    Reflecting a rotation R by M = diag(-1, 1, 1) gives M R M, a rotation about the reflected
    axis (x, -y, -z) by the same angle: the quaternion (w, x, y, z) becomes (w, x, -y, -z).
    Exact for a symmetric skeleton (SMPL's template is symmetric to a few millimetres).
    """
    order = mirror_joint_order(motion.skeleton.names)
    rotations = motion.rotations[:, order] * np.array([1.0, 1.0, -1.0, -1.0])
    root = motion.root_positions * np.array([-1.0, 1.0, 1.0])
    metadata = dict(motion.metadata, mirrored=not motion.metadata.get("mirrored", False))
    return motion.replace(root_positions=root, rotations=rotations, metadata=metadata)


def stretched(motion: Motion, factor: float) -> Motion:
    """The dance ``factor`` times as fast (1.25: a quarter faster, and 1/1.25 as long).

    Frame i of the result is source frame i * factor (slerped); the frame rate stays the same.
    """
    if not 0.25 <= factor <= 4.0:
        raise ParameterError(f"stretch factor must be within [0.25, 4], got {factor}")
    num_frames = int(np.floor((motion.num_frames - 1) / factor)) + 1
    return motion.sample_frames(np.arange(num_frames) * factor)


def turned(motion: Motion, degrees: float) -> Motion:
    """The whole dance turned by ``degrees`` about the vertical (y) axis through its mean root
    position on the floor: the path rotates about that point and the root joint's orientation
    turns with it, so every joint position does."""
    from .stitch import rotate_about_y, turned_and_moved

    angle = np.deg2rad(float(degrees))
    centre = motion.root_positions.mean(axis=0) * np.array([1.0, 0.0, 1.0])
    out = turned_and_moved(motion, angle, centre - rotate_about_y(centre, angle))
    total = float(motion.metadata.get("turned_degrees", 0.0)) + float(degrees)
    return out.replace(metadata=dict(motion.metadata, turned_degrees=total))
