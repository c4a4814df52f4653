"""Batches split over machines (--shard K/N) and re-run after a failure (--skip-existing)."""

import json
import random
from pathlib import Path

import pytest
from test_cli import run_cli

from choreo.cli.batch import Shard, already_written
from choreo.errors import ParameterError


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
    (tmp_path / "a.bvh").write_text("x")
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

    def dance_one(backend, song, outputs, settings, constraints=None):
        danced.append(song.name)
        for path in outputs:
            Path(path).write_text("dance")
        return {"song": str(song), "ok": True, "outputs": outputs}

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
    (tmp_path / "song0.bvh").write_text("done")
    (tmp_path / "song0.npz").write_text("done")
    (tmp_path / "song1.bvh").write_text("half done")  # its npz is missing: danced again
    code, out, _ = run_cli(capsys, "generate", *files, "--out-dir", tmp_path, "--skip-existing", "--json", "-f", "bvh,npz")
    assert code == 0
    assert fake_dance == ["song1.wav", "song2.wav"]
    summary = json.loads(out)
    assert [s.get("skipped", False) for s in summary["songs"]] == [True, False, False]
    assert (tmp_path / "song0.bvh").read_text() == "done"


def test_shard_and_skip_existing_need_a_batch(tmp_path, capsys):
    for flags in (["--shard", "1/2"], ["--skip-existing"]):
        code, _, err = run_cli(capsys, "generate", tmp_path / "a.wav", "-o", tmp_path / "a.bvh", *flags)
        assert code == 2 and "--out-dir" in err
