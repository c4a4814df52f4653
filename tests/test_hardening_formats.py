"""Issue 38, items 7-9 on motion formats: amplification, exit codes and names, from hostile bytes."""

from __future__ import annotations

import io
import json
import struct
import tracemalloc

import numpy as np
import pytest

from choreo.errors import MotionFormatError, OutputError
from choreo.formats import gltf, json_arrays, read_motion, write_motion, write_motions
from choreo.formats.bvh import parse_bvh, write_bvh
from choreo.motion import Motion
from choreo.render.html import write_html_preview
from choreo.skeleton import SMPL24


def dance(frames: int = 8, names=SMPL24.names, source: str = "/home/someone/secret/take.bvh") -> Motion:
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
    gltf.write_glb(dance(), handle)
    document, blob = glb_chunks(handle.getvalue())
    change(document)
    path = tmp_path / "forged.glb"
    path.write_bytes(glb_bytes(document, blob))
    return str(path)


def test_channels_sharing_one_accessor_convert_it_once(tmp_path, monkeypatch):
    def share(document):
        animation = document["animations"][0]
        animation["channels"] += [dict(animation["channels"][1]) for _ in range(2000)]

    path = forged_glb(tmp_path, share)
    conversions = []
    convert = gltf._accessor_array
    monkeypatch.setattr(gltf, "_accessor_array", lambda *a: conversions.append(a[2]) or convert(*a))
    assert read_motion(path).num_frames == 8
    assert len(conversions) == len(set(conversions)) <= 26  # times, root, 24 joints: each once


def test_a_glb_of_more_objects_than_any_dance_is_refused_before_it_is_decoded(tmp_path, monkeypatch):
    """Issue 48, item 13: 100,000 channels on one 8 MB accessor took pygltflib 20-23 s to decode."""
    import time

    handle = io.BytesIO()
    gltf.write_glb(dance(), handle)
    document, blob = glb_chunks(handle.getvalue())
    document["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": 8 << 20})
    document["accessors"].append({"bufferView": len(document["bufferViews"]) - 1, "componentType": 5126,
                                  "count": (8 << 20) // 16, "type": "VEC4"})
    animation = document["animations"][0]
    animation["samplers"].append({"input": animation["samplers"][0]["input"], "output": len(document["accessors"]) - 1})
    channel = {"sampler": len(animation["samplers"]) - 1, "target": {"node": 1, "path": "rotation"}}
    animation["channels"] += [channel] * 100_000
    document["buffers"][0]["byteLength"] = len(blob) + (8 << 20)
    path = tmp_path / "many.glb"
    path.write_bytes(glb_bytes(document, blob + bytes(8 << 20)))
    assert read_motion(forged_glb(tmp_path, lambda d: None)).num_frames == 8  # choreo's own: 175 objects
    monkeypatch.setattr(gltf, "_gltf", lambda: pytest.fail("decoded before the objects were counted"))
    started = time.perf_counter()
    with pytest.raises(MotionFormatError, match="more than 20,000 JSON objects"):
        read_motion(path)
    assert time.perf_counter() - started < 15


@pytest.mark.parametrize("field, value", [("count", 2**63), ("count", 2**64 + 5), ("byteOffset", 2**63),
                                          ("count", -1), ("byteOffset", 1.5)])
def test_huge_or_odd_counts_and_offsets_are_a_damaged_file(tmp_path, field, value):
    path = forged_glb(tmp_path, lambda document: document["accessors"][-1].__setitem__(field, value))
    with pytest.raises(MotionFormatError):
        read_motion(path)


def test_sparse_accessors_are_refused_in_one_line(tmp_path):
    sparse = {"count": 1, "indices": {"bufferView": 0, "componentType": 5121}, "values": {"bufferView": 0}}
    path = forged_glb(tmp_path, lambda document: [a.__setitem__("sparse", sparse) for a in document["accessors"]])
    with pytest.raises(MotionFormatError, match="sparse"):
        read_motion(path)


# -- BVH ------------------------------------------------------------------------------------------
def bvh_text(frames: int) -> str:
    handle = io.BytesIO()
    write_bvh(dance(frames), handle)
    return handle.getvalue().decode()


def peak_bytes(function, *args) -> int:
    tracemalloc.start()
    try:
        function(*args)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_reading_a_bvh_takes_memory_near_the_motions_size(tmp_path):
    """Per frame, reading 4x the frames may cost about 4x the memory (linear), and a few times
    the text plus the motion's values, not a Python object per number."""
    small, large = bvh_text(500), bvh_text(2000)
    (tmp_path / "large.bvh").write_text(large)
    parse_small, parse_large = peak_bytes(parse_bvh, small), peak_bytes(parse_bvh, large)
    assert parse_large < 5 * parse_small
    assert parse_large < 3 * len(large) + 3 * 2000 * 75 * 8
    longer = bvh_text(16000)  # long enough that the rotations' per-block work is amortised
    (tmp_path / "longer.bvh").write_text(longer)
    quaternion_bytes = 16000 * 24 * 4 * 8
    assert peak_bytes(read_motion, tmp_path / "longer.bvh") < 4 * len(longer) + 4 * quaternion_bytes + (48 << 20)


@pytest.mark.parametrize("name", ["l_hip\nMOTION\nFrames: 1", "l hip", "l_hip{", "", "l_hip\x1b[2J", "l_hip\u200b"])
def test_joint_names_that_would_break_a_file_are_refused(tmp_path, name):
    names = list(SMPL24.names)
    names[1] = name
    for extension in (".bvh", ".glb"):
        with pytest.raises(MotionFormatError, match="joint name"):
            write_motion(dance(names=names), tmp_path / f"out{extension}")
    assert not list(tmp_path.iterdir())


# -- JSON -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("text", ['{"format": "choreo-motion", "rotations": ' + "[" * 10**6 + "]" * 10**6 + "}",
                                  "[" * 10**6, '{"a": ' * 10**5 + "1" + "}" * 10**5])
