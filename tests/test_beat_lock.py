"""Beat lock: motion beats re-timed onto music beats, within speed bounds, given frames untouched."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import BeatLockConfig, beat_lock, lock_warp
from choreo.finishing.beat_lock import free_spans, landed_beats
from choreo.metrics import beat_align_score, motion_beats
from choreo.motion import Motion
from choreo.skeleton import rotations as rot


def swinging_dance(beat_frames: np.ndarray, num_frames: int) -> Motion:
    """Arms swing through a pose and stop at each of ``beat_frames``: speed minima (motion beats) there."""
    phase = np.interp(np.arange(num_frames), np.concatenate([[0], beat_frames, [num_frames - 1]]),
                      np.arange(len(beat_frames) + 2, dtype=float))
    angle = 0.8 * np.cos(np.pi * phase)  # one swing per beat interval, at rest (zero speed) on each beat
    axis_angle = np.zeros((num_frames, 24, 3))
    for joint in (16, 17, 18, 19):  # shoulders and elbows
        axis_angle[:, joint, 2] = angle
    return Motion(np.tile([0.0, 0.9, 0.0], (num_frames, 1)), rot.axis_angle_to_quaternion(axis_angle))


def test_warp_puts_each_dance_beat_on_its_music_beat():
    dance_beats = np.array([12, 27, 44, 58, 75, 90])
    music_beats = np.arange(15, 100, 15)
    source, pairs = lock_warp(dance_beats, music_beats, 110, np.zeros(110, bool), 30.0,
                              BeatLockConfig(hold_frames=0, ramp_frames=0))
    assert pairs == [(12, 15), (27, 30), (44, 45), (58, 60), (75, 75), (90, 90)]
    for dance, music in pairs:
        assert source[music] == pytest.approx(dance)  # output frame `music` plays the dance's beat
    speed = np.diff(source)
    assert speed.min() >= 0.75 - 1e-9 and speed.max() <= 1.33 + 1e-9
    assert source[0] == 0 and source[-1] == 109


def test_default_warp_holds_its_speed_around_each_locked_beat():
    dance_beats = np.array([12, 27, 44, 58, 75, 90])
    source, pairs = lock_warp(dance_beats, np.arange(15, 100, 15), 110, np.zeros(110, bool), 30.0)
    speed = np.diff(source)
    assert speed.min() >= 0.75 - 1e-9 and speed.max() <= 1.33 + 1e-9
    assert [source[m] for _, m in pairs] == pytest.approx([d for d, _ in pairs], abs=1e-9)  # exactly on the pair
    for _, music in pairs[1:-1]:  # interior pairs: one speed through the beat
        around = speed[music - 2: music + 2]
        assert np.ptp(around) < 1e-9, around
    assert (np.abs(np.diff(speed)) < 0.25).all()  # raised-cosine ramps: no jump of pace (0.58 max change over 4 frames)


def uneven_dance(num_frames: int = 600, seed: int = 3, beat: int = 30) -> tuple[Motion, np.ndarray]:
    """A dancer travelling with a shallow, smooth pulse of speed (as real motion beats are, after
    the metric's smoothing: the speed dips, never stops) whose dips come at uneven gaps (0.8-1.25
    x the music's beat, drifting on and off the grid), and the music beats."""
    from scipy.interpolate import PchipInterpolator

    rng = np.random.default_rng(seed)
    dips = np.cumsum(np.concatenate([[0.0, 20.0], beat * rng.uniform(0.8, 1.25, num_frames // 20)]))
    phase = PchipInterpolator(dips, np.arange(len(dips)))(np.arange(num_frames))
    speed = 0.01 + 0.01 * np.sin(np.pi * phase) ** 2  # metres per frame, slowest at each dip
    root = np.stack([np.cumsum(speed), np.full(num_frames, 0.9), np.zeros(num_frames)], axis=1)
    return Motion(root, np.tile([1.0, 0.0, 0.0, 0.0], (num_frames, 24, 1))), np.arange(20, num_frames - 10, beat)


def test_locked_beats_are_still_motion_beats_after_the_warp():
    # A playback speed that changes across a speed minimum tilts it: the beat lock must leave
    # the re-timed dance's own motion beats where it put them, not a few frames beside them.
    dance, music_beats = uneven_dance()
    result = beat_lock(dance, music_beats)
    assert len(result.pairs) >= 15
    realised = motion_beats(result.motion.joint_positions())
    targets = np.array([m for _, m in result.pairs])
    misses = np.abs(realised[np.abs(realised[None, :] - targets[:, None]).argmin(axis=1)] - targets)
    assert np.mean(misses <= 1) >= 0.85, misses  # the smoothly varying warp before: 0.47
    # the file's metadata reports beats that landed, not beats that were aimed at
    landed = int(result.motion.metadata["beat_lock"].split(" of ")[0])
    assert abs(landed - int(np.sum(misses <= 1))) <= 1 and landed < len(result.pairs)


def test_beats_out_of_reach_are_left_alone():
    # the only music beat is 20 frames (0.67 s) from the dance's beat: further than max_shift
    source, pairs = lock_warp(np.array([40]), np.array([60]), 100, np.zeros(100, bool), 30.0)
    assert pairs == [] and np.array_equal(source, np.arange(100))
    # within reach, but reaching it would need more than the speed bounds allow
    source, pairs = lock_warp(np.array([10]), np.array([3]), 100, np.zeros(100, bool), 30.0)
    assert pairs == []


def test_fixed_frames_are_anchors():
    fixed = np.zeros(120, bool)
    fixed[50:60] = True
    assert free_spans(fixed) == [(0, 50), (59, 119)]
    source, pairs = lock_warp(np.array([20, 80, 100]), np.array([25, 85, 95]), 120, fixed, 30.0)
    assert np.array_equal(source[50:60], np.arange(50, 60))
    assert {m for _, m in pairs} <= {25, 85, 95}


def test_a_dance_half_a_beat_late_is_put_on_the_beat():
    music_beats = np.arange(20, 290, 16)  # 112.5 bpm
    dance = swinging_dance(music_beats + 5, 300)
    before = beat_align_score(music_beats, motion_beats(dance.joint_positions()))
    result = beat_lock(dance, music_beats)
    after_beats = motion_beats(result.motion.joint_positions())
    after = beat_align_score(music_beats, after_beats)
    assert before < 0.5 and after > 0.9
    assert result.motion.num_frames == dance.num_frames
    assert len(result.pairs) >= len(music_beats) - 2


def test_given_frames_stay_exactly():
    music_beats = np.arange(20, 290, 16)
    dance = swinging_dance(music_beats + 5, 300)
    fixed = np.zeros(300, bool)
    fixed[:30] = fixed[200:230] = True
    result = beat_lock(dance, music_beats, fixed)
    np.testing.assert_array_equal(result.motion.rotations[fixed], dance.rotations[fixed])
    np.testing.assert_array_equal(result.motion.root_positions[fixed], dance.root_positions[fixed])
    assert not np.allclose(result.motion.rotations[~fixed], dance.rotations[~fixed])


def test_bad_settings_are_refused():
    with pytest.raises(ParameterError):
        BeatLockConfig(min_speed=1.2)
    with pytest.raises(ParameterError):
        beat_lock(swinging_dance(np.array([20]), 60), np.array([20]), np.zeros(10, bool))


def test_retimed_spans_follow_the_warp():
    from choreo.finishing.beat_lock import retimed_span

    identity = np.arange(100.0)
    assert retimed_span([10, 29], identity) == [10, 29]
    slower = np.arange(200) / 2.0  # half speed: output frame i shows frame i / 2
    assert retimed_span([10, 29], slower) == [19, 58]  # 9.5 rounds up into the span, 29.5 out of it
    assert retimed_span([0, 9], slower)[1] == 18  # the span before ends where this one starts
    faster = np.minimum(np.arange(50) * 2.0, 99)  # twice as fast: 10..29 over 5..14
    assert retimed_span([10, 29], faster) == [5, 14]
    assert retimed_span([90, 99], faster) == [45, 49]


def test_landed_beats_are_the_nearest_motion_beats_earlier_on_a_tie(monkeypatch):
    """The binary search (an hour's song would need a targets x beats table) picks what a full
    table's argmin picks, ties to the earlier beat included."""
    import sys

    module = sys.modules["choreo.finishing.beat_lock"]  # the package's name beat_lock is the function

    rng = np.random.default_rng(0)
    for case in range(300):
        beats = np.unique(rng.integers(0, 400, size=rng.integers(1, 40)))
        targets = np.concatenate([rng.uniform(-50, 450, size=30), (beats[:-1] + beats[1:]) / 2])  # ties too
        monkeypatch.setattr(module, "motion_beats", lambda _: beats)
        expected = beats[np.abs(beats[None, :] - targets[:, None]).argmin(axis=1)]
        np.testing.assert_array_equal(landed_beats(None, targets), expected)
    monkeypatch.setattr(module, "motion_beats", lambda _: np.array([], int))
    assert np.isinf(landed_beats(None, np.array([3.0, 7.0]))).all()
