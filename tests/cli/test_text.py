"""Issue 38, item 6 (and 8's non-UTF-8 names): text that comes from files and names is printed as
text. Rich markup in it is not interpreted (``[/x]`` used to crash with exit 70), terminal
controls (ESC, OSC, C1, bidi overrides) never reach the terminal, an error stays one line when a
path holds a newline, and in a batch one such song neither stops the others nor loses --json."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from choreo.cli import main
from choreo.cli.text import markup, plain
from choreo.formats import write_motion
from choreo.motion import Motion

HOSTILE = "[/x][red]\x1b]0;owned\x07\x1b[2J\x9b31m\u202eevil\n"  # markup, OSC, CSI, C1 CSI, bidi, newline


NAME = HOSTILE.replace("/", "")  # as a file name


RAW_CONTROLS = ("\x1b", "\x07", "\x9b", "\u202e")


def dance(frames: int = 10) -> Motion:
    rng = np.random.default_rng(2)
    axis_angle = np.cumsum(rng.normal(scale=0.02, size=(frames, 24, 3)), axis=0)
    return Motion.from_axis_angle(np.zeros((frames, 3)) + [0, 0.95, 0], axis_angle, fps=30.0)


def run(capsys, *args):
    code = main(list(map(str, args)))
    out, err = capsys.readouterr()
    return code, out, err


def assert_inert(*texts):
    for text in texts:
        assert not any(control in text for control in RAW_CONTROLS), repr(text)


def hostile_path(folder: Path, suffix: str) -> Path:
    """A path that holds markup (``[/x]`` across its folders), controls and a newline."""
    (folder / "songs[").mkdir()
    return folder / "songs[" / f"x]{NAME}{suffix}"


@pytest.mark.hardening
def test_plain_shows_every_control_as_an_escape_on_one_line():
    assert plain("a\x1b[31mb\nc\td\x00\x7f\x85\x9b") == "a\\x1b[31mb\\nc\\td\\x00\\x7f\\x85\\x9b"
    assert plain("\u2028\u202e\u2066") == "\\u2028\\u202e\\u2066"
    assert plain(os.fsdecode(b"dance\xff\xfe.bvh")) == "dance\\xff\\xfe.bvh"  # a name that is not UTF-8
    assert plain("tänzer – ok [x]") == "tänzer – ok [x]"  # printable text is left alone


@pytest.mark.hardening
def test_markup_prints_back_exactly_as_plain_text():
    from rich.console import Console

    console = Console(record=True, width=500, color_system=None)
    console.print(markup(HOSTILE), highlight=False, end="")
    assert console.export_text() == plain(HOSTILE)


@pytest.mark.hardening
def test_info_prints_hostile_file_and_joint_names_as_text(tmp_path, capsys):
    motion = dance()
    path = hostile_path(tmp_path, ".json")
    write_motion(motion, path)
    document = json.loads(path.read_text())
    document["joint_names"][:2] = [HOSTILE, "l_hip[/bold]"]
    path.write_text(json.dumps(document))
    code, out, err = run(capsys, "info", path)
    assert code == 0, err
    assert "[/x][red]" in out and "l_hip[/bold]" in out and "\\x1b]0;owned\\x07" in out
    assert_inert(out, err)


@pytest.mark.hardening
def test_an_error_about_a_hostile_path_is_one_inert_line(tmp_path, capsys):
    for args in (["info", tmp_path / f"missing{HOSTILE}.bvh"], ["convert", tmp_path / f"{HOSTILE}.bvh", "out.bvh"],
                 ["render", tmp_path / f"{HOSTILE}.bvh", "-o", "out.png"]):
        code, out, err = run(capsys, *args)
        assert code == 2 and out == "" and len(err.splitlines()) == 1 and err.startswith("choreo: error: "), err
        assert_inert(err)


@pytest.mark.hardening
def test_a_convert_to_a_hostile_name_says_so_in_one_line(tmp_path, capsys):
    source = tmp_path / "a.bvh"
    write_motion(dance(), source)
    target = hostile_path(tmp_path, ".npz")
    code, out, err = run(capsys, "convert", source, target)
    assert code == 0 and target.is_file(), err
    assert len(err.splitlines()) == 1 and "songs[/x][x][red]" in err
    assert_inert(err)


@pytest.mark.hardening
def test_info_of_a_motion_whose_name_is_not_utf8_on_a_strict_stdout(tmp_path):
    path = Path(os.fsdecode(bytes(tmp_path) + b"/dance\xff.bvh"))
    write_motion(dance(), path)
    done = subprocess.run([sys.executable, "-m", "choreo", "info", path], capture_output=True,
                          env={**os.environ, "PYTHONIOENCODING": "utf-8:strict", "COLUMNS": "300"})
    assert done.returncode == 0, done.stderr
    assert b"dance\\xff.bvh" in done.stdout


@pytest.mark.hardening
def test_a_hostile_song_in_a_batch_fails_alone_and_the_json_summary_lists_every_song(tmp_path, capsys):
    import soundfile

    bad = hostile_path(tmp_path, ".wav")
    bad.write_bytes(b"RIFF\x00\x00\x00\x00WAVEnot audio")
    good = tmp_path / "good[red].wav"
    seconds = np.arange(6 * 22050) / 22050
    soundfile.write(good, 0.3 * np.sin(2 * np.pi * 220 * seconds) * (np.sin(2 * np.pi * 2 * seconds) > 0), 22050)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    code, out, err = run(capsys, "generate", bad, good, "--out-dir", out_dir, "--json", "--steps", "2")
    assert code == 1, err
    summary = json.loads(out)
    assert [song["ok"] for song in summary["songs"]] == [False, True] and summary["failed"] == 1
    assert summary["songs"][0]["song"] == str(bad) and summary["songs"][0]["exit_code"] == 2
    assert (out_dir / "good[red].bvh").is_file()
    assert "good[red].bvh" in err and "songs[/x][x][red]" in err
    assert_inert(err)
    assert len([line for line in err.splitlines() if line.strip()]) == 3  # failed, wrote, the summary's error


@pytest.mark.hardening
def test_a_song_whose_name_is_not_utf8_is_read(tmp_path, capsys):
    import soundfile as sf

    name = os.path.join(os.fsencode(tmp_path), b"song\xff.wav")
    clicks = np.zeros(22050 * 4, np.float32)
    clicks[:: 11025] = 1.0  # a click every half second
    sf.write(name, clicks, 22050)
    code, out, err = run(capsys, "info", os.fsdecode(name))
    assert code == 0, err
    assert "120 at 30 fps" in out  # 4 s of it analysed


def assert_strict_json(text: str):
    """What a strict parser takes: UTF-8, and no escaped lone surrogate (``\\udcff``) anywhere."""
    import re

    text.encode("utf-8")
    assert not re.search(r"\\u[dD][89a-fA-F][0-9a-fA-F]{2}", text), text
    return json.loads(text)


@pytest.mark.hardening
def test_json_outputs_write_a_name_that_is_not_utf8_as_escaped_bytes(tmp_path, capsys):
    """Round five, item 15: --json (and every JSON that names a file: motion JSON, NPZ and glb
    metadata, eval --json) wrote the lone surrogates Python decodes a non-UTF-8 byte to (``\\udcff``),
    which strict JSON parsers refuse; such bytes are now ``\\xNN``, as choreo prints them."""
    import soundfile

    song = Path(os.fsdecode(os.path.join(os.fsencode(tmp_path), b"song\xff.wav")))
    seconds = np.arange(6 * 22050) / 22050
    soundfile.write(os.fsencode(song), 0.3 * np.sin(2 * np.pi * 220 * seconds) * (np.sin(2 * np.pi * 2 * seconds) > 0),
                    22050)
    bad = Path(os.fsdecode(os.path.join(os.fsencode(tmp_path), b"bad\xfe.wav")))
    bad.write_bytes(b"RIFF\x00\x00\x00\x00WAVEnot audio")
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    code, out, err = run(capsys, "generate", song, bad, "--out-dir", out_dir, "--json", "--steps", "2", "-f", "npz")
    assert code == 1, err
    summary = assert_strict_json(out)
    escaped = os.fsencode(tmp_path).decode("utf-8", "backslashreplace")
    assert summary["songs"][0]["song"] == f"{escaped}/song\\xff.wav"
    assert summary["songs"][0]["outputs"] == [f"{escaped}/out/song\\xff.npz"]
    assert summary["songs"][1]["song"] == f"{escaped}/bad\\xfe.wav" and "bad\\xfe.wav" in summary["songs"][1]["error"]
    dance_ = dance()
    dance_.metadata = {"source": os.fsdecode(b"take\xff.bvh"), os.fsdecode(b"key\xfe"): [os.fsdecode(b"\xfd")]}
    for kind in ("json", "npz", "glb"):
        write_motion(dance_, tmp_path / f"dance.{kind}")
    assert_strict_json((tmp_path / "dance.json").read_text())["metadata"] == \
        {"source": "take\\xff.bvh", "key\\xfe": ["\\xfd"]}
    assert_strict_json(str(np.load(tmp_path / "dance.npz")["metadata"]))["key\\xfe"] == ["\\xfd"]
    glb = (tmp_path / "dance.glb").read_bytes()
    length = int.from_bytes(glb[12:16], "little")
    assert assert_strict_json(glb[20:20 + length].decode())["extras"]["metadata"]["source"] == "take\\xff.bvh"
    (tmp_path / "gen").mkdir()
    write_motion(dance(40), Path(os.fsdecode(os.path.join(os.fsencode(tmp_path), b"gen/a\xff.npz"))))
    code, _, err = run(capsys, "eval", tmp_path / "gen", "--gt", tmp_path / "gen", "--json", tmp_path / "scores.json")
    assert code == 0, err
    text = (tmp_path / "scores.json").read_text()
    assert_strict_json(text)
    assert r'"name": "a\\xff"' in text  # the clip's name: a backslash, escaped in JSON, then xff