def test_deeply_nested_motion_json_is_a_format_error(tmp_path, text):
    path = tmp_path / "deep.json"
    path.write_text(text)
    with pytest.raises(MotionFormatError):
        read_motion(path)


@pytest.mark.parametrize("text", ['{"a": [[1, 2], [3, 4.5e1]], "b": "x: [1, 2]"}', '{"a": [[1], [2, 3]]}',
                                  '{"a": [], "b": [[[-0.5]]]}', '{"a": [1, [2]], "c": {"a": [7]}}',
                                  '{"a": [1 2]}', '{"a": [1,,2]}', '{"a": [1e5e5]}', '{"a": [[]]}'])
def test_number_arrays_read_as_json_reads_them(text):
    try:
        expected = json.loads(text)
    except ValueError:
        with pytest.raises(ValueError):
            json_arrays.loads(text, arrays_at={"a", "b"})
        return
    got = json_arrays.loads(text, arrays_at={"a", "b"})
    assert json.loads(json.dumps(got, default=lambda a: a.tolist())) == expected


def test_a_motion_json_reads_its_arrays_without_a_python_float_per_number(tmp_path):
    write_motion(dance(2000), tmp_path / "dance.json")
    text = (tmp_path / "dance.json").read_text()
    assert peak_bytes(json_arrays.loads, text, ("rotations", "root_positions", "joint_positions")) < 3 * len(text)


def test_a_motion_json_is_written_in_blocks_of_frames_as_one_dumps_wrote_it(tmp_path, monkeypatch):
    """Issue 48, item 14: ``json.dumps`` of the whole document peaked at 20x the motion (4 GB for 20
    minutes at 120 fps). Streamed a block at a time, the bytes are the same and the writer holds
    about what the NPZ writer holds."""
    from choreo.formats import json_format
    from choreo.formats.npz import write_npz

    monkeypatch.setattr(json_format, "CHUNK_FRAMES", 64)
    for frames in (0, 1, 64, 300):
        motion = dance(frames)
        motion.metadata["where"] = tmp_path  # written as text (default=str)
        document = {"format": "choreo-motion", "version": 1, "fps": motion.fps, "joint_names": list(SMPL24.names),
                    "parents": list(SMPL24.parents), "offsets": np.round(SMPL24.offsets, 6).tolist(),
                    "root_positions": np.round(motion.root_positions, 6).tolist(),
                    "rotations": np.round(motion.axis_angle(), 7).tolist(),
                    "joint_positions": np.round(motion.joint_positions(), 5).tolist(), "metadata": motion.metadata}
        handle = io.BytesIO()
        json_format.write_json(motion, handle)
        assert handle.getvalue() == json.dumps(document, default=str).encode()
    monkeypatch.setattr(json_format, "CHUNK_FRAMES", 256)
    with open(tmp_path / "dance.json", "wb") as out, open(tmp_path / "dance.npz", "wb") as npz:
        streamed = peak_bytes(json_format.write_json, dance(6000), out)  # the whole document: 58 MB
        stored = peak_bytes(write_npz, dance(6000), npz)
    assert streamed < 2 * stored + (2 << 20)


