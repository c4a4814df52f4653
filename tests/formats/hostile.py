"""Hostile inputs for the format tests: a dance with chosen joint names and source, forged glb files, a peak-memory probe."""

from __future__ import annotations

import io
import json
import struct
import tracemalloc

import numpy as np

from choreo.formats import gltf
from choreo.motion import Motion
from choreo.skeleton import SMPL24


def hostile_dance(frames: int = 8, names=SMPL24.names, source: str = "/home/someone/secret/take.bvh") -> Motion:
    rng = np.random.default_rng(0)
    rotations = np.tile([1.0, 0.0, 0.0, 0.0], (frames, 24, 1)) + rng.normal(scale=0.1, size=(frames, 24, 4))
    skeleton = SMPL24 if names is SMPL24.names else type(SMPL24)(tuple(names), SMPL24.parents, SMPL24.offsets)
    return Motion(rng.normal(size=(frames, 3)), rotations, fps=30, skeleton=skeleton, metadata={"source": source})


# -- glb ------------------------------------------------------------------------------------------
def glb_chunks(data: bytes) -> tuple[dict, bytes]:
    length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + length])
    return document, data[20 + length + 8:]


def glb_bytes(document: dict, blob: bytes) -> bytes:
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def forged_glb(tmp_path, change) -> str:
    handle = io.BytesIO()
    gltf.write_glb(hostile_dance(), handle)
    document, blob = glb_chunks(handle.getvalue())
    change(document)
    path = tmp_path / "forged.glb"
    path.write_bytes(glb_bytes(document, blob))
    return str(path)


def peak_bytes(function, *args) -> int:
    tracemalloc.start()
    try:
        function(*args)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
