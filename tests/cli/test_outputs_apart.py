"""Issue 59, items 1 and 12: an output never writes over an input or another output; --out-dir is
made when missing. Every refusal comes before any work: exit 2, one line, the inputs untouched."""

import os

import numpy as np
import pytest
import soundfile as sf

from choreo.formats import write_motion
from choreo.motion import Motion
from tests.helpers import assert_one_line_error, run_cli


@pytest.fixture
def files(tmp_path):
    song = tmp_path / "s.wav"
    sf.write(song, 0.3 * np.sin(2 * np.pi * 220 * np.arange(3 * 22050) / 22050), 22050)
    dance = Motion.from_axis_angle(np.zeros((60, 3)) + [0, 0.9, 0], np.zeros((60, 24, 3)))
    write_motion(dance, tmp_path / "d.npz")
    (tmp_path / "beats.csv").write_text("0.5\n1.0\n1.5\n2.0\n")
    os.link(song, tmp_path / "hard.wav")
    (tmp_path / "soft.wav").symlink_to(song)
    return tmp_path


def refused(capsys, files, *args, words="also an input"):
    before = {p.name: p.read_bytes() for p in files.iterdir() if p.is_file()}
    code, _, err = run_cli(capsys, *args)
    assert_one_line_error(code, err)
    assert words in err
    assert {p.name: p.read_bytes() for p in files.iterdir() if p.is_file()} == before


@pytest.mark.parametrize("output", ["s.wav", "hard.wav", "soft.wav", "./s.wav"])
def test_the_song_is_never_overwritten_by_its_own_dance(capsys, files, tiny_checkpoint, output):
    refused(capsys, files, "generate", files / "s.wav", "-o", files / output, "-f", "bvh", "--checkpoint", tiny_checkpoint)


def test_no_input_is_overwritten(capsys, files, tiny_checkpoint):
    song, common = files / "s.wav", ["--checkpoint", tiny_checkpoint]
    refused(capsys, files, "generate", song, "-o", files / "beats.csv", "-f", "bvh", "--beats", files / "beats.csv", *common)
    refused(capsys, files, "generate", song, "-o", files / "d.npz", "--seed-motion", files / "d.npz", *common)
    refused(capsys, files, "inpaint", song, "--motion", files / "d.npz", "-o", files / "d.npz", *common)
    refused(capsys, files, "inbetween", song, "--key", f"1={files / 'd.npz'}@3", "-o", files / "d.npz", *common)
    refused(capsys, files, "trajectory", song, "--path", files / "d.npz", "-o", files / "d.npz", *common)
    refused(capsys, files, "convert", files / "d.npz", files / "d.npz")


def test_two_outputs_that_are_one_file_are_refused(capsys, files, tiny_checkpoint):
    refused(capsys, files, "generate", files / "s.wav", "-o", files / "a.bvh", "-o", f"{files}/./a.bvh",
            "--checkpoint", tiny_checkpoint, words="are one file")


def test_out_dir_is_made_with_its_parents(capsys, files, tiny_checkpoint):
    out = files / "new" / "deeper"
    code, _, err = run_cli(capsys, "generate", files / "s.wav", "--out-dir", out, "--checkpoint", tiny_checkpoint,
                           "--steps", "1")
    assert code == 0, err
    assert (out / "s.bvh").is_file()
