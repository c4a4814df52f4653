"""NumPy files read with their sizes checked first: a few hundred bytes must not ask for terabytes.

``np.load`` trusts an .npy header's shape and decompresses an .npz member in full before anything
can look at it: a 646-byte .npz declaring 10^12 rows, or a 3 MB zip bomb, would take the machine
down. Here every array's declared size is read from its header (and, in an .npz, the member's
uncompressed size from the zip directory) and checked against the bytes actually present and a
ceiling before a byte of data is allocated.
"""

from __future__ import annotations

import tokenize
import zipfile
from pathlib import Path

import numpy as np

from ..errors import MotionFormatError

MAX_ARRAY_BYTES = 1 << 30  # 1 GiB per array: hours of motion in float64, far below a bomb's ask
HEADER_LENGTH_BYTES = {(1, 0): 2, (2, 0): 4, (3, 0): 4}  # the .npy versions, and their length fields
MAX_HEADER_BYTES = 1 << 16  # numpy itself refuses headers over 10,000 characters
# zipfile raises NotImplementedError for an unknown compression method, ValueError for bad names
ZIP_ERRORS = (zipfile.BadZipFile, OSError, EOFError, ValueError, NotImplementedError)
# numpy parses the header's dict as Python source: a damaged one raises tokenizer and syntax errors
HEADER_ERRORS = (ValueError, OSError, EOFError, SyntaxError, tokenize.TokenError, RecursionError)


def printable(name: str) -> str:
    """A member's name fit for a one-line message: a zip may name a member with newlines in it."""
    return name if name.isprintable() else ascii(name)


def _declared_bytes(handle, where: str) -> int:
    """Bytes the .npy stream's header says its data takes (the stream is left after the header)."""
    try:
        version = np.lib.format.read_magic(handle)
        _check_header_length(handle, version, where)
        shape, _, dtype = (np.lib.format.read_array_header_1_0(handle) if version == (1, 0)
                           else np.lib.format.read_array_header_2_0(handle))
    except HEADER_ERRORS as error:
        raise MotionFormatError(f"{where}: not a readable NumPy array ({type(error).__name__})") from None
    if dtype.hasobject:
        raise MotionFormatError(f"{where}: holds Python objects, which choreo does not load")
    if any(d < 0 for d in shape):
        raise MotionFormatError(f"{where}: a negative dimension in its header")
    count = int(np.prod(shape, dtype=object))
    if dtype.itemsize == 0 and count > 0:  # zero bytes declared, yet any conversion would allocate them all
        raise MotionFormatError(f"{where}: items of zero bytes ({dtype.str})")
    return count * dtype.itemsize


def _check_header_length(handle, version: tuple[int, int], where: str) -> None:
    """Refuse an unknown version or a header longer than numpy reads, before numpy asks the file
    for that many bytes: a damaged version byte turns the length field into gigabytes."""
    if version not in HEADER_LENGTH_BYTES:
        raise MotionFormatError(f"{where}: unknown .npy format version {version[0]}.{version[1]}")
    start = handle.tell()
    length = int.from_bytes(handle.read(HEADER_LENGTH_BYTES[version]), "little")
    if length > MAX_HEADER_BYTES:
        raise MotionFormatError(f"{where}: a {length:,}-byte .npy header (damaged or forged)")
    handle.seek(start)


def _check_text(array: np.ndarray, where: str) -> np.ndarray:
    """Refuse text arrays holding code points beyond Unicode: numpy loads them unchecked and makes
    Python strings of them that break later (a SystemError in json.loads or str.rpartition)."""
    if array.dtype.kind == "U" and array.size:
        codes = np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("=")).view(np.uint32)
        if int(codes.max()) > 0x10FFFF:
            raise MotionFormatError(f"{where}: text with characters beyond Unicode (damaged file)")
    return array


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
    return _check_text(np.load(path, allow_pickle=False), str(path))


def load_npz(path: str | Path, limit: int = MAX_ARRAY_BYTES) -> dict[str, np.ndarray]:
    """Every array of an .npz, each member's sizes checked before it is decompressed."""
    try:
        archive = zipfile.ZipFile(path)
    except ZIP_ERRORS as error:
        raise MotionFormatError(f"{path}: not a readable NPZ file ({type(error).__name__})") from None
    arrays = {}
    with archive:
        for info in archive.infolist():
            where = f"{path}: {printable(info.filename)}"
            if info.file_size > limit + 4096:  # the zip directory's own word on the uncompressed size
                raise MotionFormatError(f"{where}: {info.file_size:,} bytes uncompressed (more than choreo reads)")
            try:
                with archive.open(info) as member:
                    declared = _declared_bytes(member, where)
                    _check(declared, info.file_size - member.tell(), where, limit)
                with archive.open(info) as member:  # from the start again: read_array wants the header too
                    array = np.lib.format.read_array(member, allow_pickle=False)
                arrays[info.filename.removesuffix(".npy")] = _check_text(array, where)
            except ZIP_ERRORS as error:
                raise MotionFormatError(f"{where}: not a readable array ({type(error).__name__})") from None
    return arrays
