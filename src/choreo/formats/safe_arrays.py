"""NumPy files read with their sizes checked first: a few hundred bytes must not ask for terabytes.

``np.load`` trusts an .npy header's shape and decompresses an .npz member in full before anything
can look at it: a 646-byte .npz declaring 10^12 rows, or a 3 MB zip bomb, would take the machine
down. Here every array's declared size is read from its header (and, in an .npz, the member's
uncompressed size from the zip directory) and checked against the bytes actually present and a
ceiling before a byte of data is allocated.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from ..errors import MotionFormatError

MAX_ARRAY_BYTES = 1 << 30  # 1 GiB per array: hours of motion in float64, far below a bomb's ask


def _declared_bytes(handle, where: str) -> int:
    """Bytes the .npy stream's header says its data takes (the stream is left after the header)."""
    try:
        version = np.lib.format.read_magic(handle)
        shape, _, dtype = (np.lib.format.read_array_header_1_0(handle) if version == (1, 0)
                           else np.lib.format.read_array_header_2_0(handle))
    except (ValueError, OSError, EOFError) as error:
        raise MotionFormatError(f"{where}: not a readable NumPy array ({error})") from None
    if dtype.hasobject:
        raise MotionFormatError(f"{where}: holds Python objects, which choreo does not load")
    if any(d < 0 for d in shape):
        raise MotionFormatError(f"{where}: a negative dimension in its header")
    return int(np.prod(shape, dtype=object)) * dtype.itemsize


def _check(declared: int, present: int, where: str, limit: int) -> None:
    if declared > limit:
        raise MotionFormatError(f"{where}: declares {declared:,} bytes of data (more than the {limit:,} choreo reads)")
    if declared > present:
        raise MotionFormatError(f"{where}: declares {declared:,} bytes of data but holds {present:,} (damaged or forged)")


def load_npy(path: str | Path, limit: int = MAX_ARRAY_BYTES) -> np.ndarray:
    """One .npy array, its header checked against the file's size and ``limit`` before loading."""
    path = Path(path)
    with open(path, "rb") as handle:
        declared = _declared_bytes(handle, str(path))
        _check(declared, path.stat().st_size - handle.tell(), str(path), limit)
    return np.load(path, allow_pickle=False)


def load_npz(path: str | Path, limit: int = MAX_ARRAY_BYTES) -> dict[str, np.ndarray]:
    """Every array of an .npz, each member's sizes checked before it is decompressed."""
    try:
        archive = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, EOFError) as error:
        raise MotionFormatError(f"{path}: not a readable NPZ file ({type(error).__name__})") from None
    arrays = {}
    with archive:
        for info in archive.infolist():
            where = f"{path}: {info.filename}"
            if info.file_size > limit + 4096:  # the zip directory's own word on the uncompressed size
                raise MotionFormatError(f"{where}: {info.file_size:,} bytes uncompressed (more than choreo reads)")
            try:
                with archive.open(info) as member:
                    declared = _declared_bytes(member, where)
                    _check(declared, info.file_size - member.tell(), where, limit)
                with archive.open(info) as member:  # from the start again: read_array wants the header too
                    arrays[info.filename.removesuffix(".npy")] = np.lib.format.read_array(member, allow_pickle=False)
            except (zipfile.BadZipFile, OSError, EOFError, ValueError) as error:
                raise MotionFormatError(f"{where}: not a readable array ({type(error).__name__})") from None
    return arrays
