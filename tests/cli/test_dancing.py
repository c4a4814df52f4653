"""choreo.cli.dancing: the options every dancing command shares, declared once, and the road to choreo.dance."""

from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

import choreo
from choreo.cli import main
from choreo.formats import read_motion
from choreo.generator import available_plugins
from choreo.options import FLAG, flag_fields
from choreo.pipeline import Finishing

SONG = Path(__file__).parents[2] / "examples" / "drum_and_bass_174bpm.wav"
DANCING = (("generate",), ("inbetween",), ("inpaint",), ("trajectory",), ("graph", "dance"))
SHARED = ("--style", "--checkpoint", "--seed", "--format", "--rig", "--bpm", "--beats", "--beat-tracker", "--threads")


def command_params(*command: str) -> dict:
    """{flag: its click parameter} of a command, e.g. command_params("graph", "dance")."""
    import click
    from typer.main import get_command

    from choreo.cli.app import app

    found = get_command(app)
    for name in command:
        found = found.get_command(click.Context(found), name)
    return {flag: p for p in found.params for flag in (*p.opts, *p.secondary_opts)}


def flag_names(options_type) -> list[str]:
    return [f.metadata[FLAG].names[0].split("/")[0] if f.metadata[FLAG].names else f"--{f.name.replace('_', '-')}"
            for f in flag_fields(options_type)]


def test_every_dancing_command_takes_the_shared_and_the_finishing_flags():
    for command in DANCING:
        params = command_params(*command)
        for flag in SHARED + tuple(flag_names(Finishing)) + ("--no-root-path", "--no-pace", "--no-footsteps"):
            assert flag in params, (command, flag)


def test_the_requests_beats_and_deliverys_flags_are_declared_once_on_their_dataclasses():
    """Each shared flag's help is its dataclass field's (DanceRequest, BeatOptions, Delivery): the
    commands that take them (the dancing ones, info, convert) read the same declaration."""
    from choreo.motion.delivery_options import Delivery
    from choreo.music.beat_options import BeatOptions
    from choreo.pipeline import DanceRequest

    owners = {DanceRequest: DANCING, BeatOptions: DANCING + (("info",),), Delivery: DANCING + (("convert",),)}
    for owner, commands in owners.items():
        helps = {name: f.metadata[FLAG].help for name, f in zip(flag_names(owner), flag_fields(owner))}
        assert helps, owner
        for command in commands:
            params = command_params(*command)
            for flag, help_text in helps.items():
                assert params[flag].help.startswith(help_text.replace("\\[", "[")[:40]), (command, flag)


def test_building_the_command_line_loads_neither_numpy_nor_torch():
    """The flags' dataclasses live in modules free of numpy (choreo.lazy), so --help and a mistyped
    flag answer at once."""
    import subprocess
    import sys

    code = "import sys, choreo.cli.app; print(sorted({'numpy', 'torch', 'scipy'} & set(sys.modules)))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "[]"


def test_backend_flags_and_their_defaults_come_from_the_plugins_options():
    sgmd, graph = available_plugins()["sgmd"].options, available_plugins()["graph"].options
    for command, options_type in ((("generate",), sgmd), (("inpaint",), sgmd), (("graph", "dance"), graph)):
        params = command_params(*command)
        for flag in flag_names(options_type):
            assert flag in params, (command, flag)
    assert f"[default: {sgmd().steps}]" in command_params("generate")["--steps"].help
    assert f"[default: {graph().top_k}]" in command_params("graph", "dance")["--top-k"].help
    assert "--top-k" not in command_params("generate") and "--guidance" not in command_params("graph", "dance")


