"""choreo.motion.delivery: a finished dance at another frame rate, or without its travel."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.motion import Motion
from choreo.motion.delivery import at_fps, check_fps, delivered, in_place
from choreo.motion.travel import ground_track

from .helpers import FPS, wobbly_walk


def turning_dance(frames: int = 90, hz: float = 1.0, fps: float = FPS) -> Motion:
    t = np.arange(frames) / fps
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 0, 1] = np.linspace(0, 4 * np.pi, frames)  # two whole turns
    axis_angle[:, 18, 2] = 0.8 * np.sin(2 * np.pi * hz * t)
    root = np.stack([0.5 * t, 0.9 + 0.02 * np.sin(2 * np.pi * t), 0.1 * t], -1)
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def test_a_higher_rate_has_every_source_frame_and_no_repeated_frame():
    motion = turning_dance()
    fast = at_fps(motion, 60)
    assert fast.fps == 60 and abs(fast.num_frames - 2 * motion.num_frames) <= 1
    np.testing.assert_allclose(fast.joint_positions()[::2], motion.joint_positions(), atol=1e-6)
    steps = np.abs(np.diff(fast.joint_positions(), axis=0)).max(axis=(1, 2))
    assert steps.min() > 1e-6  # a held frame would be a step of zero
    assert fast.duration <= motion.duration


def test_a_lower_rate_keeps_slow_motion_and_does_not_alias_fast_motion():
    slow, fast = turning_dance(hz=1.0), turning_dance(hz=13.0)
    film = at_fps(slow, 24)
    times = np.arange(film.num_frames) / 24
    assert film.num_frames == int((slow.num_frames - 1) * 24 / FPS) + 1
    np.testing.assert_allclose(film.root_positions[:, 0], 0.5 * times, atol=2e-3)
    wrist_swing = lambda m: np.ptp(m.joint_positions()[10:-10, 20, 1])  # noqa: E731 - the arm swinging at `hz`
    assert wrist_swing(at_fps(fast, 10)) < 0.2 * wrist_swing(fast)  # 13 Hz cannot be shown at 10 fps: it is removed
    naive = fast.resample(10)  # picking frames folds 13 Hz down to 3 Hz at almost full swing
    assert wrist_swing(naive) > 0.5 * wrist_swing(fast)


def test_the_same_rate_is_the_same_dance():
    motion = turning_dance()
    assert at_fps(motion, FPS) is motion and delivered(motion) is motion


def test_rates_outside_what_files_are_written_at_are_refused():
    for fps in (10, 24, 60, 240):
        check_fps(fps)
    for fps in (0, 9.9, 240.5, 1000):
        with pytest.raises(ParameterError, match="--fps must be 10 to 240"):
            check_fps(fps)


def test_in_place_keeps_the_dancer_at_its_start_with_its_sway_height_and_facing():
    walk = wobbly_walk(seconds=60.0, speed=0.6, wobble=0.05)
    still = in_place(walk)
    track = ground_track(still.root_positions, FPS)
    assert np.linalg.norm(track - track[0], axis=-1).max() <= 0.02
    sway = lambda m: (m.root_positions[:, [0, 2]] - ground_track(m.root_positions, FPS)).std(0)  # noqa: E731
    assert (sway(still) >= 0.5 * sway(walk)).all()
    np.testing.assert_array_equal(still.root_positions[:, 1], walk.root_positions[:, 1])
    np.testing.assert_allclose(still.rotations, walk.rotations, atol=1e-12)  # facing kept: a spinning dancer still spins
    np.testing.assert_allclose(still.root_positions[0], walk.root_positions[0], atol=0.02)
