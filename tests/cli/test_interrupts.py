"""Tests of choreo.cli.interrupts: issue 38, items 1 and 2: Ctrl-C and SIGTERM end every command with 130 / 143 and one line on
stderr, and leave no output, no temporary file and no child process (ffmpeg, Blender) behind.

Each test starts choreo in a child process, waits until it is provably at work (its stdin read,
its encoder or Blender started), sends the signal to choreo alone (not to its children, as
`kill` or a job scheduler does) and checks what is left.


Markers say where a test came from: hardening (pyproject.toml, tests/README.md)."""

import fcntl
import os
import signal
import subprocess
import sys
import termios
import time
from pathlib import Path

import numpy as np
import pytest

from choreo.formats import write_motion
from choreo.motion import Motion

SIGNALS = [(signal.SIGINT, 130), (signal.SIGTERM, 143)]


def dance(frames: int) -> Motion:
    rng = np.random.default_rng(0)
    axis_angle = np.cumsum(rng.normal(scale=0.02, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.95, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=30.0)


def start(args, cwd: Path, env=None) -> subprocess.Popen:
    """choreo in a child whose Ctrl-C is live: pytest itself may run with SIGINT ignored (started in
    the background by a script, as `nohup ... &` does), and choreo rightly leaves it ignored then."""
    return subprocess.Popen([sys.executable, "-m", "choreo", *map(str, args)], cwd=cwd, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env={**os.environ, **(env or {})},
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def wait_for(condition, what: str, timeout: float = 120.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = condition()
        if found:
            return found
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def unread_bytes(pipe) -> int:
    """Bytes written to ``pipe`` that the reader has not taken yet (FIONREAD works on either end)."""
    count = np.zeros(1, dtype=np.int32)
    fcntl.ioctl(pipe.fileno(), termios.FIONREAD, count)
    return int(count[0])


def children_of(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def running(pid: int) -> bool:
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def finish(process: subprocess.Popen, timeout: float = 60.0) -> tuple[int, list[str]]:
    """Exit code and stderr lines; a hang (the bug of waiting on a child) fails the test."""
    _, err = process.communicate(timeout=timeout)
    return process.returncode, [line for line in err.decode(errors="replace").splitlines() if line.strip()]


def assert_interrupted(code, lines, expected, signum):
    assert code == expected, lines
    assert len(lines) == 1 and lines[0] == f"choreo: error: interrupted ({signal.Signals(signum).name})", lines


@pytest.mark.hardening
@pytest.mark.parametrize("signum, expected", SIGNALS)
@pytest.mark.parametrize("command", [["info", "-"], ["convert", "-", "out.bvh"], ["render", "-", "-o", "out.png"]])
def test_a_signal_while_reading_stdin_exits_128_plus_signal_with_one_line(tmp_path, command, signum, expected):
    process = start(command, tmp_path)
    process.stdin.write(b"HIERARCHY\nROOT pelvis\n")  # half a BVH: choreo reads on, waiting for the rest
    process.stdin.flush()
    wait_for(lambda: unread_bytes(process.stdin) == 0, "choreo to read its stdin")
    process.send_signal(signum)
    code, lines = finish(process)
    assert_interrupted(code, lines, expected, signum)
    assert list(tmp_path.iterdir()) == []  # no output, no temporary


@pytest.mark.hardening
@pytest.mark.parametrize("signum, expected", SIGNALS)
def test_a_signal_during_a_video_render_ends_ffmpeg_and_leaves_no_temporary(tmp_path, signum, expected):
    pytest.importorskip("imageio_ffmpeg", reason="video previews need imageio-ffmpeg")
    write_motion(dance(9000), tmp_path / "dance.npz")
    process = start(["render", "dance.npz", "-o", "out.mp4", "--size", "320x240"], tmp_path)
    def encoding():
        return any(p.name.endswith(".tmp.mp4") for p in tmp_path.iterdir()) and children_of(process.pid)

    encoder = wait_for(encoding, "ffmpeg to start")[0]
    process.send_signal(signum)
    code, lines = finish(process)
    assert_interrupted(code, lines, expected, signum)
    assert not running(encoder)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dance.npz"]


@pytest.mark.hardening
@pytest.mark.parametrize("signum, expected", SIGNALS)
def test_a_signal_during_fbx_export_ends_blender_and_removes_its_folder(tmp_path, signum, expected):
    bin_folder, scratch = tmp_path / "bin", tmp_path / "scratch"
    bin_folder.mkdir()
    scratch.mkdir()
    blender = bin_folder / "blender"  # a Blender that never finishes: choreo must end it
    blender.write_bytes(b"#!/bin/sh\nexec sleep 600\n")
    blender.chmod(0o755)
    write_motion(dance(30), tmp_path / "dance.bvh")
    process = start(["convert", "dance.bvh", "out.fbx"], tmp_path,
                    env={"PATH": f"{bin_folder}{os.pathsep}{os.environ['PATH']}", "TMPDIR": str(scratch)})
    child = wait_for(lambda: children_of(process.pid), "Blender to start")[0]
    wait_for(lambda: any(p.name.startswith("choreo-fbx-") for p in scratch.iterdir()), "the FBX folder")
    process.send_signal(signum)
    code, lines = finish(process)
    assert_interrupted(code, lines, expected, signum)
    assert not running(child)
    assert list(scratch.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin", "dance.bvh", "scratch"]


@pytest.mark.hardening
def test_an_ignored_sigint_stays_ignored_and_a_third_signal_ends_choreo_at_once():
    """`choreo ... &` in a script ignores Ctrl-C, as every program started so must; and if the
    unwinding after a signal ever hung, repeating the signal still ends choreo."""
    from choreo.cli.interrupts import Interrupted, signals_raise

    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with signals_raise():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            assert signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL
    finally:
        signal.signal(signal.SIGINT, before)
    with pytest.raises(Interrupted), signals_raise() as received:
        handler = signal.getsignal(signal.SIGTERM)
        handler(signal.SIGTERM, None)
    assert received.signum == signal.SIGTERM and received.exit_code == 143
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # put back


@pytest.mark.hardening
@pytest.mark.parametrize("gap", [0.0, 0.05])
def test_int_then_term_while_four_outputs_are_written_leave_none_of_them(tmp_path, gap):
    """Round five, item 3: SIGINT after the first temporary file appears, then SIGTERM while the
    first one unwinds: the second is ignored, every temporary removed, exit 130 with one line."""
    song = Path(__file__).parents[2] / "examples" / "drum_and_bass_174bpm.wav"
    outputs = [f"B.{ext}" for ext in ("bvh", "npz", "json", "glb")]
    process = start(["generate", song, *(a for o in outputs for a in ("-o", o)), "--fps", "240", "--steps", "2",
                     "--threads", "1"], tmp_path)
    wait_for(lambda: any(p.name.startswith(".B.") for p in tmp_path.iterdir()), "the first temporary file")
    process.send_signal(signal.SIGINT)
    time.sleep(gap)
    process.send_signal(signal.SIGTERM)
    code, lines = finish(process)
    if code == 0:  # the signals came after the last output was in place: nothing to clean up
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted(outputs)
        return
    assert_interrupted(code, lines, 130, signal.SIGINT)
    assert list(tmp_path.iterdir()) == []
