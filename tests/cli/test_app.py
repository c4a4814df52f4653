"""The `choreo` CLI: help texts, listings, conversions and one-line errors with no partial output."""

from pathlib import Path

import numpy as np
import pytest

from choreo.finishing.speed_limit import REAL_FLOOR_STEP
from choreo.motion import Motion
from tests.helpers import AISTPP_FIXTURES, EXAMPLE_SONG, assert_one_line_error, run_cli

COMMANDS = ["info", "convert", "generators", "prepare", "eval", "train", "generate", "inbetween", "inpaint", "trajectory",
            "render", "graph"]


def write_dance(path, frames=45, fps=30):
    from choreo.formats import write_motion

    rng = np.random.default_rng(0)
    axis_angle = np.cumsum(rng.normal(scale=0.03, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.95, 0]
    motion = Motion.from_axis_angle(root, axis_angle, fps=fps)
    write_motion(motion, path)
    return motion


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_help_with_an_example(capsys, command):
    code, out, _ = run_cli(capsys, command, "--help")
    assert code == 0
    assert "Example" in out and "choreo " + command in out


def test_top_level_help(capsys):
    code, out, _ = run_cli(capsys, "--help")
    assert code == 0 and all(c in out for c in COMMANDS)


def test_generators_lists_both_backends_and_which_is_ready(capsys):
    code, out, _ = run_cli(capsys, "generators")
    assert code == 0
    rows = {line.split("│")[1].strip(): line for line in out.splitlines() if line.count("│") > 2}
    assert "yes" in rows["sgmd"] and "yes" in rows["graph"]


def test_graph_with_the_bundled_models_and_repertoire(tmp_path, capsys):
    from choreo.formats import read_motion

    code, _, err = run_cli(capsys, "graph", EXAMPLE_SONG, "-o", tmp_path / "dance.bvh", "-k", "16")
    assert code == 0, err
    motion = read_motion(tmp_path / "dance.bvh")
    import soundfile as sf

    assert abs(motion.duration - sf.info(str(EXAMPLE_SONG)).duration) < 0.1
    floor_step = np.linalg.norm(np.diff(motion.root_positions[:, [0, 2]], axis=0), axis=-1).max()
    assert floor_step < REAL_FLOOR_STEP + 1e-3  # no teleporting at seams: no faster than real dancers travel (+ BVH rounding)
    code, _, err = run_cli(capsys, "graph", EXAMPLE_SONG, "-o", tmp_path / "x.bvh", "--style", "hip-hop")
    assert code == 2 and "repertoire genre" in err and not (tmp_path / "x.bvh").exists()


def test_generate_with_the_bundled_model_and_no_flags(tmp_path, capsys):
    from choreo.formats import read_motion

    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "dance.bvh", "--steps", "2")
    assert code == 0, err
    motion = read_motion(tmp_path / "dance.bvh")
    import soundfile as sf

    assert motion.fps == 30 and abs(motion.duration - sf.info(str(EXAMPLE_SONG)).duration) < 0.1
    speed = np.linalg.norm(np.diff(motion.joint_positions(), axis=0), axis=-1).mean() * 30
    assert 0.05 < speed < 3.0  # it moves, like a person (metres per second, mean over joints)


def test_info_on_motion(tmp_path, capsys):
    write_dance(tmp_path / "dance.bvh", frames=60)
    code, out, _ = run_cli(capsys, "info", tmp_path / "dance.bvh")
    assert code == 0
    assert "60" in out and "2.00 s" in out and "24" in out


def test_info_on_example_song(capsys):
    code, out, _ = run_cli(capsys, "info", EXAMPLE_SONG)
    assert code == 0
    assert "bpm" in out and "beats" in out
    assert "music           0.00-11.30 s" in out  # the loop's last 0.23 s are its decay (choreo.music.loudness)


def test_convert_bvh_to_npz_and_back(tmp_path, capsys):
    motion = write_dance(tmp_path / "dance.bvh")
    assert run_cli(capsys, "convert", tmp_path / "dance.bvh", tmp_path / "dance.npz")[0] == 0
    assert run_cli(capsys, "convert", tmp_path / "dance.npz", tmp_path / "again.bvh", "--fps", "60")[0] == 0
    from choreo.formats import read_motion

    again = read_motion(tmp_path / "again.bvh")
    assert again.fps == 60 and again.num_frames == 2 * motion.num_frames - 1  # no frame held past the end
    np.testing.assert_allclose(again.joint_positions()[::2], motion.joint_positions(), atol=1e-4)


