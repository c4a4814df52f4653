"""`choreo eval` end to end on small folders of joint arrays with click tracks beside them."""

import json

import numpy as np
import pytest
import soundfile as sf

from choreo.cli import main
from choreo.formats import write_motion
from choreo.motion import Motion


def click_track(path, seconds=6.0, bpm=120, sr=22050):
    signal = 0.01 * np.sin(2 * np.pi * 220 * np.arange(int(seconds * sr)) / sr)
    for beat in np.arange(0, seconds, 60 / bpm):
        start = int(beat * sr)
        signal[start: start + 300] += np.hanning(600)[300:] * np.sin(np.arange(300))
    sf.write(path, signal.astype(np.float32), sr)


def dance(seed, frames=150):
    rng = np.random.default_rng(seed)
    axis_angle = np.cumsum(rng.normal(scale=0.05, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.02, size=(frames, 3)), axis=0) + [0, 0.9, 0]
    return Motion.from_axis_angle(root, axis_angle)


@pytest.fixture
def folders(tmp_path):
    generated, truth = tmp_path / "generated", tmp_path / "truth"
    generated.mkdir()
    truth.mkdir()
    for i in range(4):
        np.save(generated / f"clip{i}.npy", dance(i).joint_positions().astype(np.float32))
        click_track(generated / f"clip{i}.wav")
        write_motion(dance(100 + i).resample(60), truth / f"real{i}.bvh")  # other format, other fps
    return generated, truth


def test_eval_prints_a_table_and_writes_json(folders, tmp_path, capsys):
    generated, truth = folders
    code = main(["eval", str(generated), "--gt", str(truth), "--json", str(tmp_path / "scores.json")])
    out = capsys.readouterr().out
    assert code == 0
    assert "BeatAlign" in out and "FID_k" in out
    report = json.loads((tmp_path / "scores.json").read_text())
    assert report["generated_count"] == 4 and report["ground_truth_count"] == 4 and report["fps"] == 30.0
    assert 0.0 <= report["beat_align"] <= 1.0
    assert all(np.isfinite(report[k]) for k in ("fid_k", "fid_g", "div_k", "div_g", "pfc"))
    assert [c["name"] for c in report["clips"]] == [f"clip{i}" for i in range(4)]
    assert all(c["frames"] == 150 and c["seconds"] == 5.0 and c["beat_align"] is not None for c in report["clips"])
    assert report["ground_truth_clips"][0]["frames"] == 150  # resampled from 60 fps
    assert any("resampled from 60" in note for note in report["notes"])
    assert report["ground_truth_beat_align"] is None  # no music beside the ground truth
    assert "ankle lift" in out and "classifier test" in out  # the legs and realism (docs/metrics.md)
    assert set(report["legs"]) == {"feet_speed", "ankle_lift", "pelvis_speed", "foot_jerk"}
    assert all(np.isfinite(v) and v >= 0 for v in report["legs"].values())
    assert set(report["clips"][0]["legs"]) == set(report["legs"])
    assert report["classifier"]["windows"] == 4 and 0.0 <= report["classifier"]["accuracy"] <= 1.0  # one 5 s window each


def test_eval_with_music_folder_and_z_up(folders, tmp_path, capsys):
    generated, truth = folders
    music = tmp_path / "songs"
    music.mkdir()
    for wav in generated.glob("*.wav"):
        wav.rename(music / wav.name)
    assert main(["eval", str(generated), "--gt", str(truth), "--music", str(music), "--json", str(tmp_path / "a.json")]) == 0
    capsys.readouterr()
    with_music = json.loads((tmp_path / "a.json").read_text())
    assert with_music["beat_align"] is not None


def test_eval_errors_are_one_line(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    (tmp_path / "notes.txt").write_text("hello")
    np.save(tmp_path / "bad.npy", np.zeros((10, 17, 3)))
    for args in (["eval", str(empty), "--gt", str(empty)], ["eval", str(tmp_path / "notes.txt"), "--gt", str(empty)],
                 ["eval", str(tmp_path / "bad.npy"), "--gt", str(tmp_path / "bad.npy")]):
        code = main(args)
        err = capsys.readouterr().err
        assert code == 2  # bad input
        lines = [line for line in err.splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("choreo: error:"), err


@pytest.mark.parametrize("fps, words", [("inf", "--fps takes a finite number"), ("1e308", "--fps must be 10 to 240"), ("1000", "--fps must be 10 to 240"),
                                        ("0", "--fps must be 10 to 240"), ("5", "--fps must be 10 to 240")])
def test_eval_fps_is_bounded_before_any_file_is_read(tmp_path, capsys, fps, words):
    """Issue 48, item 10: --fps inf overflowed the resampling (exit 70)."""
    code = main(["eval", str(tmp_path / "nothing"), "--gt", str(tmp_path / "nothing"), "--fps", fps])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err, err
