"""M2D: every clip in ../shared/data/m2d loads, aligned, fitted, on the floor, in its split."""

import json
from pathlib import Path

import numpy as np
import pytest

from choreo.datasets import TEST, TRAIN, WindowConfig, WindowedDataset, load_dataset
from choreo.datasets.m2d import GENRES, M2D_JOINTS, clip_splits, music_offsets, read_recording
from choreo.music import FEATURE_DIM

M2D = Path(__file__).resolve().parents[2] / "shared" / "data" / "m2d"
pytestmark = pytest.mark.skipif(not M2D.is_dir(), reason="../shared/data/m2d not available")


@pytest.fixture(scope="module")
def clips():
    return load_dataset(M2D)  # first run fits and featurises every clip (~2-3 min), later runs hit the cache


def test_every_clip_loads(clips):
    folders = sorted(p.name for p in M2D.iterdir() if p.is_dir() and p.name.startswith("DANCE_"))
    assert sorted(c.name for c in clips) == folders


def test_genres_and_fixed_split(clips):
    for clip in clips:
        assert clip.genre == GENRES[clip.name.split("_")[1]]
        assert clip.split in (TRAIN, TEST)
    splits = clip_splits()
    assert set(splits) == {c.name for c in clips}  # the split file covers every clip, by clip
    for genre in ("cha-cha", "rumba", "waltz"):  # tango has a single clip: train only
        assert {c.split for c in clips if c.genre == genre} == {TRAIN, TEST}
    test_seconds = sum(c.motion.duration for c in clips if c.split == TEST)
    assert 0.15 < test_seconds / sum(c.motion.duration for c in clips) < 0.3


def test_motion_and_music_are_aligned_and_finite(clips):
    for clip in clips:
        assert clip.motion.fps == 30.0
        assert clip.features.shape == (clip.motion.num_frames, FEATURE_DIM)
        assert np.isfinite(clip.features).all() and np.isfinite(clip.motion.root_positions).all()
        source_seconds = clip.info["source_frames"] / clip.info["source_fps"]
        assert abs(clip.motion.duration - source_seconds) < 0.1  # 25 -> 30 fps keeps the duration
        assert clip.audio_offset == pytest.approx(music_offsets()[clip.name])


def test_fit_error_below_3cm_after_bone_normalisation(clips):
    errors = {c.name: c.info["fit_error_cm"] for c in clips}
    assert max(errors.values()) < 3.0, errors


def test_feet_on_the_floor_and_human_sized(clips):
    for clip in clips:
        positions = clip.motion.joint_positions()
        lowest = positions[..., 1].min(axis=1)
        assert abs(np.median(lowest)) < 0.08, clip.name  # feet mostly on the floor
        height = positions[:, 15, 1] - lowest  # head above the lowest joint
        assert 1.2 < np.median(height) < 1.9, clip.name
        speed = np.linalg.norm(np.diff(clip.motion.root_positions, axis=0), axis=-1) * 30
        assert np.percentile(speed, 99) < 8.0, clip.name  # m/s: fast Viennese turns, but no teleporting


def test_windows_for_evaluation(clips):
    windows = WindowedDataset([c for c in clips if c.split == TEST], WindowConfig(seconds=5, stride_seconds=2.5))
    assert len(windows) > 50
    assert windows[0].motion.num_frames == 150 and windows[0].features.shape == (150, FEATURE_DIM)


def test_joint_layout_is_consistent_with_the_data():
    """Left joints sit at +X of the body frame, toes in front of heels, and the map is one-to-one."""
    recording = read_recording(M2D / "DANCE_R_2")
    names = [n for n, _ in M2D_JOINTS]
    raw = json.loads((M2D / "DANCE_R_2" / "skeletons.json").read_text())
    markers = np.asarray(raw["skeletons"])
    right_to_left = markers[:, names.index("l_hip")] - markers[:, names.index("r_hip")]
    up = np.array([0.0, 1.0, 0.0])
    forward = np.cross(right_to_left, up)  # x (left) cross y (up) = z (forward), right-handed
    toe_ahead = ((markers[:, names.index("l_toe")] - markers[:, names.index("l_heel")]) * forward).sum(-1)
    assert np.mean(toe_ahead > 0) > 0.9
    head_up = markers[:, names.index("head")][:, 1] - markers[:, names.index("neck")][:, 1]
    assert np.median(head_up) > 0.01  # ballroom frames lean the head back, but it is mostly above the neck
    smpl = [s for _, s in M2D_JOINTS if s is not None]
    assert len(smpl) == len(set(smpl)) == 19 and recording.targets.shape[1] == 20  # + pelvis from center