def test_convert_moves_the_travel_onto_a_root_bone_and_back(tmp_path, capsys):
    motion = write_dance(tmp_path / "dance.bvh")
    assert run_cli(capsys, "convert", tmp_path / "dance.bvh", tmp_path / "root.bvh", "--root-motion", "--rig", "mixamo")[0] == 0
    assert "ROOT root\n" in (tmp_path / "root.bvh").read_text()
    assert run_cli(capsys, "convert", tmp_path / "root.bvh", tmp_path / "back.npz")[0] == 0
    from choreo.formats import read_motion

    np.testing.assert_allclose(read_motion(tmp_path / "back.npz").joint_positions(), motion.joint_positions(), atol=1e-4)
    code, _, err = run_cli(capsys, "convert", tmp_path / "dance.bvh", tmp_path / "root.npy", "--root-motion")
    assert code == 2 and "--root-motion applies to" in err and not (tmp_path / "root.npy").exists()


def test_convert_to_stdout(tmp_path, capsys):
    write_dance(tmp_path / "dance.bvh")
    code, out, _ = run_cli(capsys, "convert", tmp_path / "dance.bvh", "-", "--format", "bvh")
    assert code == 0 and out.startswith("HIERARCHY")


def test_non_audio_file_is_one_line_error(tmp_path, capsys):
    fake = tmp_path / "song.mp3"
    fake.write_text("this is not audio\n" * 50)
    assert_one_line_error(*run_cli(capsys, "info", fake)[::2])


def test_truncated_bvh_is_one_line_error_and_writes_nothing(tmp_path, capsys):
    write_dance(tmp_path / "dance.bvh")
    text = (tmp_path / "dance.bvh").read_text()
    (tmp_path / "cut.bvh").write_text(text[: int(len(text) * 0.8)])
    code, _, err = run_cli(capsys, "convert", tmp_path / "cut.bvh", tmp_path / "out.npz")
    assert_one_line_error(code, err)
    assert not (tmp_path / "out.npz").exists()


def test_output_in_missing_folder_is_one_line_error(tmp_path, capsys):
    write_dance(tmp_path / "dance.bvh")
    code, _, err = run_cli(capsys, "convert", tmp_path / "dance.bvh", tmp_path / "nowhere" / "out.bvh")
    assert_one_line_error(code, err, exit_code=3)  # an output that cannot be written
    assert not (tmp_path / "nowhere").exists()


def test_missing_input_and_unknown_command(tmp_path, capsys):
    assert_one_line_error(*run_cli(capsys, "info", tmp_path / "absent.bvh")[::2])
    code, _, _ = run_cli(capsys, "no-such-command")
    assert code == 2  # a usage error, as the README's table says


@pytest.mark.skipif(not AISTPP_FIXTURES.is_dir(), reason="AIST++ fixtures not generated")
def test_prepare_summarises_a_dataset(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path / "cache"))
    code, out, _ = run_cli(capsys, "prepare", AISTPP_FIXTURES, "--stride", "1")
    assert code == 0
    assert "clips" in out and "windows" in out


def test_motion_commands_read_a_pipe(tmp_path):
    # `choreo generate song -o - -f npz | choreo render - ...`: a real pipe between two processes.
    import subprocess
    import sys

    from choreo.formats import read_motion

    dance = write_dance(tmp_path / "d.bvh")
    choreo = [sys.executable, "-m", "choreo"]
    piped = subprocess.run(choreo + ["convert", tmp_path / "d.bvh", "-", "-f", "npz"], capture_output=True, check=True).stdout
    result = subprocess.run(choreo + ["convert", "-", tmp_path / "back.json"], input=piped, capture_output=True)
    assert result.returncode == 0, result.stderr
    np.testing.assert_allclose(read_motion(tmp_path / "back.json").joint_positions(), dance.joint_positions(), atol=2e-3)


@pytest.mark.parametrize("format", ["npz", "bvh", "json", "glb", "pkl"])
def test_piped_motion_is_read_in_the_format_its_bytes_show(tmp_path, monkeypatch, format):
    import io
    import sys

    from choreo.formats import read_motion, write_motion

    dance = write_dance(tmp_path / "d.bvh")
    write_motion(dance, tmp_path / f"d.{format}")
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO((tmp_path / f"d.{format}").read_bytes())))
    back = read_motion("-")
    tolerance = 2e-3 if format == "bvh" else 1e-4  # BVH stores degrees with 6 decimals
    assert back.num_frames == dance.num_frames  # (an AIST++ pkl has no frame rate: read as 60 fps, frames as written)
    np.testing.assert_allclose(back.joint_positions(), dance.joint_positions(), atol=tolerance)
    assert not list(Path(tmp_path).glob("choreo-stdin-*"))


@pytest.mark.parametrize("piped,message", [(b"", "no motion on stdin"), (b"Hello, world", "cannot tell the format")])
def test_a_pipe_without_a_motion_is_one_line_error(capsys, monkeypatch, piped, message):
    import io
    import sys

    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(piped)))
    code, _, err = run_cli(capsys, "info", "-")
    assert_one_line_error(code, err)
    assert message in err


