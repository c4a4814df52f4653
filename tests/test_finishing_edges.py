"""The finishing passes' settings and small inputs at their edges (from surviving mutants,
docs/mutation.md): each boundary accepted or refused exactly where its message says."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import BeatLockConfig, FootLockConfig, foot_lock
from choreo.finishing.beat_lock import retimed_span
from choreo.motion import Motion

SPEEDS = r"^beat lock speeds must satisfy 0 < min <= 1 <= max, got "
LIMITS = "^beat lock: shift, hold and ramp must be >= 0 and max_skip >= 1$"


@pytest.mark.parametrize("settings", [dict(min_speed=1.0, max_speed=1.0), dict(max_shift_seconds=0.0),
                                      dict(hold_frames=0.0), dict(ramp_frames=0.0), dict(max_skip=1)])
def test_beat_lock_accepts_its_boundaries(settings):
    BeatLockConfig(**settings)


@pytest.mark.parametrize("settings, message", [
    (dict(min_speed=0.0), SPEEDS + "0.0, 1.33$"), (dict(min_speed=1.01), SPEEDS), (dict(max_speed=0.99), SPEEDS),
    (dict(max_shift_seconds=-0.1), LIMITS), (dict(hold_frames=-1.0), LIMITS), (dict(ramp_frames=-0.5), LIMITS),
    (dict(max_skip=0), LIMITS),
])  # fmt: skip
def test_beat_lock_refuses_past_them(settings, message):
    with pytest.raises(ParameterError, match=message):
        BeatLockConfig(**settings)


@pytest.mark.parametrize("settings", [dict(speed_threshold=0.0), dict(recovery_seconds=0.0)])
def test_foot_lock_needs_positive_settings(settings):
    with pytest.raises(ParameterError, match="^foot lock: speed threshold and recovery time must be positive$"):
        FootLockConfig(**settings)


def walking(frames: int) -> Motion:
    t = np.arange(frames)[:, None]
    return Motion.rest(frames).replace(root_positions=np.hstack([0.02 * t, np.full_like(t, 0.9, float), 0 * t]),
                                       metadata={"genre": "waltz"})


def test_foot_lock_works_from_three_frames_and_keeps_metadata():
    short = walking(2)
    assert foot_lock(short) is short  # nothing to correct in two frames
    three = walking(3)
    locked = foot_lock(three, config=FootLockConfig(speed_threshold=5.0))  # the standing feet count as planted
    assert not np.allclose(locked.root_positions, three.root_positions)
    assert locked.metadata == {"genre": "waltz"} and locked.metadata is not three.metadata


def test_foot_lock_refuses_a_mask_of_another_length():
    with pytest.raises(ParameterError, match=r"^fixed frames must be a \(10,\) mask, got \(9,\)$"):
        foot_lock(walking(10), np.zeros(9, bool))


def test_retimed_spans_stay_inside_the_dance():
    source = np.arange(10.0)
    assert retimed_span([12, 20], source) == [9, 9]  # a span past the end collapses onto the last frame
    assert retimed_span([5, 40], source) == [5, 9]
