"""A dance and a CLI runner for the tests of where outputs go (tests/test_fileio.py, tests/render/test_video.py)."""

import numpy as np

from choreo.cli import main
from choreo.motion import Motion


def dance(frames: int = 30) -> Motion:
    rng = np.random.default_rng(1)
    axis_angle = np.cumsum(rng.normal(scale=0.02, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.95, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=30.0)


def run(capsys, *args):
    code = main(list(map(str, args)))
    return code, [line for line in capsys.readouterr().err.splitlines() if line.strip()]