def test_render_writes_an_html_preview(capsys, tmp_path):
    write_dance(tmp_path / "d.bvh")
    code, _, err = run_cli(capsys, "render", tmp_path / "d.bvh", "--music", EXAMPLE_SONG, "-o", tmp_path / "p.html")
    assert code == 0, err
    page = (tmp_path / "p.html").read_text()
    assert page.startswith("<!DOCTYPE html>") and "data:audio/wav;base64," in page
    assert not list(tmp_path.glob("*.tmp*"))


def test_numpy_runtime_warnings_stay_off_stderr(capsys, monkeypatch, tmp_path):
    # A successful run prints its result, not numpy's overflow notes; CHOREO_DEBUG shows them again.
    import choreo.formats

    write_dance(tmp_path / "d.bvh")
    original = choreo.formats.read_motion

    def noisy_read(path, *args, **kwargs):
        np.float32(3e38) * np.float32(10)  # RuntimeWarning: overflow encountered in scalar multiply
        return original(path, *args, **kwargs)

    monkeypatch.setattr(choreo.formats, "read_motion", noisy_read)
    import warnings

    for debug, shown in (("", 0), ("1", 1)):
        monkeypatch.setenv("CHOREO_DEBUG", debug)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            code, _, err = run_cli(capsys, "info", tmp_path / "d.bvh")
        assert code == 0 and err == ""
        assert sum(issubclass(w.category, RuntimeWarning) for w in caught) == shown


@pytest.mark.parametrize("flag,value", [("--turns", "0,ninety"), ("--stretch", "1,fast")])
def test_train_number_lists_are_refused_in_one_line_naming_the_flag(capsys, tmp_path, flag, value):
    code, _, err = run_cli(capsys, "train", "sgmd", "--data", tmp_path, "--out", tmp_path / "run", flag, value)
    assert_one_line_error(code, err)
    assert flag in err and repr(value) in err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("flag,value", [("--turns", "90"), ("--config", "cpu"), ("--prompt", "description"),
                                        ("--checkpoint-every", "10")])
def test_graph_training_refuses_sgmd_flags_even_at_their_sgmd_defaults(capsys, tmp_path, flag, value):
    code, _, err = run_cli(capsys, "train", "graph", "--data", tmp_path, "--out", tmp_path / "run", flag, value)
    assert_one_line_error(code, err)
    assert code == 2 and f"No such option: {flag}" in err  # graph's training command has no sgmd flag
    assert not (tmp_path / "run").exists()


def test_graph_training_refuses_resume_before_any_work(capsys, tmp_path):
    code, _, err = run_cli(capsys, "train", "graph", "--data", tmp_path, "--out", tmp_path / "run", "--resume")
    assert_one_line_error(code, err)
    assert "cannot resume" in err and not (tmp_path / "run").exists()


@pytest.mark.parametrize("where", ["out", "out/inside"])
def test_train_refuses_an_out_that_is_a_file_before_loading_any_data(capsys, tmp_path, where):
    (tmp_path / "out").write_bytes(b"a file")
    (tmp_path / "data").mkdir()  # empty: loading it would be a dataset error, not this one
    code, _, err = run_cli(capsys, "train", "sgmd", "--data", tmp_path / "data", "--out", tmp_path / where)
    assert_one_line_error(code, err, exit_code=3)
    assert "exists and is not a folder" in err and (tmp_path / "out").read_bytes() == b"a file"


# Issue 48, items 10 and 12: numbers that overflowed (exit 70) or slipped past a bound ---------------

@pytest.mark.parametrize("fps, words", [("inf", "--fps takes a finite number"), ("nan", "--fps takes a finite number"),
                                        ("1e6", "--fps must be 10 to 240"), ("1000", "--fps must be 10 to 240"), ("0_5", "--fps takes a finite number")])
def test_convert_fps_is_bounded_before_resampling(tmp_path, capsys, fps, words):
    write_dance(tmp_path / "dance.npz")
    code, _, err = run_cli(capsys, "convert", tmp_path / "dance.npz", tmp_path / "out.bvh", "--fps", fps)
    assert_one_line_error(code, err)
    assert words in err and not (tmp_path / "out.bvh").exists()


@pytest.mark.parametrize("seed, words", [("1" + "0" * 30, "--seed must be"), ("1e30", "--seed takes a whole number"),
                                         ("9" * 5000, "--seed takes a whole number"), ("\uff17", "--seed takes a whole number")])
@pytest.mark.parametrize("command", ["generate", "graph"])
def test_seeds_past_the_backends_range_are_refused_by_name(tmp_path, capsys, command, seed, words):
    code, _, err = run_cli(capsys, command, EXAMPLE_SONG, "-o", tmp_path / "dance.bvh", "--seed", seed)
    assert_one_line_error(code, err)
    assert words in err and len(err) < 120 and not (tmp_path / "dance.bvh").exists()


