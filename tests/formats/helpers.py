"""Motions, files and checks shared by the format tests."""

import io
import math

import numpy as np
from scipy.spatial.transform import Rotation

from choreo.motion import Motion
from choreo.skeleton import SMPL24

TOLERANCE = 1e-4  # 0.1 mm


def random_motion(frames=40, fps=30.0, seed=0, wild=False):
    rng = np.random.default_rng(seed)
    if wild:  # any rotation at all, including angles near 180 degrees
        axis_angle = rng.normal(size=(frames, 24, 3))
        axis_angle *= (rng.uniform(0, math.pi, size=(frames, 24, 1)) / np.linalg.norm(axis_angle, axis=-1, keepdims=True))
    else:
        axis_angle = np.cumsum(rng.normal(scale=0.05, size=(frames, 24, 3)), axis=0)
    root = rng.normal(scale=0.5, size=(frames, 3)) + [0, 0.9, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps, metadata={"seed": 7, "style": "waltz"})


def max_joint_error(a: Motion, b: Motion) -> float:
    return float(np.abs(a.joint_positions() - b.joint_positions()).max())


J = {name: j for j, name in enumerate(SMPL24.names)}


def save(tmp_path, text, name="rig.bvh"):
    path = tmp_path / name
    path.write_text(text)
    return path


def file_forward_kinematics(data):
    """World positions of every joint and End Site of a parsed BVH, by a literal walk with scipy's rotations."""
    frames = len(data.values)
    starts = np.cumsum([0] + [len(j.channels) for j in data.joints])
    positions, tips, world = {}, {}, {}
    for j, joint in enumerate(data.joints):
        values = data.values[:, starts[j]:starts[j + 1]]
        axes = "".join(c[0].upper() for c in joint.channels if c.endswith("rotation"))
        angles = values[:, [k for k, c in enumerate(joint.channels) if c.endswith("rotation")]]
        local = Rotation.from_euler(axes, angles, degrees=True).as_matrix() if axes else np.tile(np.eye(3), (frames, 1, 1))
        if joint.parent < 0:
            base = np.tile(joint.offset, (frames, 1))
            for k, c in enumerate(joint.channels):
                if c.endswith("position"):
                    base[:, "xyz".index(c[0])] += values[:, k]
            world[j], positions[j] = local, base
        else:  # a position channel stands for the offset on its axis (a root bone's pelvis has them)
            p = joint.parent
            offset = np.tile(joint.offset, (frames, 1))
            for k, c in enumerate(joint.channels):
                if c.endswith("position"):
                    offset[:, "xyz".index(c[0])] = values[:, k]
            positions[j] = positions[p] + np.einsum("tij,tj->ti", world[p], offset)
            world[j] = world[p] @ local
        if joint.end_site is not None:
            tips[j] = positions[j] + world[j] @ joint.end_site
    return positions, tips


def smpl_arrays(frames=2):
    rng = np.random.default_rng(5)
    return rng.normal(scale=0.3, size=(frames, 72)), rng.normal(size=(frames, 3)) + [0, 1, 0]


def save_npz(tmp_path, **arrays):
    path = tmp_path / "m.npz"
    np.savez(path, **arrays)
    return path


def still(frames: int, fps=30.0, skeleton=SMPL24) -> Motion:
    rotations = np.zeros((frames, 24, 4))
    rotations[..., 0] = 1.0
    return Motion(np.tile([0.0, 0.9, 0.0], (frames, 1)), rotations, fps=fps, skeleton=skeleton)


def npy_with_header(text: str) -> bytes:
    """An .npy whose header dict is ``text`` (padded as numpy pads it), then 48 bytes of data."""
    header = text.encode()
    header += b" " * (64 - 10 - len(header) % 64 - 1) + b"\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header + bytes(48)


def small_motion(frames: int = 4) -> Motion:
    rng = np.random.default_rng(0)
    return Motion.from_axis_angle(np.zeros((frames, 3)) + [0, 0.9, 0], rng.normal(scale=0.1, size=(frames, 24, 3)))


def npz_bytes(**arrays) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()
