"""Issue 38, items 7-9 on datasets: M2D reading, genres.json and the feature cache, from bytes."""

from __future__ import annotations

import json
import os
import stat
import tracemalloc

import numpy as np
import pytest

from choreo.datasets import cache, m2d
from choreo.datasets.bvh_folder import _read_mapping
from choreo.errors import DatasetError
from choreo.music import FEATURE_DIM


def clip(tmp_path, frames: int = 40, config=None):
    folder = tmp_path / "DANCE_C_1"
    folder.mkdir()
    rng = np.random.default_rng(0)
    skeletons = np.round(rng.normal(size=(frames, 23, 3)) * 50, 4).tolist()
    (folder / "skeletons.json").write_text(json.dumps({"center": np.zeros((frames, 3)).tolist(),
                                                        "skeletons": skeletons, "length": frames}))
    (folder / "config.json").write_text(config or '{"start_position": 0, "end_position": 40}')
    return folder


def test_skeletons_json_is_read_without_a_python_float_per_number(tmp_path):
    folder = clip(tmp_path, frames=3000)
    tracemalloc.start()
    recording = m2d.read_recording(folder)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert recording.markers.shape == (3000, 23, 3)
    assert peak < 5 * (folder / "skeletons.json").stat().st_size  # json.loads took over 8x


@pytest.mark.parametrize("config", ['{"start_position": 1e999, "end_position": 40}',
                                    '{"start_position": 0, "end_position": -1e999}'])
def test_infinite_positions_in_config_are_a_dataset_error(tmp_path, config):
    with pytest.raises(DatasetError, match="finite"):
        m2d.read_recording(clip(tmp_path, config=config))


def test_deeply_nested_dataset_json_is_a_dataset_error(tmp_path):
    (tmp_path / "genres.json").write_text("[" * 10**6)
    with pytest.raises(DatasetError):
        _read_mapping(tmp_path / "genres.json")
    (tmp_path / "DANCE_C_1").mkdir()
    (tmp_path / "DANCE_C_1" / "config.json").write_text('{"a": ' * 10**5 + "1" + "}" * 10**5)
    with pytest.raises(DatasetError):
        m2d._read_json(tmp_path / "DANCE_C_1" / "config.json")


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


def test_audio_replaced_with_the_same_size_and_time_is_analysed_again(tmp_path, fake_music):
    song = tmp_path / "song.wav"
    for content in (b"a" * 3_000_000, b"a" * 2_999_999 + b"b"):  # only the last MiB differs: cp -p
        song.write_bytes(content)
        os.utime(song, ns=(10**18, 10**18))
        cache.cached_music(song)
    assert fake_music.analysed == 2


def legless_clip(root):
    """An M2D clip whose 23 markers sit at one point each frame: legs of zero length."""
    root.mkdir()
    folder = clip(root)
    frames = 40
    (folder / "skeletons.json").write_text(json.dumps({"center": [[0, 90, 0]] * frames, "length": frames,
                                                        "skeletons": np.zeros((frames, 23, 3)).tolist()}))
    (folder / "audio.mp3").write_bytes(b"")
    return folder


def test_a_recording_with_zero_leg_length_is_exit_2_through_prepare(tmp_path, monkeypatch, capsys):
    from choreo.cli import main

    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path / "cache"))
    legless_clip(tmp_path / "data")
    code = main(["prepare", str(tmp_path / "data")])
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert code == 2 and len(err) == 1 and "legs have no usable length" in err[0], err


@pytest.mark.parametrize("scale", [0.0, np.nan])
def test_a_cached_fit_with_legless_or_non_finite_bones_is_a_dataset_error(scale):
    from choreo.skeleton import SMPL24

    fit = {"root_positions": np.zeros((3, 3)), "rotations": np.tile([1.0, 0, 0, 0], (3, 24, 1)),
           "offsets": SMPL24.offsets * scale}
    with pytest.raises(DatasetError, match="DANCE_C_1: the legs"):
        m2d.standard_motion(fit, 25.0, {"source": "DANCE_C_1"})


def test_a_bvh_with_zero_leg_offsets_converts_to_glb_and_mixamo(tmp_path):
    import io

    from choreo.formats import read_motion, write_motion
    from choreo.formats.bvh import write_bvh
    from choreo.formats.rigs import retarget
    from choreo.errors import MotionFormatError
    from choreo.motion import Motion
    from choreo.skeleton import SMPL24

    offsets = SMPL24.offsets.copy()
    offsets[[1, 2, 4, 5, 7, 8, 10, 11]] = 0.0
    motion = Motion.from_axis_angle(np.zeros((4, 3)), np.zeros((4, 24, 3)), fps=30.0,
                                    skeleton=SMPL24.with_offsets(offsets))
    buffer = io.BytesIO()
    write_bvh(motion, buffer)
    (tmp_path / "legless.bvh").write_bytes(buffer.getvalue())
    legless = read_motion(tmp_path / "legless.bvh")
    write_motion(legless, tmp_path / "out.glb")  # was a NaN in the glTF JSON: exit 70
    write_motion(legless, tmp_path / "out.bvh", rig="mixamo")  # was "motion contains NaN"
    assert np.isfinite(read_motion(tmp_path / "out.bvh").joint_positions()).all()
    with pytest.raises(MotionFormatError, match="legs have no length"):
        retarget(legless, "mixamo", lengths="rig")


