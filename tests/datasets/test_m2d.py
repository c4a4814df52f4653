"""M2D: every clip in ../shared/data/m2d loads at 30 fps on SMPL-24, fitted, on the floor, in its split.

The all-clips tests are marked slow: their first run fits and featurises every clip (about 2 minutes
on 2 cores, see docs/m2d.md), later runs read the cache in seconds. ``-m 'not slow'`` keeps the
two-clip, layout and error tests.
"""

from __future__ import annotations

import json
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from choreo.datasets import TEST, TRAIN, WindowConfig, WindowedDataset, load_dataset, m2d
from choreo.datasets.bvh_folder import _read_mapping
from choreo.datasets.m2d import (
    GENRES,
    MARKER_NAMES,
    SMPL_TARGETS,
    SOURCE_FPS,
    clip_folders,
    clip_splits,
    load_clip,
    load_m2d,
    make_split,
    make_validation,
    music_offsets,
    read_recording,
    validation_clips,
)  # fmt: skip
from choreo.errors import DatasetError
from choreo.music import FEATURE_DIM
from tests.datasets.helpers import clip

M2D = Path(__file__).resolve().parents[3] / "shared" / "data" / "m2d"
needs_data = pytest.mark.skipif(not M2D.is_dir(), reason="../shared/data/m2d not available")
FIT_ERROR_LIMIT_CM = 3.0


def clip_names() -> list[str]:
    return sorted(p.name for p in M2D.iterdir() if p.is_dir() and p.name.startswith("DANCE_"))


@pytest.fixture(scope="module")
def clips():
    return load_dataset(M2D)  # the registry routes DANCE_* folders to load_m2d


def check_clip(clip) -> None:
    """What every loaded clip must satisfy, whatever its genre."""
    assert clip.genre == GENRES[clip.name.split("_")[1]]
    assert clip.motion.fps == 30.0
    assert clip.features.shape == (clip.motion.num_frames, FEATURE_DIM)
    assert np.isfinite(clip.features).all() and np.isfinite(clip.motion.root_positions).all()
    assert np.isfinite(clip.motion.rotations).all()
    source_seconds = clip.info["source_frames"] / clip.info["source_fps"]
    assert source_seconds - 2.0 < clip.motion.duration <= source_seconds + 0.05  # 30 fps keeps the duration
    assert clip.audio_offset == pytest.approx(music_offsets()[clip.name])
    assert clip.info["fit_error_cm"] < FIT_ERROR_LIMIT_CM, (clip.name, clip.info["fit_error_cm"])
    positions = clip.motion.joint_positions()
    lowest = positions[..., 1].min(axis=1)
    assert abs(np.median(lowest)) < 0.03, clip.name  # feet on the floor most of the time
    assert np.percentile(lowest, 5) > -0.10, clip.name  # and rarely through it
    height = np.median(positions[:, 15, 1] - lowest)  # head joint above the lowest joint
    assert 1.3 < height < 1.8, (clip.name, height)
    speed = np.linalg.norm(np.diff(clip.motion.root_positions, axis=0), axis=-1) * 30
    assert np.percentile(speed, 99) < 5.0, clip.name  # m/s: no teleporting (tango peaks at 4.2 m/s)


@needs_data
def test_two_clips_load_fast_path(tmp_path, monkeypatch):
    """One Latin clip and one waltz clip, cold cache: the whole pipeline in a few seconds."""
    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path))
    offsets, splits = music_offsets(), clip_splits()
    for name in ("DANCE_R_8", "DANCE_W_22"):
        clip = load_clip(M2D / name, offsets[name], splits[name])
        check_clip(clip)
        assert clip.info["source_fps"] == SOURCE_FPS[clip.genre]
    assert list((tmp_path / "m2d").glob("DANCE_R_8_*.npz"))  # the fit was cached


@needs_data
@pytest.mark.slow
def test_every_clip_loads_and_is_sound(clips):
    assert [c.name for c in clips] == [f.name for f in clip_folders(M2D)]
    assert sorted(c.name for c in clips) == clip_names()
    for clip in clips:
        check_clip(clip)


