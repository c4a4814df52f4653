"""Choose a reader or writer by file extension or format name (whisper's ``get_writer`` idea)."""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from ..errors import InputError, MotionFormatError, OutputError, ParameterError
from ..fileio import STDOUT, atomic_output, atomic_path
from ..motion import Motion
from .aistpp import read_aistpp_pkl, write_aistpp_pkl
from .bvh import read_bvh, write_bvh
from .fbx import NO_BLENDER, blender_command, write_fbx_stream
from .gltf import read_glb, write_glb
from .json_format import read_json, write_json
from .npy import read_npy_joint_positions, write_npy
from .npz import read_npz, read_npz_joint_positions, write_npz
from .rigs import RIGS, get_rig, read_bvh_rig, write_bvh_rig


@dataclass(frozen=True)
class MotionFormat:
    name: str
    extension: str
    description: str
    read: Callable[[Path], Motion] | None  # None: positions only (no rotations to read)
    write: Callable[[Motion, object], None]


def read_bvh_any_rig(path: Path) -> Motion:
    """A BVH on SMPL-24, or on a rig choreo retargets to (Mixamo names), read as SMPL-24."""
    try:
        return read_bvh(path)
    except MotionFormatError as smpl_error:
        for rig in RIGS.values():
            try:
                return read_bvh_rig(path, rig)
            except MotionFormatError:
                continue
        raise smpl_error


