"""Batches split over machines (--shard K/N) and re-run after a failure (--skip-existing)."""

import json
import random
from pathlib import Path

import numpy as np
import pytest
from tests.helpers import assert_one_line_error, run_cli

from choreo.cli.batch import Shard, already_written
from choreo.errors import ParameterError
from choreo.formats import write_motion, write_motions
from choreo.formats.complete import looks_complete
from choreo.motion import Motion
from choreo.skeleton import SMPL24


def motion(frames: int = 5) -> Motion:
    rotations = np.random.default_rng(frames).normal(scale=0.3, size=(frames, 24, 3))
    return Motion.from_axis_angle(np.zeros((frames, 3)), rotations, fps=30.0, skeleton=SMPL24)


def songs(count: int) -> list[Path]:
    return [Path(f"music/{chr(97 + i % 26)}{i:03d}.mp3") for i in range(count)]


@pytest.mark.parametrize("count,shards", [(1, 1), (7, 3), (20, 4), (3, 8)])
def test_shards_cover_every_song_once_in_any_argument_order(count, shards):
    listed = songs(count)
    shuffled = random.Random(count).sample(listed, count)
    parts = [Shard(k, shards).select(listed) for k in range(1, shards + 1)]
    assert sorted(p for part in parts for p in part) == sorted(listed)  # each song exactly once
    assert [Shard(k, shards).select(shuffled) for k in range(1, shards + 1)] == parts  # the order given does not matter
    assert max(map(len, parts)) - min(map(len, parts)) <= 1  # balanced


@pytest.mark.parametrize("text", ["0/4", "5/4", "1/0", "a/b", "3", "1/2/3", "-1/2", "",
                                  "1/" + "9" * 5000, "\uff11/\uff12"])  # issue 48: int() overflowed; \d read fullwidth
def test_bad_shards_are_refused_by_name(text):
    with pytest.raises(ParameterError, match="--shard") as refused:
        Shard.parse(text)
    assert len(str(refused.value)) < 100  # the text is cut, not echoed whole


def test_shard_parse_accepts_spaces():
    assert Shard.parse(" 2 / 8 ") == Shard(2, 8)


def test_already_written_needs_every_file(tmp_path):
    write_motion(motion(), tmp_path / "a.bvh")
    assert already_written([str(tmp_path / "a.bvh")])
    assert not already_written([str(tmp_path / "a.bvh"), str(tmp_path / "a.npz")])
    assert not already_written(["-"]) and not already_written([])
    (tmp_path / "d.bvh").mkdir()
    assert not already_written([str(tmp_path / "d.bvh")])  # a folder is not a written dance


@pytest.fixture
def fake_dance(monkeypatch):
    """dance_one writing its outputs at once, recording the songs it was given."""
    from choreo.cli import generate_command

    danced = []

    def dance_one(request, song, outputs, constraints=None):
        danced.append(song.name)
        write_motions(motion(), outputs.paths)
        return {"song": str(song), "ok": True, "outputs": outputs.paths}

    monkeypatch.setattr(generate_command, "dance_one", dance_one)
    return danced


def test_shards_of_a_batch_write_every_song_once(tmp_path, capsys, fake_dance):
    files = [tmp_path / f"song{i}.wav" for i in range(5)]
    summaries = []
    for k in (1, 2):
        code, out, _ = run_cli(capsys, "generate", *files[::-1] if k == 2 else files, "--out-dir", tmp_path,
                               "--shard", f"{k}/2", "--json", "-f", "bvh,npz")
        assert code == 0
        summaries.append(json.loads(out))
    assert sorted(fake_dance) == sorted(f.name for f in files)
    merged = [s["song"] for summary in summaries for s in summary["songs"]]
    assert sorted(merged) == sorted(map(str, files))
    assert all((tmp_path / f"song{i}.{ext}").exists() for i in range(5) for ext in ("bvh", "npz"))


def test_skip_existing_dances_only_what_is_missing(tmp_path, capsys, fake_dance):
    files = [tmp_path / f"song{i}.wav" for i in range(3)]
    write_motions(motion(7), [str(tmp_path / "song0.bvh"), str(tmp_path / "song0.npz"), str(tmp_path / "song1.bvh")])
    done = (tmp_path / "song0.bvh").read_bytes()  # song1's npz is missing: danced again
    code, out, _ = run_cli(capsys, "generate", *files, "--out-dir", tmp_path, "--skip-existing", "--json", "-f", "bvh,npz")
    assert code == 0
    assert fake_dance == ["song1.wav", "song2.wav"]
    summary = json.loads(out)
    assert [s.get("skipped", False) for s in summary["songs"]] == [True, False, False]
    assert (tmp_path / "song0.bvh").read_bytes() == done


def test_shard_and_skip_existing_need_a_batch(tmp_path, capsys):
    for flags in (["--shard", "1/2"], ["--skip-existing"]):
        code, _, err = run_cli(capsys, "generate", tmp_path / "a.wav", "-o", tmp_path / "a.bvh", *flags)
        assert code == 2 and "--out-dir" in err


