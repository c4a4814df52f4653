"""Issue 59, items 5, 6 and 11: closed and full standard streams, and a signal while Python exits.
Each case is a fresh process with the stream closed (``>&-``) or on /dev/full."""

import os
import subprocess
import sys

import numpy as np
import pytest
import soundfile as sf

from choreo.formats import write_motion
from choreo.motion import Motion

FULL = "/dev/full"


def choreo(*args, close=None, stdout=None, cwd=None):
    """``python -m choreo ARGS`` with descriptor ``close`` closed, or stdout to the file ``stdout``."""
    out = open(stdout, "w") if stdout else subprocess.PIPE
    try:
        return subprocess.run([sys.executable, "-m", "choreo", *map(str, args)], stdout=out, stderr=subprocess.PIPE,
                              preexec_fn=(lambda: os.close(close)) if close is not None else None, cwd=cwd,
                              timeout=300)
    finally:
        if stdout:
            out.close()


@pytest.fixture
def dance_file(tmp_path):
    write_motion(Motion.from_axis_angle(np.zeros((30, 3)) + [0, 0.9, 0], np.zeros((30, 24, 3))), tmp_path / "a.npz")
    return tmp_path / "a.npz"


def one_line(stderr: bytes) -> str:
    lines = [line for line in stderr.decode().splitlines() if line.strip()]
    assert len(lines) == 1, stderr
    return lines[0]


@pytest.mark.parametrize("args", [["convert", "{a}", "-", "-f", "json"], ["info", "{a}"]])
def test_a_closed_stdout_is_an_output_error(dance_file, args):
    result = choreo(*[arg.format(a=dance_file) for arg in args], close=1)
    assert result.returncode == 3 and "cannot write to standard output: it is closed" in one_line(result.stderr)


@pytest.mark.skipif(not os.path.exists(FULL), reason="no /dev/full")
@pytest.mark.parametrize("args", [["convert", "{a}", "-", "-f", "json"], ["info", "{a}"]])
def test_a_full_stdout_is_an_output_error(dance_file, args):
    result = choreo(*[arg.format(a=dance_file) for arg in args], stdout=FULL)
    assert result.returncode == 3 and "No space left on device" in one_line(result.stderr)


@pytest.fixture
def song(tmp_path):
    path = tmp_path / "s.wav"
    sf.write(path, 0.3 * np.sin(2 * np.pi * 220 * np.arange(3 * 22050) / 22050), 22050)
    return path


def test_a_closed_stderr_does_not_fail_a_good_song(song, tiny_checkpoint, tmp_path):
    common = ["--checkpoint", tiny_checkpoint, "--steps", "1", "--threads", "1"]
    closed = choreo("generate", song, "-o", tmp_path / "closed.bvh", *common, close=2)
    assert closed.returncode == 0 and closed.stdout == b""  # was exit 2, "decoding failed", on stdout
    assert choreo("generate", song, "-o", tmp_path / "open.bvh", *common).returncode == 0
    assert (tmp_path / "closed.bvh").read_bytes() == (tmp_path / "open.bvh").read_bytes()


@pytest.mark.skipif(not os.path.exists(FULL), reason="no /dev/full")
def test_a_summary_lost_to_a_full_stdout_is_exit_3_after_the_dance(song, tiny_checkpoint, tmp_path):
    result = choreo("generate", song, "--out-dir", tmp_path / "out", "--json", "--checkpoint", tiny_checkpoint,
                    "--steps", "1", stdout=FULL)
    assert result.returncode == 3 and "No space left on device" in result.stderr.decode().splitlines()[-1]
    assert (tmp_path / "out" / "s.bvh").is_file()  # the dance itself was written


def test_a_signal_while_python_exits_is_ignored():
    """SIGINT just after the dance was written raised inside an exit handler: an 11-line traceback."""
    code = ("import atexit, os, signal, time\n"
            "from choreo.cli import ignore_signals_at_exit\n"
            "atexit.register(lambda: os.kill(os.getpid(), signal.SIGINT) or time.sleep(0.1))\n"
            "ignore_signals_at_exit()\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=60)
    assert result.returncode == 0 and result.stderr == b""