def test_train_commands_are_made_from_each_backends_train_options(capsys):
    for name in ("sgmd", "graph"):
        params = command_params("train", name)
        for flag in flag_names(available_plugins()[name].train_options) + ["--data", "--out", "--resume"]:
            assert flag in params, (name, flag)
    assert "--prompt" in command_params("train", "sgmd") and "--prompt" not in command_params("train", "graph")
    assert "[default: 6.36]" not in command_params("train", "graph")["--steps"].help  # each backend's own defaults
    assert main(["train", "graph", "--data", ".", "--out", "x", "--prompt", "name"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_the_root_path_and_pace_flags_turn_their_passes_off(tmp_path, capsys, tiny_checkpoint):
    common = ["generate", str(SONG), "--checkpoint", str(tiny_checkpoint), "--steps", "2", "--threads", "1"]
    assert main([*common, "-o", str(tmp_path / "plain.npz"), "--no-root-path", "--no-pace"]) == 0
    assert main([*common, "-o", str(tmp_path / "smooth.npz")]) == 0
    plain, smooth = read_motion(tmp_path / "plain.npz"), read_motion(tmp_path / "smooth.npz")
    assert not np.allclose(plain.root_positions, smooth.root_positions, atol=1e-4)
    same = choreo.dance(SONG, checkpoint=tiny_checkpoint, options={"steps": 2}, threads=1,
                        finishing=Finishing(root_path=False, pace=False))
    np.testing.assert_allclose(same.root_positions, plain.root_positions, atol=1e-5)


def test_every_finishing_field_but_its_configs_is_a_flag():
    assert {f.name for f in fields(Finishing)} - {f.name for f in flag_fields(Finishing)} == {"configs"}


@pytest.mark.parametrize("command", DANCING)
def test_an_unknown_backend_option_value_is_refused_before_the_song_is_read(tmp_path, capsys, command):
    bad = "--guidance" if command[0] != "graph" else "--top-k"
    args = [*command, str(tmp_path / "missing.wav"), "-o", str(tmp_path / "d.bvh"), bad, "0" if bad == "--top-k" else "1e308"]
    args += {"inbetween": ["--start", "x.bvh"], "inpaint": ["--motion", "x.bvh"], "trajectory": ["--path", "x.csv"]}.get(command[0], [])
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "missing.wav" not in err and len(err.strip().splitlines()) == 1


def test_fps_writes_the_same_dance_at_another_rate(tmp_path, tiny_checkpoint):
    common = ["generate", str(SONG), "--checkpoint", str(tiny_checkpoint), "--steps", "2", "--threads", "1"]
    assert main([*common, "-o", str(tmp_path / "d30.bvh")]) == 0
    assert main([*common, "-o", str(tmp_path / "d60.bvh"), "--fps", "60"]) == 0
    assert "Frame Time: 0.01666667" in (tmp_path / "d60.bvh").read_text()
    d30, d60 = read_motion(tmp_path / "d30.bvh"), read_motion(tmp_path / "d60.bvh")
    assert d60.fps == 60 and abs(d60.num_frames - 2 * d30.num_frames) <= 1
    assert np.abs(d60.joint_positions()[::2] - d30.joint_positions()).max() < 0.01
    assert np.abs(np.diff(d60.joint_positions(), axis=0)).max(axis=(1, 2)).min() > 0  # no repeated frame


@pytest.mark.parametrize("command", DANCING)
@pytest.mark.parametrize("fps", ["0", "1000", "nan"])
def test_a_frame_rate_no_file_is_written_at_is_one_line_and_exit_2(tmp_path, capsys, command, fps):
    args = [*command, str(SONG), "-o", str(tmp_path / "d.bvh"), "--fps", fps]
    args += {"inbetween": ["--start", "x.bvh"], "inpaint": ["--motion", "x.bvh"], "trajectory": ["--path", "x.csv"]}.get(command[0], [])
    assert main(args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--fps" in err and not (tmp_path / "d.bvh").exists()


def test_in_place_takes_the_travel_out_of_every_written_file(tmp_path, tiny_checkpoint):
    from choreo.motion.travel import ground_track

    common = ["generate", str(SONG), "--checkpoint", str(tiny_checkpoint), "--steps", "2", "--threads", "1"]
    assert main([*common, "-o", str(tmp_path / "travel.npz")]) == 0
    assert main([*common, "-o", str(tmp_path / "still.npz"), "-o", str(tmp_path / "still.bvh"), "--in-place"]) == 0
    travel = read_motion(tmp_path / "travel.npz")
    moved = ground_track(travel.root_positions, travel.fps)
    assert np.linalg.norm(moved - moved[0], axis=-1).max() > 0.2  # there was travel to take out
    for name in ("still.npz", "still.bvh"):
        still = read_motion(tmp_path / name)
        track = ground_track(still.root_positions, still.fps)
        assert np.linalg.norm(track - track[0], axis=-1).max() <= 0.02, name
        np.testing.assert_allclose(still.root_positions[:, 1], travel.root_positions[:, 1], atol=1e-4)


def test_root_motion_puts_the_travel_on_a_root_bone_in_every_written_file(tmp_path, tiny_checkpoint):
    from choreo.formats import read_bvh_raw

    common = ["generate", str(SONG), "--checkpoint", str(tiny_checkpoint), "--steps", "2", "--threads", "1"]
    assert main([*common, "-o", str(tmp_path / "plain.npz")]) == 0
    assert main([*common, "-o", str(tmp_path / "root.bvh"), "-o", str(tmp_path / "root.glb"), "--root-motion"]) == 0
    plain = read_motion(tmp_path / "plain.npz")
    assert [joint.name for joint in read_bvh_raw(tmp_path / "root.bvh").joints[:2]] == ["root", "pelvis"]
    for name in ("root.bvh", "root.glb"):  # the same dance, read back through the root bone
        assert np.abs(read_motion(tmp_path / name).joint_positions() - plain.joint_positions()).max() < 1e-3, name


@pytest.mark.parametrize("extra, words", [
    (["-o", "d.npz"], "--root-motion applies to .bvh, .glb, .fbx outputs, not .npz"),
    (["-o", "d.bvh", "--in-place"], "--in-place and --root-motion exclude each other"),
])
def test_root_motion_that_cannot_be_written_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, extra, words):
    monkeypatch.chdir(tmp_path)
    assert main(["generate", str(SONG), "--root-motion", *extra]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and words in err and not list(tmp_path.iterdir())


def test_a_loop_says_its_bars_and_refuses_seed_motion(tmp_path, capsys, source):
    assert main(["graph", str(SONG), "-o", str(tmp_path / "idle.npz"), "--loop", "--threads", "1"]) == 0
    err = capsys.readouterr().err
    assert "a loop of" in err and "bars of 4 beats" in err
    assert read_motion(tmp_path / "idle.npz").metadata["loop"]["beats_per_bar"] == 4
    assert main(["generate", str(SONG), "-o", str(tmp_path / "x.bvh"), "--loop", "--seed-motion", str(source)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--loop" in err and not (tmp_path / "x.bvh").exists()