@pytest.mark.parametrize("formats", [",", " , ", "", "xyz", "bvh,xyz", "npz,,.mp3"])
@pytest.mark.parametrize("flags", [[], ["--skip-existing", "--preview"]])
def test_format_lists_are_checked_before_any_song(tmp_path, capsys, fake_dance, formats, flags):
    """Issue 48, item 6: ``,`` danced every song, wrote nothing and said ok (with --skip-existing
    --preview: exit 70); an unknown format failed song by song (exit 1). Now up front: exit 2 for a
    list of none, 3 for an unknown format (as an unknown -o extension)."""
    songs = [tmp_path / "a.wav", tmp_path / "b.wav"]
    code, out, err = run_cli(capsys, "generate", *songs, "--out-dir", tmp_path, "-f", formats, "--json", *flags)
    assert_one_line_error(code, err, 3 if "xyz" in formats or "mp3" in formats else 2)
    assert "--format" in err and fake_dance == [] and out == "" and sorted(tmp_path.iterdir()) == []


def test_a_format_named_twice_is_written_once(tmp_path, capsys, fake_dance):
    code, out, _ = run_cli(capsys, "generate", tmp_path / "a.wav", "--out-dir", tmp_path, "-f", "bvh,BVH,.bvh, npz",
                           "--json")
    assert code == 0
    assert json.loads(out)["songs"][0]["outputs"] == [str(tmp_path / "a.bvh"), str(tmp_path / "a.npz")]


def mp4_box(kind: bytes, body: bytes = b"") -> bytes:
    return (8 + len(body)).to_bytes(4, "big") + kind + body


@pytest.mark.parametrize("ext", ["bvh", "npz", "npy", "glb", "json", "pkl"])
def test_outputs_cut_short_are_not_whole(tmp_path, ext):
    """Issue 48, item 7: --skip-existing trusted zero-byte and truncated outputs, so their songs
    were skipped for ever."""
    path = tmp_path / f"dance.{ext}"
    write_motion(motion(40), path)
    whole = path.read_bytes()
    assert looks_complete(path)
    cut = whole[:whole.rindex(b"\n", 0, len(whole) - 1) + 1] if ext == "bvh" else whole[:-1]  # a BVH cut at a row
    for damaged in (b"", whole[:len(whole) // 2], cut):
        path.write_bytes(damaged)
        assert not looks_complete(path), len(damaged)


def test_videos_and_fbx_files_cut_short_are_not_whole(tmp_path):
    from choreo.formats.complete import FBX_HEAD, FBX_TAIL

    video = mp4_box(b"ftyp", b"isom") + mp4_box(b"mdat", bytes(100)) + mp4_box(b"moov", mp4_box(b"mvhd", bytes(20)))
    fbx = FBX_HEAD + bytes(300) + FBX_TAIL
    for name, whole in (("a.mp4", video), ("a.fbx", fbx)):
        path = tmp_path / name
        path.write_bytes(whole)
        assert looks_complete(path)
        for damaged in (b"", whole[:-1], whole[:40]):
            path.write_bytes(damaged)
            assert not looks_complete(path)
    (tmp_path / "b.mp4").write_bytes(mp4_box(b"ftyp", b"isom") + mp4_box(b"mdat", bytes(10)))  # no index
    assert not looks_complete(tmp_path / "b.mp4")


def test_skip_existing_dances_again_over_an_empty_or_truncated_output(tmp_path, capsys, fake_dance):
    songs = [tmp_path / f"song{i}.wav" for i in range(3)]
    for i in range(3):
        write_motion(motion(), tmp_path / f"song{i}.npz")
    (tmp_path / "song0.npz").write_bytes(b"")
    (tmp_path / "song1.npz").write_bytes((tmp_path / "song1.npz").read_bytes()[:-30])
    code, _, _ = run_cli(capsys, "generate", *songs, "--out-dir", tmp_path, "--skip-existing", "-f", "npz")
    assert code == 0 and fake_dance == ["song0.wav", "song1.wav"]
    assert all(looks_complete(tmp_path / f"song{i}.npz") for i in range(3))


def test_without_an_output_each_song_is_danced_into_the_current_folder(tmp_path, capsys, fake_dance, monkeypatch):
    """Issue 47: `choreo generate song.mp3` writes song.bvh here, as whisper and most audio CLIs do."""
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, "generate", tmp_path / "a.wav", "--json")
    assert code == 0, err
    assert json.loads(out)["songs"][0]["outputs"] == ["a.bvh"] and (tmp_path / "a.bvh").stat().st_size > 0
    code, _, err = run_cli(capsys, "generate", tmp_path / "a.wav", "-o", tmp_path / "b.bvh", "--out-dir", tmp_path)
    assert code == 2 and "not both" in err
