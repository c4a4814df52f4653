"""The finishing passes through the CLI, and several outputs written all or none."""

from pathlib import Path

import numpy as np
from test_cli import EXAMPLE_SONG, run_cli

from choreo.formats import read_motion
from choreo.metrics import beat_align_score, motion_beats
from choreo.music import Music


def test_beat_lock_is_on_by_default_and_moves_motion_beats_onto_music_beats(tmp_path, capsys):
    args = ("generate", EXAMPLE_SONG, "--steps", "2", "--seed", "3")
    assert run_cli(capsys, *args, "-o", tmp_path / "locked.npz")[0] == 0
    assert run_cli(capsys, *args, "-o", tmp_path / "raw.npz", "--no-beat-lock")[0] == 0
    locked, raw = read_motion(tmp_path / "locked.npz"), read_motion(tmp_path / "raw.npz")
    assert locked.num_frames == raw.num_frames
    assert not np.allclose(locked.rotations, raw.rotations)
    beats = Music.from_file(EXAMPLE_SONG).beat_frames
    score = lambda m: beat_align_score(beats, motion_beats(m.joint_positions()))  # noqa: E731
    assert score(locked) > score(raw)


def test_foot_lock_is_asked_for_and_moves_only_the_root(tmp_path, capsys):
    args = ("generate", EXAMPLE_SONG, "--steps", "2", "--no-beat-lock")
    assert run_cli(capsys, *args, "-o", tmp_path / "raw.npz")[0] == 0
    assert run_cli(capsys, *args, "-o", tmp_path / "feet.npz", "--foot-lock")[0] == 0
    raw, feet = read_motion(tmp_path / "raw.npz"), read_motion(tmp_path / "feet.npz")
    np.testing.assert_allclose(feet.rotations, raw.rotations, atol=1e-6)
    assert not np.allclose(feet.root_positions, raw.root_positions)


def test_seed_motion_frames_survive_the_beat_lock(tmp_path, capsys):
    assert run_cli(capsys, "generate", EXAMPLE_SONG, "--steps", "2", "-o", tmp_path / "first.npz", "--no-beat-lock")[0] == 0
    opening = read_motion(tmp_path / "first.npz").slice_frames(0, 40)
    from choreo.formats import write_motion

    write_motion(opening, tmp_path / "opening.npz")
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "--steps", "2", "--seed", "5",
                           "--seed-motion", tmp_path / "opening.npz", "-o", tmp_path / "continued.npz")
    assert code == 0, err
    continued = read_motion(tmp_path / "continued.npz")
    np.testing.assert_allclose(continued.joint_positions()[:40], opening.joint_positions(), atol=1e-4)


def test_an_unknown_second_output_leaves_no_first_output(tmp_path, capsys):
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "a.bvh", "-o", tmp_path / "b.xyz")
    assert code == 3 and "b.xyz" in err
    assert not Path(tmp_path / "a.bvh").exists()
    assert list(tmp_path.iterdir()) == []