@needs_data
@pytest.mark.slow
def test_fixed_split_by_clip(clips):
    splits = clip_splits()
    assert set(splits) == set(clip_names())  # the split file covers every clip, nothing else
    assert make_split(clip_names()) == {s: sorted(n for n in splits if splits[n] == s) for s in (TRAIN, TEST)}
    for genre in ("cha-cha", "rumba", "waltz"):  # tango has a single clip: train only
        assert {c.split for c in clips if c.genre == genre} == {TRAIN, TEST}
    test_seconds = sum(c.motion.duration for c in clips if c.split == TEST)
    assert 0.15 < test_seconds / sum(c.motion.duration for c in clips) < 0.3
    assert [c.name for c in load_m2d(M2D, split=TEST)] == [c.name for c in clips if c.split == TEST]


def test_validation_clips_are_drawn_from_train_per_genre():
    """The validation clips (m2d_split.json) are what make_validation draws: train clips only,
    at least one per genre that has several, none from tango's single clip."""
    splits = clip_splits()
    train = sorted(n for n, s in splits.items() if s == TRAIN)
    held = validation_clips()
    assert list(held) == make_validation(train) and set(held) <= set(train)
    assert {n.split("_")[1] for n in held} == {"C", "R", "W"}
    assert make_validation(train) != make_validation(train, seed=2018)  # the seed matters


@needs_data
@pytest.mark.slow
def test_test_split_windows_for_evaluation(clips):
    test_clips = [c for c in clips if c.split == TEST]
    windows = WindowedDataset(test_clips, WindowConfig(seconds=5, stride_seconds=2.5))
    assert len(windows) > 100
    assert windows[0].motion.num_frames == 150 and windows[0].features.shape == (150, FEATURE_DIM)


@needs_data
def test_marker_layout_matches_the_data():
    """Left markers at +x of the hip frame, toes ahead of heels, head markers side by side."""
    raw = np.asarray(json.loads((M2D / "DANCE_R_2" / "skeletons.json").read_text())["skeletons"])
    index = {name: i for i, name in enumerate(MARKER_NAMES)}
    right_to_left = raw[:, index["l_hip"]] - raw[:, index["r_hip"]]
    forward = np.cross(right_to_left, [0.0, 1.0, 0.0])  # x (left) cross y (up) = z (forward)
    for side in ("l", "r"):
        toe_ahead = ((raw[:, index[f"{side}_toe"]] - raw[:, index[f"{side}_heel"]]) * forward).sum(-1) > 0
        assert toe_ahead.mean() > 0.9
    head = raw[:, index["l_head"]] - raw[:, index["r_head"]]
    assert (head * right_to_left).sum(-1).mean() > 0 and abs(np.median(head[:, 1])) < 3.0  # cm
    assert ((raw[:, index["l_shoulder"]] - raw[:, index["r_shoulder"]]) * right_to_left).sum(-1).mean() > 0
    markers = [m for ms in SMPL_TARGETS.values() for m in ms]
    assert len(SMPL_TARGETS) == 16 and len(markers) == len(set(markers)) == 17
    recording = read_recording(M2D / "DANCE_R_2")
    targets, joints = recording.targets()
    assert targets.shape == (recording.num_frames, 16, 3) and joints == sorted(joints)


def write_fake_clip(folder: Path, frames: int = 20) -> None:
    """A made-up clip with the M2D file layout (not data from the corpus)."""
    folder.mkdir(parents=True)
    rng = np.random.default_rng(0)
    skeleton = rng.normal(scale=30.0, size=(frames, 23, 3)).tolist()
    (folder / "skeletons.json").write_text(json.dumps({"length": frames, "center": [[0, 90, 0]] * frames,
                                                       "skeletons": skeleton}))
    (folder / "config.json").write_text(json.dumps({"start_position": 0, "end_position": frames}))
    (folder / "audio.mp3").write_bytes(b"")