FORMATS = {
    f.name: f
    for f in (
        MotionFormat("bvh", ".bvh", "BVH, SMPL-24 skeleton (or a Mixamo rig's), metres, Y up", read_bvh_any_rig,
                     write_bvh),
        MotionFormat("npz", ".npz", "NPZ with AIST++ keys (smpl_poses, smpl_trans, ...)", read_npz, write_npz),
        MotionFormat("pkl", ".pkl", "AIST++ motion pickle (60 fps unless choreo wrote another)", read_aistpp_pkl, write_aistpp_pkl),
        MotionFormat("json", ".json", "choreo motion JSON", read_json, write_json),
        MotionFormat("npy", ".npy", "joint positions (T, 24, 3), metres, Y up", None, write_npy),
        MotionFormat("glb", ".glb", "glTF 2.0 binary: SMPL-24 skin, a skinned body, the dance as its animation",
                     read_glb, write_glb),
        MotionFormat("fbx", ".fbx", "FBX through Blender: armature and baked animation, Y up, -Z forward (Unity, Unreal)",
                     None, write_fbx_stream),
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


STDIN = "-"
MAX_PIPED_BYTES = 2 * 2**30  # a motion piped in is held in memory once; more than this is not a dance
MAGIC = ((b"PK\x03\x04", "npz"), (b"\x93NUMPY", "npy"), (b"glTF", "glb"), (b"\x80", "pkl"),
         (b"HIERARCHY", "bvh"), (b"{", "json"))  # fmt: skip


@contextlib.contextmanager
def piped_motion_file(format: str | None = None, stream=None) -> Iterator[Path]:
    """Motion bytes from stdin (``-``), saved to a temporary file named for their format so every
    reader can take them as it takes a file; removed on exit. The format comes from ``format`` or
    from the bytes' own signature (zip, .npy, glTF, pickle, BVH, JSON)."""
    stream = sys.stdin.buffer if stream is None else stream
    data = stream.read(MAX_PIPED_BYTES + 1)
    if len(data) > MAX_PIPED_BYTES:
        raise InputError(f"the motion on stdin is larger than {MAX_PIPED_BYTES // 2**30} GiB")
    if not data.strip():
        raise MotionFormatError("no motion on stdin (nothing was piped in)")
    if format is not None:
        chosen = _format_for(STDIN, format, InputError)
    else:
        head = data.lstrip()[:16]
        name = next((name for magic, name in MAGIC if head.startswith(magic)), None)
        if name is None:
            raise MotionFormatError("cannot tell the format of the motion on stdin "
                                    f"(known: {', '.join(FORMATS)}; pipe one of those)")
        chosen = FORMATS[name]
    with tempfile.TemporaryDirectory(prefix="choreo-stdin-") as folder:
        path = Path(folder) / f"stdin{chosen.extension}"
        path.write_bytes(data)
        yield path


def read_motion(path: str | os.PathLike, format: str | None = None) -> Motion:
    """Read a motion file into a Motion (metres, Y up, the file's own fps); ``-`` reads stdin."""
    if str(path) == STDIN:
        with piped_motion_file(format) as piped:
            return read_motion(piped)
    path = Path(path)
    chosen = _format_for(path, format, InputError)
    _check_readable(path)
    _check_reader(path, chosen)
    return chosen.read(path)


def _check_reader(path: Path, chosen: MotionFormat) -> None:
    if chosen.read is None and chosen.name == "npy":
        raise InputError(f"{path}: a {chosen.extension} file holds joint positions only, not a rotation-based motion")
    if chosen.read is None:
        raise InputError(f"{path}: choreo writes {chosen.extension} files but does not read them")


def read_joint_positions(path: str | os.PathLike, format: str | None = None) -> tuple[np.ndarray, float | None]:
    """(T, 24, 3) joint positions from any supported file, and its fps (None when unknown: .npy);
    ``-`` reads stdin."""
    if str(path) == STDIN:
        with piped_motion_file(format) as piped:
            return read_joint_positions(piped)
    path = Path(path)
    chosen = _format_for(path, format, InputError)
    _check_readable(path)
    if chosen.name == "npy":
        return read_npy_joint_positions(path), None
    _check_reader(path, chosen)
    motion = chosen.read(path)
    if chosen.name == "npz":
        stored = read_npz_joint_positions(path)
        if stored is not None and stored.shape == (motion.num_frames, 24, 3):
            return stored, motion.fps
    return motion.joint_positions(), motion.fps


def check_output_format(path: str | os.PathLike, format: str | None = None, rig: str | None = None,
                        root_motion: bool = False) -> None:
    """Refuse (OutputError, exit 3) an output whose format is unknown, or that cannot carry ``rig``
    or a root bone (ParameterError, exit 2), before any work is done."""
    if str(path) == STDOUT and format is None:
        raise OutputError("writing to stdout (-) needs an explicit --format")
    chosen = _format_for(path, format, OutputError)
    _writer(chosen, rig, root_motion)
    if chosen.name == "fbx" and blender_command() is None:
        raise OutputError(NO_BLENDER)


RIG_WRITERS = {"bvh": write_bvh_rig, "fbx": write_fbx_stream}  # the formats that can carry another rig
ROOT_MOTION_FORMATS = ("bvh", "glb", "fbx")  # the formats a root bone can be added to (the others hold SMPL-24)


def _writer(chosen: MotionFormat, rig: str | None, root_motion: bool = False) -> Callable[[Motion, object], None]:
    """The format's writer, on SMPL-24 or retargeted onto ``rig`` (mixamo: names, tree, T-pose),
    under a root bone with ``root_motion``."""
    target = get_rig(rig)  # unknown names: a one-line ParameterError
    if root_motion and chosen.name not in ROOT_MOTION_FORMATS:
        raise ParameterError(f"--root-motion applies to {', '.join('.' + n for n in ROOT_MOTION_FORMATS)} outputs, "
                             f"not {chosen.extension} (use --in-place, or one of those)")
    if target is not None and chosen.name not in RIG_WRITERS:
        raise ParameterError(f"--rig {rig} applies to {' and '.join('.' + n for n in RIG_WRITERS)} outputs, "
                             f"not {chosen.extension}")
    write = chosen.write if target is None else functools.partial(RIG_WRITERS[chosen.name], rig=target)
    return functools.partial(write, root_motion=True) if root_motion else write


def write_motions(motion: Motion, paths: list[str], format: str | None = None, rig: str | None = None,
                  companions: dict[str, Callable[[Path], None]] | None = None, root_motion: bool = False) -> list[str]:
    """Write ``motion`` to every path, all or none: each file is written in full to a temporary
    beside it, and only when every one is written are they moved into place. ``companions`` maps
    more outputs (a preview video) to a function that writes one to the temporary path it is
    given: they join the all or none. ``root_motion``: under a floor-level root bone."""
    for path in paths:
        check_output_format(path, format, rig, root_motion)
    with contextlib.ExitStack() as stack:
        for path in paths:
            handle = stack.enter_context(atomic_output(path))
            _writer(_format_for(path, format, OutputError), rig, root_motion)(motion, handle)
        for path, write in (companions or {}).items():
            write(stack.enter_context(atomic_path(path)))
    return [str(p) for p in paths]


METADATA_FORMATS = ("npz", "json", "glb")  # the formats that carry a motion's metadata (loop, genre, seed ...)
FILE_KEYS = ("source", "rig")  # metadata every reader sets from the file itself: its name, its bones


def dropped_metadata(motion: Motion, path: str | os.PathLike, format: str | None = None) -> list[str]:
    """The keys of ``motion``'s metadata that writing it to ``path`` drops: all but the file's own
    name and rig where the format holds none (BVH, FBX, pkl, npy), none elsewhere."""
    if _format_for(path, format, OutputError).name in METADATA_FORMATS:
        return []
    return [str(key) for key in motion.metadata if key not in FILE_KEYS]


def write_motion(motion: Motion, path: str | os.PathLike, format: str | None = None, rig: str | None = None,
                 root_motion: bool = False) -> str:
    """Write ``motion`` atomically (or to stdout for "-"), optionally on another ``rig`` or under a
    root bone; returns the path."""
    check_output_format(path, format, rig, root_motion)
    write = _writer(_format_for(path, format, OutputError), rig, root_motion)
    with atomic_output(path) as handle:
        write(motion, handle)
    return str(path)