def test_positions_too_far_to_fit_are_a_dataset_error(tmp_path):
    folder = clip(tmp_path, frames=12)
    data = json.loads((folder / "skeletons.json").read_text())
    data["skeletons"][3][5][1] = 1e308  # finite, but it overflowed the Procrustes fit (SVD did not converge, or a hang)
    (folder / "skeletons.json").write_text(json.dumps(data))
    with pytest.raises(DatasetError, match="beyond"):
        m2d.read_recording(folder)


# Issue 48, item 1: cache entries are never written through a link planted at their name ----------

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


def test_a_link_planted_at_an_m2d_fit_entry_is_replaced_not_written_through(tmp_path, monkeypatch):
    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path / "cache"))
    fit = {"rotations": np.zeros((40, 24, 4), np.float32), "offsets": np.zeros((24, 3))}
    monkeypatch.setattr(m2d, "fit_recording", lambda recording: fit)
    recording = m2d.read_recording(clip(tmp_path))
    victim = tmp_path / "victim.txt"
    victim.write_bytes(b"precious")
    entry = m2d._fit_cache_path(tmp_path / "DANCE_C_1", recording.fps)
    entry.parent.mkdir(parents=True)
    entry.symlink_to(victim)
    m2d.load_fit(tmp_path / "DANCE_C_1", recording)
    assert victim.read_bytes() == b"precious" and not entry.is_symlink()
    assert np.load(entry)["rotations"].shape == (40, 24, 4)


# Issue 48, item 9: one validating reader for both caches; damage is a miss, writes best effort -----

def test_a_truncated_feature_entry_is_recomputed(tmp_path, fake_music):
    song = tmp_path / "song.wav"
    song.write_bytes(b"RIFF" + bytes(100))
    cache.cached_music(song)
    entry, = (tmp_path / "cache" / "features").iterdir()
    entry.write_bytes(entry.read_bytes()[:200])
    assert np.isfinite(cache.cached_music(song).features).all() and fake_music.analysed == 2


def good_fit(frames: int, fps: float) -> dict:
    from choreo.skeleton import SMPL24

    return {"rotations": np.tile(np.float32([1, 0, 0, 0]), (frames, 24, 1)), "root_positions": np.zeros((frames, 3)),
            "offsets": SMPL24.offsets, "joint_errors": np.zeros(len(m2d.SMPL_TARGETS)),
            "fit_error": np.array(0.01), "standard_error": np.array(0.02), "fps": np.array(fps)}


def damage_fit(entry, damage, recording):
    fit = good_fit(recording.num_frames, recording.fps)
    if damage == "truncated":
        entry.write_bytes(entry.read_bytes()[:300])  # was BadZipFile: exit 70
        return
    if damage == "no offsets":
        del fit["offsets"]  # was KeyError: exit 70
    elif damage == "nan":
        fit["rotations"][3, 5, 0] = np.nan  # was exit 2 naming no cache, and never refitted
    elif damage == "shape":
        fit["root_positions"] = np.zeros((recording.num_frames, 2))
    elif damage == "legless":
        fit["offsets"] = fit["offsets"] * 0.0
    elif damage == "fps":
        fit["fps"] = np.array(recording.fps * 2)
    elif damage == "zero quaternion":  # found by the fuzzer (fuzz_inputs m2dfit): trusted, then every load failed
        fit["rotations"][2, 7] = 0.0
    elif damage == "far root":  # the same: a root 200 km out passed the fit's checks, then Motion refused it
        fit["root_positions"][4, 0] = 2e5
    with open(entry, "wb") as handle:
        np.savez(handle, **fit)


@pytest.mark.parametrize("damage", ["truncated", "no offsets", "nan", "shape", "legless", "fps", "zero quaternion",
                                    "far root"])
def test_a_damaged_m2d_fit_entry_is_refitted(tmp_path, monkeypatch, damage):
    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path / "cache"))
    fits = []
    monkeypatch.setattr(m2d, "fit_recording", lambda recording: fits.append(1) or good_fit(recording.num_frames, recording.fps))
    folder = clip(tmp_path)
    recording = m2d.read_recording(folder)
    m2d.load_fit(folder, recording)
    assert m2d.load_fit(folder, recording) is not None and len(fits) == 1  # a good entry is used
    damage_fit(m2d._fit_cache_path(folder, recording.fps), damage, recording)
    fit = m2d.load_fit(folder, recording)
    assert len(fits) == 2 and np.isfinite(fit["rotations"]).all()
    m2d.load_fit(folder, recording)
    assert len(fits) == 2  # the rewritten entry is used


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
