"""Helpers shared by the tests in this folder."""

from __future__ import annotations

import json

import numpy as np


def clip(tmp_path, frames: int = 40, config=None):
    folder = tmp_path / "DANCE_C_1"
    folder.mkdir()
    rng = np.random.default_rng(0)
    skeletons = np.round(rng.normal(size=(frames, 23, 3)) * 50, 4).tolist()
    (folder / "skeletons.json").write_text(json.dumps({"center": np.zeros((frames, 3)).tolist(),
                                                        "skeletons": skeletons, "length": frames}))
    (folder / "config.json").write_text(config or '{"start_position": 0, "end_position": 40}')
    return folder