@pytest.mark.parametrize("threads, words", [("-3", "--threads must be at least 1"), ("0", "--threads must be at least 1"),
                                            ("1.5", "--threads takes a whole number")])
@pytest.mark.parametrize("command", ["generate", "graph"])
def test_thread_counts_below_one_are_refused_by_name(tmp_path, capsys, command, threads, words):
    code, _, err = run_cli(capsys, command, EXAMPLE_SONG, "-o", tmp_path / "dance.bvh", f"--threads={threads}")
    assert_one_line_error(code, err)
    assert words in err and not (tmp_path / "dance.bvh").exists()


@pytest.mark.parametrize("flags, words", [(("--guidance", "nan"), "--guidance takes a finite number"),
                                          (("--guidance", "inf"), "--guidance takes a finite number"),
                                          (("--guidance", "1e308"), "guidance must be 0 to 20"),
                                          (("--style-guidance", "nan"), "--style-guidance takes a finite number")])
def test_guidance_is_checked_before_the_dance(tmp_path, capsys, monkeypatch, flags, words):
    import choreo.music

    monkeypatch.setattr(choreo.music.Music, "from_file", lambda *a, **k: pytest.fail("analysed before the check"))
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "dance.bvh", *flags)
    assert_one_line_error(code, err)
    assert words in err and not (tmp_path / "dance.bvh").exists()


@pytest.mark.parametrize("flags, words", [(("--sampler", "ddpm", "--steps", "10"), "ddpm runs all 1000 steps"),
                                          (("--steps", "1001"), "steps must be 1 to 1000"),
                                          (("--steps", "9223372036854775808"), "steps must be 1 to 100,000")])
@pytest.mark.parametrize("command", ["generate", "inbetween", "inpaint", "trajectory"])
def test_steps_are_checked_before_the_song_is_analysed(tmp_path, capsys, monkeypatch, command, flags, words):
    """Issue 48, item 8: these were exit 70 once the song had been analysed."""
    import choreo.music

    monkeypatch.setattr(choreo.music.Music, "from_file", lambda *a, **k: pytest.fail("analysed before the check"))
    given = {"inbetween": ("--key", "1=pose.bvh"), "inpaint": ("--motion", "dance.bvh"), "trajectory": ("--path", "p.csv")}
    code, _, err = run_cli(capsys, command, EXAMPLE_SONG, "-o", tmp_path / "out.bvh", *given.get(command, ()), *flags)
    assert_one_line_error(code, err)
    assert words in err and not (tmp_path / "out.bvh").exists()


def test_a_checkpoint_that_is_a_folder_says_so(tmp_path, capsys):
    (tmp_path / "weights").mkdir()
    code, _, err = run_cli(capsys, "generate", EXAMPLE_SONG, "-o", tmp_path / "dance.bvh", "--checkpoint", tmp_path / "weights")
    assert_one_line_error(code, err)
    assert "is a folder, expected a file" in err and "does not exist" not in err


def _commands(group, path=()):
    """(path, click command) for every command and subcommand of the app."""
    import click

    for name, command in getattr(group, "commands", {}).items():
        yield (*path, name), command
        if isinstance(command, click.Group):
            yield from _commands(command, (*path, name))


def test_every_bracket_in_help_reaches_the_screen(monkeypatch, capsys):
    """Help is rich markup: `pip install "choreo[madmom]"` lost its `[madmom]` (issue 47). Every
    bracketed text of every option's help and every command's docstring must be shown."""
    import re

    import typer

    from choreo.cli.app import app

    monkeypatch.setenv("COLUMNS", "400")  # no wrapping inside a bracket
    checked = 0
    for path, command in _commands(typer.main.get_command(app)):
        texts = [command.help or ""] + [getattr(p, "help", None) or "" for p in command.params]
        wanted = [b.replace("\\[", "[") for t in texts for b in re.findall(r"\\?\[[^\]\n]*\]", t)]
        if not wanted:
            continue
        code, out, _ = run_cli(capsys, *path, "--help")
        shown = " ".join(out.split())
        assert code == 0
        for bracket in wanted:
            assert " ".join(bracket.split()) in shown, (path, bracket)
            checked += 1
    assert checked >= 3


@pytest.mark.parametrize("args", [["generate", "x.wav", "--bogus"], ["generate", "x.wav", "--steps=abc"],
                                  ["frobnicate"], ["generate"]])
def test_usage_errors_are_one_line_naming_the_help(capsys, args):
    """click's usage errors printed a usage block, a hint and the error (four lines): one line now,
    like every other bad input (README, "Errors and exit codes")."""
    code, out, err = run_cli(capsys, *args)
    assert_one_line_error(code, err)
    assert "--help" in err and out == ""
