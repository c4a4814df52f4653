"""The finishing passes through the CLI; outputs written all or none, and never over anything
that is not a regular file."""

import os
from pathlib import Path

import numpy as np
import pytest
from tests.helpers import EXAMPLE_SONG, run_cli

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
    args = ("generate", EXAMPLE_SONG, "--steps", "2", "--no-beat-lock", "--no-footsteps")
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


@pytest.mark.parametrize("make, words", [
    (lambda p: p.mkdir(), "is a folder"),
    (lambda p: os.mkfifo(p), "not a regular file"),
    (lambda p: os.symlink("/dev/null", p), "link to something that is not a regular file"),
])  # fmt: skip
def test_outputs_that_are_not_regular_files_are_refused_before_any_work(tmp_path, capsys, make, words):
    target = tmp_path / "dance.bvh"
    make(target)
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", target, "--steps", "2")
    assert code == 3 and words in err and len(err.strip().splitlines()) == 1


def test_a_symlinked_output_is_written_through_and_kept(tmp_path, capsys):
    real, link = tmp_path / "real.bvh", tmp_path / "link.bvh"
    real.write_text("old")
    link.symlink_to(real)
    assert run_cli(capsys, "generate", EXAMPLE_SONG, "-o", link, "--steps", "2")[0] == 0
    assert link.is_symlink() and real.read_text().startswith("HIERARCHY")


def test_a_name_too_long_is_an_output_error(tmp_path, capsys):
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / ("a" * 300 + ".bvh"), "--steps", "2")
    assert code == 3 and "cannot write" in err


def test_json_summary_and_motion_on_stdout_are_refused_together(capsys):
    code, out, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", "-", "-f", "npz", "--json")
    assert code == 2 and "standard output" in err and out == ""


def test_batch_contract(tmp_path, capsys):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    song = EXAMPLE_SONG.read_bytes()
    (tmp_path / "a" / "song.wav").write_bytes(song)
    (tmp_path / "b" / "song.wav").write_bytes(song)
    out = tmp_path / "out"
    out.mkdir()
    code, _, err = run_cli(capsys, "generate", tmp_path / "a" / "song.wav", tmp_path / "b" / "song.wav", "--out-dir", out)
    assert code == 2 and "more than once" in err and list(out.iterdir()) == []
    (tmp_path / "a file").write_bytes(b"x")
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "--out-dir", tmp_path / "a file" / "deeper")
    assert code == 3 and "not a folder" in err  # something else is there
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "x.bvh", "--generator", "nope")
    assert code == 2 and "not available" in err


def test_an_unexpected_failure_of_one_song_does_not_stop_the_batch(tmp_path, capsys, monkeypatch):
    import json

    from choreo.cli import generate_command

    real = generate_command.dance_one

    def flaky(backend, song, *args, **kwargs):
        if song.name == "bad.wav":
            raise RuntimeError("a bug")
        return real(backend, song, *args, **kwargs)

    monkeypatch.setattr(generate_command, "dance_one", flaky)
    (tmp_path / "bad.wav").write_bytes(EXAMPLE_SONG.read_bytes())
    code, out, err = run_cli(capsys, "generate", tmp_path / "bad.wav", EXAMPLE_SONG, "--out-dir", tmp_path,
                             "--steps", "2", "--json")
    summary = json.loads(out)
    assert code == 1 and summary["failed"] == 1
    assert [s["ok"] for s in summary["songs"]] == [False, True] and summary["songs"][0]["exit_code"] == 70
    assert (tmp_path / f"{EXAMPLE_SONG.stem}.bvh").exists()


def test_sampling_flags_given_to_the_graph_are_refused_by_name(tmp_path, capsys):
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "x.bvh", "--generator", "graph",
                           "--steps", "50", "--guidance", "3")
    assert code == 2 and "graph has no options guidance, steps (its options: " in err
    assert not (tmp_path / "x.bvh").exists()


def test_footsteps_are_on_by_default_and_move_only_the_legs(tmp_path, capsys):
    # one thread in both runs: the same seed's dance differs in the last float32 bits between thread counts
    args = ("generate", EXAMPLE_SONG, "--steps", "2", "--no-beat-lock", "--threads", "1")
    assert run_cli(capsys, *args, "-o", tmp_path / "stepped.npz")[0] == 0
    assert run_cli(capsys, *args, "-o", tmp_path / "glide.npz", "--no-footsteps")[0] == 0
    stepped, glide = read_motion(tmp_path / "stepped.npz"), read_motion(tmp_path / "glide.npz")
    np.testing.assert_allclose(stepped.root_positions, glide.root_positions, atol=1e-6)
    legs = [1, 2, 4, 5, 7, 8]
    others = [j for j in range(24) if j not in legs]
    np.testing.assert_allclose(stepped.rotations[:, others], glide.rotations[:, others], atol=1e-6)
    assert not np.allclose(stepped.rotations[:, legs], glide.rotations[:, legs], atol=1e-3)