def test_layout_errors_are_one_line(tmp_path):
    def fails(match, call, *args):
        with pytest.raises(DatasetError, match=match) as caught:
            call(*args)
        assert "\n" not in str(caught.value)

    fails("does not exist", load_m2d, tmp_path / "nowhere")
    fails("no DANCE_", load_m2d, tmp_path)
    write_fake_clip(tmp_path / "DANCE_X_1")
    fails("DANCE_X_1: not an M2D clip folder", load_m2d, tmp_path)
    (tmp_path / "DANCE_X_1").rename(tmp_path / "DANCE_W_1")
    (tmp_path / "DANCE_W_1" / "skeletons.json").unlink()
    fails("skeletons.json is missing", load_m2d, tmp_path)
    write_fake_clip(tmp_path / "odd" / "DANCE_C_1")
    (tmp_path / "odd" / "DANCE_C_1" / "skeletons.json").write_text('{"center": [], "skeletons": [[1, 2]]}')
    fails("expected", read_recording, tmp_path / "odd" / "DANCE_C_1")
    (tmp_path / "odd" / "DANCE_C_1" / "config.json").write_text("{not json")
    fails("config.json is unreadable", read_recording, tmp_path / "odd" / "DANCE_C_1")


@pytest.mark.hardening
def test_skeletons_json_is_read_without_a_python_float_per_number(tmp_path):
    folder = clip(tmp_path, frames=3000)
    tracemalloc.start()
    recording = m2d.read_recording(folder)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert recording.markers.shape == (3000, 23, 3)
    assert peak < 5 * (folder / "skeletons.json").stat().st_size  # json.loads took over 8x


@pytest.mark.hardening
@pytest.mark.parametrize("config", ['{"start_position": 1e999, "end_position": 40}',
                                    '{"start_position": 0, "end_position": -1e999}'])
def test_infinite_positions_in_config_are_a_dataset_error(tmp_path, config):
    with pytest.raises(DatasetError, match="finite"):
        m2d.read_recording(clip(tmp_path, config=config))


@pytest.mark.hardening
def test_deeply_nested_dataset_json_is_a_dataset_error(tmp_path):
    (tmp_path / "genres.json").write_text("[" * 10**6)
    with pytest.raises(DatasetError):
        _read_mapping(tmp_path / "genres.json")
    (tmp_path / "DANCE_C_1").mkdir()
    (tmp_path / "DANCE_C_1" / "config.json").write_text('{"a": ' * 10**5 + "1" + "}" * 10**5)
    with pytest.raises(DatasetError):
        m2d._read_json(tmp_path / "DANCE_C_1" / "config.json")


@pytest.mark.hardening
@pytest.mark.parametrize("scale", [0.0, np.nan])
def test_a_cached_fit_with_legless_or_non_finite_bones_is_a_dataset_error(scale):
    from choreo.skeleton import SMPL24

    fit = {"root_positions": np.zeros((3, 3)), "rotations": np.tile([1.0, 0, 0, 0], (3, 24, 1)),
           "offsets": SMPL24.offsets * scale}
    with pytest.raises(DatasetError, match="DANCE_C_1: the legs"):
        m2d.standard_motion(fit, 25.0, {"source": "DANCE_C_1"})


@pytest.mark.hardening
def test_positions_too_far_to_fit_are_a_dataset_error(tmp_path):
    folder = clip(tmp_path, frames=12)
    data = json.loads((folder / "skeletons.json").read_text())
    data["skeletons"][3][5][1] = 1e308  # finite, but it overflowed the Procrustes fit (SVD did not converge, or a hang)
    (folder / "skeletons.json").write_text(json.dumps(data))
    with pytest.raises(DatasetError, match="beyond"):
        m2d.read_recording(folder)


@pytest.mark.hardening
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
    elif damage == "zero quaternion":  # found by the fuzzer (tests/fuzz/inputs.py m2dfit): trusted, then every load failed
        fit["rotations"][2, 7] = 0.0
    elif damage == "far root":  # the same: a root 200 km out passed the fit's checks, then Motion refused it
        fit["root_positions"][4, 0] = 2e5
    with open(entry, "wb") as handle:
        np.savez(handle, **fit)


@pytest.mark.hardening
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
