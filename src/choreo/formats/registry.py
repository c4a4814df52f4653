"""Choose a reader or writer by file extension or format name (whisper's ``get_writer`` idea)."""

from __future__ import annotations

import contextlib

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import InputError, MotionFormatError, OutputError
from ..fileio import STDOUT, atomic_output
from ..motion import Motion
from .aistpp import read_aistpp_pkl, write_aistpp_pkl
from .bvh import read_bvh, write_bvh
from .gltf import read_glb, write_glb
from .json_format import read_json, write_json
from .npy import read_npy_joint_positions, write_npy
from .npz import read_npz, read_npz_joint_positions, write_npz


@dataclass(frozen=True)
class MotionFormat:
    name: str
    extension: str
    description: str
    read: Callable[[Path], Motion] | None  # None: positions only (no rotations to read)
    write: Callable[[Motion, object], None]


FORMATS = {
    f.name: f
    for f in (
        MotionFormat("bvh", ".bvh", "BVH, SMPL-24 skeleton, metres, Y up", read_bvh, write_bvh),
        MotionFormat("npz", ".npz", "NPZ with AIST++ keys (smpl_poses, smpl_trans, ...)", read_npz, write_npz),
        MotionFormat("pkl", ".pkl", "AIST++ motion pickle (60 fps on read)", read_aistpp_pkl, write_aistpp_pkl),
        MotionFormat("json", ".json", "choreo motion JSON", read_json, write_json),
        MotionFormat("npy", ".npy", "joint positions (T, 24, 3), metres, Y up", None, write_npy),
        MotionFormat("glb", ".glb", "glTF 2.0 binary: SMPL-24 skin, a skinned body, the dance as its animation",
                     read_glb, write_glb),
    )
}


def list_formats() -> list[MotionFormat]:
    return list(FORMATS.values())


def _format_for(path: str | os.PathLike, format: str | None, error: type) -> MotionFormat:
    if format is not None:
        key = format.lower().lstrip(".")
        if key not in FORMATS:
            raise error(f"unknown motion format {format!r} (supported: {', '.join(FORMATS)})")
        return FORMATS[key]
    suffix = Path(str(path)).suffix.lower()
    for candidate in FORMATS.values():
        if candidate.extension == suffix:
            return candidate
    raise error(f"{path}: unknown motion file type {suffix or '(none)'!r} "
                f"(supported: {', '.join(f.extension for f in FORMATS.values())})")


def _check_readable(path: Path) -> None:
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if path.is_dir():
        raise InputError(f"{path} is a folder, expected a motion file")
    if path.stat().st_size == 0:
        raise MotionFormatError(f"{path} is empty")


def read_motion(path: str | os.PathLike, format: str | None = None) -> Motion:
    """Read a motion file into a Motion (metres, Y up, the file's own fps)."""
    path = Path(path)
    chosen = _format_for(path, format, InputError)
    _check_readable(path)
    if chosen.read is None:
        raise InputError(f"{path}: a {chosen.extension} file holds joint positions only, not a rotation-based motion")
    return chosen.read(path)


def read_joint_positions(path: str | os.PathLike, format: str | None = None) -> tuple[np.ndarray, float | None]:
    """(T, 24, 3) joint positions from any supported file, and its fps (None when unknown: .npy)."""
    path = Path(path)
    chosen = _format_for(path, format, InputError)
    _check_readable(path)
    if chosen.name == "npy":
        return read_npy_joint_positions(path), None
    motion = chosen.read(path)
    if chosen.name == "npz":
        stored = read_npz_joint_positions(path)
        if stored is not None and stored.shape == (motion.num_frames, 24, 3):
            return stored, motion.fps
    return motion.joint_positions(), motion.fps


def check_output_format(path: str | os.PathLike, format: str | None = None) -> None:
    """Refuse (OutputError, exit 3) an output whose format is unknown, before any work is done."""
    if str(path) == STDOUT and format is None:
        raise OutputError("writing to stdout (-) needs an explicit --format")
    _format_for(path, format, OutputError)


def write_motions(motion: Motion, paths: list[str], format: str | None = None) -> list[str]:
    """Write ``motion`` to every path, all or none: each file is written in full to a temporary
    beside it, and only when every one is written are they moved into place."""
    for path in paths:
        check_output_format(path, format)
    with contextlib.ExitStack() as stack:
        for path in paths:
            handle = stack.enter_context(atomic_output(path))
            _format_for(path, format, OutputError).write(motion, handle)
    return [str(p) for p in paths]


def write_motion(motion: Motion, path: str | os.PathLike, format: str | None = None) -> str:
    """Write ``motion`` atomically (or to stdout for "-"); returns the path written."""
    if str(path) == STDOUT and format is None:
        raise OutputError("writing to stdout (-) needs an explicit --format")
    chosen = _format_for(path, format, OutputError)
    with atomic_output(path) as handle:
        chosen.write(motion, handle)
    return str(path)
