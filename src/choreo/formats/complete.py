"""Whether an output file on disk is whole: a cheap look at its structure, never a full read.

``--skip-existing`` leaves a song alone when its outputs are there. choreo writes atomically, but a
file can still be cut short by a copy that was interrupted, another tool, or a full disk elsewhere:
a zero-byte or truncated output was trusted and its song skipped for ever. Each check reads the
few bytes that only a finished file has (a zip's directory, a BVH's frame count against its rows,
a glb's declared length, a closing footer); a file that fails one is danced again.
"""

from __future__ import annotations

import json
import struct
import zipfile
from pathlib import Path

import numpy as np

from .safe_arrays import HEADER_ERRORS, ZIP_ERRORS

BLOCK = 1 << 20  # bytes read at a time where a file is scanned to its end
MAX_HEAD = 1 << 20  # a BVH's hierarchy (a Mixamo rig's is 10 kB) or a JSON's metadata fits in this
MAX_PARTS = 64  # top-level glb chunks or MP4 boxes: choreo's have 2 and about 5
FBX_HEAD = b"Kaydara FBX Binary  \x00"
FBX_TAIL = b"\xf8\x5a\x8c\x6a\xde\xf5\xd9\x7e\xec\xe9\x0c\xe3\x75\x8f\x29\x0b"  # every binary FBX ends so


def _bvh(path: Path) -> bool:
    """The MOTION section is there and holds exactly as many rows as its ``Frames:`` line says."""
    with open(path, "rb") as handle:
        head = handle.read(MAX_HEAD)
        start = head.find(b"\nMOTION\n")
        lines = head[start + 8:].split(b"\n", 2) if start >= 0 else []
        if len(lines) < 3 or not lines[0].startswith(b"Frames:") or not lines[1].startswith(b"Frame Time:"):
            return False
        try:
            frames = int(lines[0][7:])
        except ValueError:
            return False
        handle.seek(start + 8 + len(lines[0]) + len(lines[1]) + 2)
        rows, last = 0, b"\n"
        while block := handle.read(BLOCK):
            rows, last = rows + block.count(b"\n"), block[-1:]
    return rows == frames and last == b"\n"


def _npz(path: Path) -> bool:
    """The zip's directory is readable and every member lies inside the file."""
    size = path.stat().st_size
    with zipfile.ZipFile(path) as archive:
        members = archive.infolist()
    return bool(members) and all(m.header_offset + m.compress_size < size for m in members)


def _npy(path: Path) -> bool:
    """The header's shape and type account for exactly the bytes after it."""
    with open(path, "rb") as handle:
        read_header = {(1, 0): np.lib.format.read_array_header_1_0,
                       (2, 0): np.lib.format.read_array_header_2_0}.get(np.lib.format.read_magic(handle))
        if read_header is None:
            return False
        shape, _, dtype = read_header(handle)
        return handle.tell() + int(np.prod(shape, dtype=object)) * dtype.itemsize == path.stat().st_size


def _glb(path: Path) -> bool:
    """The header's length is the file's, and its chunks tile the rest exactly."""
    size = path.stat().st_size
    with open(path, "rb") as handle:
        magic, version, length = struct.unpack("<4sII", handle.read(12))
        offset = 12
        for _ in range(MAX_PARTS):
            if offset >= size:
                break
            handle.seek(offset)
            offset += 8 + struct.unpack("<I", handle.read(8)[:4])[0]
    return magic == b"glTF" and version == 2 and length == size == offset


def _pkl(path: Path) -> bool:
    """A pickle (protocol 2 or later) ends with its STOP opcode."""
    return _ends(path, b"\x80", b".")


def _json(path: Path) -> bool:
    """A choreo motion JSON ends with its metadata object, whole, and the document's brace."""
    with open(path, "rb") as handle:
        if not handle.read(64).startswith(b'{"format": "choreo-motion"'):
            return False
        handle.seek(max(0, path.stat().st_size - MAX_HEAD))
        tail = handle.read()
    key = tail.rfind(b', "metadata": ')
    if key < 0 or not tail.endswith(b"}"):
        return False
    json.loads(tail[key + 14:-1])
    return True


def _fbx(path: Path) -> bool:
    return _ends(path, FBX_HEAD, FBX_TAIL)


def _mp4(path: Path) -> bool:
    """The ISO boxes tile the file exactly, and the index (``moov``) is one of them."""
    size, offset, kinds = path.stat().st_size, 0, set()
    with open(path, "rb") as handle:
        for _ in range(MAX_PARTS):
            if offset >= size:
                break
            handle.seek(offset)
            length, kind = struct.unpack(">I4s", handle.read(8))
            if length == 1:
                length = struct.unpack(">Q", handle.read(8))[0]
            elif length == 0:
                length = size - offset
            if length < 8:
                return False
            offset, kinds = offset + length, kinds | {kind}
    return offset == size and b"moov" in kinds


def _ends(path: Path, head: bytes, tail: bytes) -> bool:
    size = path.stat().st_size
    with open(path, "rb") as handle:
        start = handle.read(len(head))
        handle.seek(max(0, size - len(tail)))
        return start == head and size >= len(head) + len(tail) and handle.read() == tail


CHECKS = {".bvh": _bvh, ".npz": _npz, ".npy": _npy, ".glb": _glb, ".pkl": _pkl, ".json": _json, ".fbx": _fbx,
          ".mp4": _mp4}


def looks_complete(path: str | Path) -> bool:
    """Whether ``path`` is a regular, non-empty file whose structure is whole for its extension
    (other extensions: non-empty is all that is asked)."""
    path = Path(path)
    try:
        if not path.is_file() or path.stat().st_size == 0:
            return False
        check = CHECKS.get(path.suffix.lower())
        return check is None or check(path)
    except (struct.error, *ZIP_ERRORS, *HEADER_ERRORS, TypeError, OverflowError):
        return False