def test_a_bvh_is_written_a_chunk_of_frames_at_a_time(tmp_path, monkeypatch):
    """Issue 48, item 14 for every writer: the BVH writer held a long dance's rotation matrices and
    its whole text at once. Written a chunk at a time, it holds about what the NPZ writer holds, and
    its curves stay continuous across the chunks' seams."""
    import choreo.formats.bvh as bvh
    from choreo.formats.npz import write_npz

    motion = dance(6000)
    with open(tmp_path / "whole.bvh", "wb") as out:
        write_bvh(motion, out)
    monkeypatch.setattr(bvh, "frame_chunks", lambda frames: [slice(0, frames)])  # as it was: all at once
    with open(tmp_path / "once.bvh", "wb") as out:
        at_once = peak_bytes(write_bvh, motion, out)
    monkeypatch.setattr(bvh, "frame_chunks", lambda frames: (slice(s, s + 256) for s in range(0, frames, 256)))
    with open(tmp_path / "dance.bvh", "wb") as out, open(tmp_path / "dance.npz", "wb") as npz:
        streamed = peak_bytes(write_bvh, motion, out)
        stored = peak_bytes(write_npz, motion, npz)
    assert (tmp_path / "dance.bvh").read_bytes() == (tmp_path / "whole.bvh").read_bytes()
    assert streamed < stored and streamed < at_once / 3  # measured: 5.5, 21 and 24 MB


# -- where outputs come from, and the preview ------------------------------------------------------
def test_outputs_carry_the_inputs_file_name_not_its_path(tmp_path):
    folder = tmp_path / "private user"
    folder.mkdir()
    write_motion(dance(), folder / "take.bvh")
    motion = read_motion(folder / "take.bvh")
    assert motion.metadata["source"] == "take.bvh"
    for extension in (".json", ".glb"):
        write_motion(motion, tmp_path / f"out{extension}")
        assert b"private user" not in (tmp_path / f"out{extension}").read_bytes()
    assert read_motion(tmp_path / "out.json").metadata["source"] == "take.bvh"


def test_preview_placeholders_in_the_source_stay_text_and_names_stay_inside_their_script():
    motion = dance(source="__AUDIO__ __DANCE_JSON__ __THREE_B64__ <b>")
    names = list(SMPL24.names)
    names[5] = "<!--<script>"
    motion = Motion(motion.root_positions, motion.rotations, fps=30, metadata=motion.metadata,
                    skeleton=type(SMPL24)(tuple(names), SMPL24.parents, SMPL24.offsets))
    handle = io.BytesIO()
    write_html_preview(motion, None, None, handle)
    page = handle.getvalue().decode()
    title = page[page.index("<title>"):page.index("</title>")]
    assert title == "<title>__AUDIO__ __DANCE_JSON__ __THREE_B64__ &lt;b&gt;"
    script = page[page.index('<script id="dance"'):]
    script = script[script.index(">") + 1:script.index("</script>")]
    assert "<" not in script and json.loads(script)["names"][5] == "<!--<script>"


def test_a_failing_companion_output_leaves_no_motion(tmp_path):
    def fail(temporary):
        raise OutputError("the preview cannot be rendered")

    with pytest.raises(OutputError):
        write_motions(dance(), [str(tmp_path / "a.bvh"), str(tmp_path / "a.json")],
                      companions={str(tmp_path / "a.mp4"): fail})
    assert list(tmp_path.iterdir()) == []
    written = write_motions(dance(), [str(tmp_path / "a.bvh")],
                            companions={str(tmp_path / "a.mp4"): lambda temporary: temporary.write_bytes(b"v")})
    assert written == [str(tmp_path / "a.bvh")] and (tmp_path / "a.mp4").read_bytes() == b"v"
