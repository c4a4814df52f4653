"""Tests of choreo.cli.commands.

Markers say where a test came from: hardening (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.datasets.helpers import clip


def legless_clip(root):
    """An M2D clip whose 23 markers sit at one point each frame: legs of zero length."""
    root.mkdir()
    folder = clip(root)
    frames = 40
    (folder / "skeletons.json").write_text(json.dumps({"center": [[0, 90, 0]] * frames, "length": frames,
                                                        "skeletons": np.zeros((frames, 23, 3)).tolist()}))
    (folder / "audio.mp3").write_bytes(b"")
    return folder


@pytest.mark.hardening
def test_a_recording_with_zero_leg_length_is_exit_2_through_prepare(tmp_path, monkeypatch, capsys):
    from choreo.cli import main

    monkeypatch.setenv("CHOREO_CACHE_DIR", str(tmp_path / "cache"))
    legless_clip(tmp_path / "data")
    code = main(["prepare", str(tmp_path / "data")])
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert code == 2 and len(err) == 1 and "legs have no usable length" in err[0], err
