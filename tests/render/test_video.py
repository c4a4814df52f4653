"""Tests of choreo.render.video.

Markers say where a test came from: hardening (pyproject.toml, tests/README.md)."""

import subprocess
from pathlib import Path

import numpy as np
import pytest

from tests.outputs import run


def wav_bytes(seconds: float = 1.0, rate: int = 8000) -> bytes:
    """A mono 16-bit WAV of a quiet tone, header and all."""
    import struct

    samples = (np.sin(np.arange(int(seconds * rate)) * 0.1) * 3000).astype("<i2").tobytes()
    header = b"RIFF" + struct.pack("<I", 36 + len(samples)) + b"WAVEfmt " + struct.pack(
        "<IHHIIHH", 16, 1, 1, rate, rate * 2, 2, 16) + b"data" + struct.pack("<I", len(samples))
    return header + samples


@pytest.mark.hardening
@pytest.mark.parametrize("name", ["concat:a.wav|b.wav", "http:/127.0.0.1/song.wav", "subfile,,start,0,end,9,,:x.wav"])
def test_music_named_like_an_ffmpeg_protocol_is_read_as_that_file(tmp_path, source, capsys, monkeypatch, name):
    pytest.importorskip("imageio_ffmpeg", reason="video previews need imageio-ffmpeg")
    monkeypatch.chdir(tmp_path)
    Path(name).parent.mkdir(parents=True, exist_ok=True)
    Path(name).write_bytes(wav_bytes())
    code, lines = run(capsys, "render", source, "--music", name, "-o", "out.mp4", "--size", "64x48")
    assert code == 0, lines
    from choreo.render.video import ffmpeg_executable

    probe = subprocess.run([ffmpeg_executable(), "-i", "out.mp4"], capture_output=True, text=True).stderr
    assert "Audio:" in probe


@pytest.mark.hardening
def test_ffmpeg_is_given_a_file_url_with_an_absolute_path(tmp_path, monkeypatch):
    from choreo.render.video import ffmpeg_input

    monkeypatch.chdir(tmp_path)
    Path("-i").write_bytes(wav_bytes())  # even a name that looks like an option
    assert ffmpeg_input("-i") == f"file:{tmp_path}/-i"
