"""The ground track (choreo.motion.travel) and the low-pass it is built on (choreo.motion.filters)."""

import numpy as np
import pytest

from choreo.motion.filters import low_pass
from choreo.motion.travel import ground_track, pace, track_reach

from .helpers import FPS, wobbly_walk


def test_low_pass_keeps_slow_motion_and_removes_fast_wobble():
    t = np.arange(600) / FPS
    slow, fast = np.sin(2 * np.pi * 0.3 * t), 0.2 * np.sin(2 * np.pi * 8 * t)
    out = low_pass(slow + fast, FPS, 2.5)
    assert np.abs(out - slow)[30:-30].max() < 0.01  # no delay: zero-phase
    assert np.abs(low_pass(slow, FPS, 2.5) - slow).max() < 0.005  # the ends are not pulled to zero
    assert low_pass(slow + fast + 1, FPS, 2.5)[0] == pytest.approx(1.0, abs=1e-6)  # the first frame stays


def test_ground_track_pace_ignores_wobble():
    motion = wobbly_walk(speed=0.5, wobble=0.05)
    floor_speed = np.linalg.norm(np.diff(motion.root_positions[:, [0, 2]], axis=0), axis=-1).mean() * FPS
    assert floor_speed > 0.8  # frame to frame, the wobble counts as travel
    assert pace(motion.root_positions, FPS) == pytest.approx(0.5, rel=0.03)
    assert track_reach(ground_track(motion.root_positions, FPS)) == pytest.approx(0.5 * (len(motion) - 1) / FPS, rel=0.03)
    assert ground_track(motion.root_positions, FPS).shape == (len(motion), 2)
