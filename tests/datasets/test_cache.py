"""Tests of choreo.datasets.cache.

Markers say where a test came from: hardening (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest

from choreo.datasets import cache
from choreo.music import FEATURE_DIM


class FakeMusic:
    """Stands in for choreo.music.Music: counts analyses, takes what the cache hands back."""

    analysed = 0

    def __init__(self, **fields):
        self.__dict__.update(fields)

    @classmethod
    def from_file(cls, path, start=None, end=None):
        cls.analysed += 1
        return cls(path=path, duration=2.0, fps=30.0, features=np.ones((60, FEATURE_DIM)), beat_times=np.array([0.5, 1.0]),
                   tempo=120.0, start=0.0)


@pytest.fixture
def fake_music(monkeypatch, tmp_path):
    import choreo.music

    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(choreo.music, "Music", FakeMusic)
    FakeMusic.analysed = 0
    return FakeMusic


def planted(entry, **arrays):
    good = {"features": np.ones((60, FEATURE_DIM)), "beat_times": np.array([0.5]), "tempo": 120.0, "duration": 2.0, "fps": 30.0}
    with open(entry, "wb") as handle:
        np.savez(handle, **{**good, **arrays})


@pytest.mark.hardening
@pytest.mark.parametrize("bad", [{"features": np.full((60, FEATURE_DIM), np.nan)}, {"features": np.ones(60)},
                                 {"features": np.ones((60, FEATURE_DIM + 1))},  # issue 48, item 9: train crashed
                                 {"features": np.array(["x"])}, {"beat_times": np.array([np.inf])},
                                 {"fps": -30.0}, {"duration": np.ones(3)}, {"tempo": np.nan}])
def test_a_planted_cache_entry_is_recomputed_not_trusted(tmp_path, fake_music, bad):
    song = tmp_path / "song.wav"
    song.write_bytes(b"RIFF" + bytes(100))
    cache.cached_music(song)
    entry, = (tmp_path / "cache" / "features").iterdir()
    planted(entry, **bad)
    music = cache.cached_music(song)
    assert fake_music.analysed == 2 and np.isfinite(music.features).all()
    assert cache.cached_music(song) is not None and fake_music.analysed == 2  # the rewritten entry is used


@pytest.mark.hardening
def test_audio_replaced_with_the_same_size_and_time_is_analysed_again(tmp_path, fake_music):
    song = tmp_path / "song.wav"
    for content in (b"a" * 3_000_000, b"a" * 2_999_999 + b"b"):  # only the last MiB differs: cp -p
        song.write_bytes(content)
        os.utime(song, ns=(10**18, 10**18))
        cache.cached_music(song)
    assert fake_music.analysed == 2


@pytest.mark.hardening
@pytest.mark.parametrize("victim_kind", ["file", "fifo"])
def test_a_link_planted_at_a_feature_entry_is_replaced_not_written_through(tmp_path, fake_music, victim_kind):
    song, victim = tmp_path / "song.wav", tmp_path / "victim"
    song.write_bytes(b"RIFF" + bytes(100))
    victim.write_bytes(b"precious") if victim_kind == "file" else os.mkfifo(victim)  # a FIFO: reading never ends
    cache.cached_music(song)
    entry, = (tmp_path / "cache" / "features").iterdir()
    entry.unlink()
    entry.symlink_to(victim)  # a warm cache whose entries were swapped for links
    cache.cached_music(song)
    assert victim.read_bytes() == b"precious" if victim_kind == "file" else stat.S_ISFIFO(victim.stat().st_mode)
    assert not entry.is_symlink() and entry.is_file() and fake_music.analysed == 2
    assert cache.cached_music(song) is not None and fake_music.analysed == 2  # the new entry is used


@pytest.mark.hardening
def test_a_truncated_feature_entry_is_recomputed(tmp_path, fake_music):
    song = tmp_path / "song.wav"
    song.write_bytes(b"RIFF" + bytes(100))
    cache.cached_music(song)
    entry, = (tmp_path / "cache" / "features").iterdir()
    entry.write_bytes(entry.read_bytes()[:200])
    assert np.isfinite(cache.cached_music(song).features).all() and fake_music.analysed == 2


@pytest.mark.hardening
@pytest.mark.parametrize("root", ["file", "under a file", "read-only"])
def test_a_cache_that_cannot_be_written_is_skipped(tmp_path, fake_music, monkeypatch, root):
    import choreo.fileio

    song, base = tmp_path / "song.wav", tmp_path / "cache"
    song.write_bytes(b"RIFF" + bytes(100))
    if root == "read-only":
        (base / "features").mkdir(parents=True)
        (base / "features").chmod(0o555)
        real_access = os.access  # root may write anywhere: say what a user would be told
        monkeypatch.setattr(choreo.fileio.os, "access", lambda path, mode: False if str(path).startswith(str(base)) else real_access(path, mode))
    else:
        base.write_bytes(b"not a folder")  # CHOREO_CACHE_DIR set to a file: was exit 70
        monkeypatch.setenv("CHOREO_CACHE_DIR", str(base / "deeper" if root == "under a file" else base))
    for analysed in (1, 2):  # nothing cached: analysed again, and the command goes on
        assert np.isfinite(cache.cached_music(song).features).all() and fake_music.analysed == analysed
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache", "song.wav"]
    assert base.is_file() or not list((base / "features").iterdir())
