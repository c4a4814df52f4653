"""A glb taken apart and put back together by hand (GLB header, JSON chunk, BIN chunk), and a still dance to write."""

import json
import struct

import numpy as np

from choreo.motion import Motion  # noqa: E402
from choreo.skeleton import SMPL24  # noqa: E402


def split_glb(data: bytes) -> tuple[dict, bytes]:
    """(JSON document, BIN chunk) of a GLB, checking the header and chunk framing on the way."""
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert (magic, version, length) == (b"glTF", 2, len(data))
    json_length, json_type = struct.unpack_from("<I4s", data, 12)
    assert json_type == b"JSON" and json_length % 4 == 0
    document = json.loads(data[20:20 + json_length].decode("utf-8"))
    at = 20 + json_length
    if at == len(data):
        return document, b""
    bin_length, bin_type = struct.unpack_from("<I4s", data, at)
    assert bin_type == b"BIN\0" and bin_length % 4 == 0 and at + 8 + bin_length == len(data)
    return document, data[at + 8:at + 8 + bin_length]


def join_glb(document: dict, blob: bytes) -> bytes:
    """A GLB from a JSON document and a binary chunk (this file's own packing, not pygltflib's)."""
    text = json.dumps(document).encode("utf-8")
    text += b" " * (-len(text) % 4)
    blob = bytes(blob) + b"\0" * (-len(blob) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def still_glb(frames: int, fps: float = 30.0, skeleton=None):
    rotations = np.zeros((frames, 24, 4))
    rotations[..., 0] = 1.0
    return Motion(np.tile([0.1, 0.9, -0.2], (frames, 1)), rotations, fps=fps, skeleton=skeleton or SMPL24)
