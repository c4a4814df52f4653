"""Dataset readers (AIST++ fixtures, BVH folders) and the shared windowing."""

from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from choreo.datasets import WindowConfig, WindowedDataset, detect_dataset_kind, load_dataset, window_starts
from choreo.datasets.aistpp import load_aistpp, parse_sequence_name
from choreo.datasets.bvh_folder import load_bvh_folder
from choreo.errors import DatasetError
from choreo.formats import write_motion
from choreo.motion import Motion
from choreo.music import FEATURE_DIM

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "aistpp"


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path / "cache"))


def test_sequence_names():
    assert parse_sequence_name("gBR_sBM_cAll_d04_mBR0_ch01") == ("break", "mBR0")
    assert parse_sequence_name("gJB_sFM_cAll_d09_mJB5_ch10") == ("ballet jazz", "mJB5")
    with pytest.raises(DatasetError):
        parse_sequence_name("DANCE_W_12")


def test_aistpp_fixtures_load_with_splits_genres_and_aligned_features():
    clips = {c.name: c for c in load_aistpp(FIXTURES)}
    assert set(clips) == {"gBR_sBM_cAll_d04_mBR0_ch01", "gPO_sBM_cAll_d10_mPO1_ch02",
                          "gWA_sFM_cAll_d25_mWA2_ch03", "gHO_sBM_cAll_d19_mHO3_ch04"}  # ignore list honoured
    po = clips["gPO_sBM_cAll_d10_mPO1_ch02"]
    assert po.genre == "pop" and po.split == "train" and po.motion.fps == 30.0
    assert po.motion.num_frames == 180 and po.features.shape == (180, FEATURE_DIM)  # 6 s at 30 fps
    assert clips["gWA_sFM_cAll_d25_mWA2_ch03"].split == "val"  # kept apart, as EDGE leaves it out
    assert clips["gHO_sBM_cAll_d19_mHO3_ch04"].split == "test"
    # smpl_trans / smpl_scaling is metres: the root hovers about 0.9 m up.
    assert np.median(po.motion.root_positions[:, 1]) == pytest.approx(0.9, abs=0.05)
    assert [c.name for c in load_aistpp(FIXTURES, split="test")] == ["gHO_sBM_cAll_d19_mHO3_ch04"]


def test_windows_have_the_right_shapes():
    clips = load_dataset(FIXTURES, split="train")
    dataset = WindowedDataset(clips, WindowConfig(seconds=2.0, stride_seconds=1.0))
    lengths = {c.name: c.motion.num_frames for c in clips}
    assert len(dataset) == sum(len(window_starts(n, dataset.config)) for n in lengths.values())
    window = dataset[len(dataset) - 1]
    assert window.motion.num_frames == 60 and window.features.shape == (60, FEATURE_DIM)
    assert window.start_frame + 60 <= lengths[window.clip]


def test_window_starts():
    config = WindowConfig(seconds=5.0, stride_seconds=2.5)
    assert window_starts(150, config) == [0]
    assert window_starts(149, config) == []
    assert window_starts(300, config) == [0, 75, 150]


def test_detection():
    assert detect_dataset_kind(FIXTURES) == "aistpp"
    with pytest.raises(DatasetError):
        detect_dataset_kind(FIXTURES / "wavs")


def make_bvh_folder(root: Path) -> None:
    rng = np.random.default_rng(0)
    for folder, name, seconds in (("tango", "take1", 3.0), (".", "take2", 2.5), (".", "no_audio", 2.0)):
        (root / folder).mkdir(parents=True, exist_ok=True)
        frames = int(seconds * 60)
        motion = Motion.from_axis_angle(np.tile([0, 0.9, 0], (frames, 1)),
                                        np.cumsum(rng.normal(scale=0.02, size=(frames, 24, 3)), axis=0), fps=60)
        write_motion(motion, root / folder / f"{name}.bvh")
        if name != "no_audio":
            t = np.arange(int((seconds + 0.5) * 22050)) / 22050
            sf.write(root / folder / f"{name}.wav", (0.3 * np.sin(2 * np.pi * 440 * t) * (np.sin(2 * np.pi * 2 * t) > 0)).astype(np.float32), 22050)
    (root / "split.json").write_text('{"take1": "train", "take2": "test"}')


def test_bvh_folder(tmp_path):
    make_bvh_folder(tmp_path)
    with pytest.warns(UserWarning, match="without audio"):
        clips = {c.name: c for c in load_bvh_folder(tmp_path)}
    assert set(clips) == {"tango/take1", "take2"}
    take1 = clips["tango/take1"]
    assert take1.genre == "tango" and take1.split == "train" and take1.motion.fps == 30.0
    assert take1.motion.num_frames == 90 and take1.features.shape == (90, FEATURE_DIM)
    assert clips["take2"].genre is None and clips["take2"].split == "test"
    assert detect_dataset_kind(tmp_path) == "bvh"


def test_bvh_folder_without_any_audio(tmp_path):
    write_motion(Motion.rest(10), tmp_path / "lonely.bvh")
    with pytest.raises(DatasetError, match="no BVH file has an audio"), pytest.warns(UserWarning):
        load_bvh_folder(tmp_path)
