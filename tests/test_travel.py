"""Travel and its passes: the ground track (choreo.motion.travel), the root path's low-pass
(choreo.finishing.root_path), the pace pass (choreo.finishing.pace) and the whole-song figures
(choreo.metrics.whole_song)."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import finish
from choreo.finishing.pace import ANY_GENRE_PACE, REAL_PACE, PaceConfig, paced, target_pace, travel_scale
from choreo.finishing.root_path import RootPathConfig, smooth_root_path
from choreo.metrics.whole_song import beat_dip, jerks, median_jerk, whole_song
from choreo.motion import Motion
from choreo.motion.filters import low_pass
from choreo.motion.travel import ground_track, pace, track_reach

FPS = 30.0


def wobbly_walk(seconds: float = 20.0, speed: float = 0.5, wobble: float = 0.03, seed: int = 0,
                genre: str | None = "rumba") -> Motion:
    """A dancer walking a straight line at ``speed`` whose root wobbles by ``wobble`` metres at 4-8 Hz."""
    frames = int(seconds * FPS)
    t = np.arange(frames) / FPS
    rng = np.random.default_rng(seed)
    root = np.zeros((frames, 3))
    root[:, 0] = speed * t
    root[:, 1] = 0.9
    for axis in range(3):
        for hz in (4.0, 6.0, 8.0):
            root[:, axis] += wobble / 3 * np.sin(2 * np.pi * hz * t + rng.uniform(0, 2 * np.pi))
    rotations = np.zeros((frames, 24, 3))
    rotations[:, 16:22] = 0.3 * np.sin(2 * np.pi * 1.0 * t)[:, None, None]  # arms swinging on a 1 Hz beat
    motion = Motion.from_axis_angle(root, rotations, fps=FPS)
    motion.metadata = {"genre": genre}
    return motion


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


def test_root_path_pass_removes_wobble_and_keeps_fixed_frames_exactly():
    motion = wobbly_walk()
    fixed = np.zeros(len(motion), bool)
    fixed[100:130] = True
    out = smooth_root_path(motion, fixed, RootPathConfig(cutoff_hz=2.5))
    assert median_jerk(out.root_positions[:, None], FPS) < 0.2 * median_jerk(motion.root_positions[:, None], FPS)
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])
    np.testing.assert_allclose(out.rotations, motion.rotations, atol=1e-12)  # only the root moves
    assert pace(out.root_positions, FPS) == pytest.approx(pace(motion.root_positions, FPS), rel=0.01)
    with pytest.raises(ParameterError):
        RootPathConfig(cutoff_hz=0)


def test_travel_scale_pulls_to_the_target_within_bounds():
    config = PaceConfig(max_scale=1.25)
    assert travel_scale(0.50, 0.45, config) == pytest.approx(0.9)
    assert travel_scale(2.00, 0.45, config) == pytest.approx(0.8)  # at most 1.25 x slower
    assert travel_scale(0.10, 0.45, config) == pytest.approx(1.25)
    assert travel_scale(0.0, 0.45, config) == 1.0
    with pytest.raises(ParameterError):
        PaceConfig(max_scale=0.5)


def test_pace_pass_scales_a_rushing_dance_toward_its_genre():
    motion = wobbly_walk(seconds=40.0, speed=1.0, genre="rumba")
    out = paced(motion)
    assert out.metadata["pace"]["model"] == pytest.approx(1.0, rel=0.03)
    assert pace(out.root_positions, FPS) == pytest.approx(0.8, rel=0.03)  # bounded at 1 / 1.25
    assert out.metadata["pace"]["finished"] == pytest.approx(pace(out.root_positions, FPS), rel=1e-3)
    wobble = motion.root_positions - np.pad(ground_track(motion.root_positions, FPS), ((0, 0), (0, 1)))[:, [0, 2, 1]]
    kept = out.root_positions - np.pad(ground_track(out.root_positions, FPS), ((0, 0), (0, 1)))[:, [0, 2, 1]]
    np.testing.assert_allclose(kept[:, [0, 2]], wobble[:, [0, 2]], atol=2e-3)  # the sway around the track stays
    np.testing.assert_array_equal(out.root_positions[:, 1], motion.root_positions[:, 1])


def test_pace_pass_leaves_short_constrained_and_unlabelled_dances_alone():
    motion = wobbly_walk(seconds=40.0, speed=1.0)
    short = wobbly_walk(seconds=20.0, speed=1.0)
    assert paced(short) is short  # a few seconds have no pace to speak of
    fixed = np.zeros(len(motion), bool)
    fixed[0] = True
    assert paced(motion, fixed) is motion
    unlabelled = motion.replace(metadata={})
    assert paced(unlabelled) is unlabelled
    assert paced(motion.replace(metadata={"genre": "breaking"})).root_positions is motion.root_positions
    assert target_pace(None) == ANY_GENRE_PACE and target_pace("waltz") == REAL_PACE["waltz"]


def test_finish_keeps_fixed_frames_with_the_new_passes():
    motion = wobbly_walk(speed=1.0)
    fixed = np.zeros(len(motion), bool)
    fixed[200:260] = True
    out = finish(motion, np.arange(0, len(motion), 15), fixed)
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])
    np.testing.assert_array_equal(out.rotations[fixed], motion.rotations[fixed])


def test_median_jerk_of_a_cubic_is_its_third_derivative():
    t = np.arange(100) / FPS
    positions = np.zeros((100, 2, 3))
    positions[:, :, 0] = (2.0 * t**3)[:, None]  # d3/dt3 = 12
    assert median_jerk(positions, FPS) == pytest.approx(12.0, rel=1e-6)
    whole, root, body = jerks(positions, FPS)
    assert whole == pytest.approx(12.0, rel=1e-6) and root == pytest.approx(12.0, rel=1e-6) and body == pytest.approx(0.0)


def test_beat_dip_is_deeper_for_a_dancer_who_stops_on_beats():
    t = np.arange(600) / FPS
    stops = np.zeros((600, 24, 3))
    stops[:, :, 0] = (t - np.sin(2 * np.pi * t) / (2 * np.pi))[:, None]  # speed 1 - cos: stops once a second
    even = np.zeros((600, 24, 3))
    even[:, :, 0] = (t - 0.3 * np.sin(2 * np.pi * t) / (2 * np.pi))[:, None]  # speed never below 0.7
    assert beat_dip(stops) > 0.6 and 0.1 < beat_dip(even) < 0.45 and beat_dip(stops) > 2 * beat_dip(even)


def test_whole_song_figures_of_a_walk():
    figures = whole_song(wobbly_walk().joint_positions(), FPS)
    assert figures.seconds == pytest.approx(20.0)
    assert figures.pace == pytest.approx(0.5, rel=0.03)
    assert figures.root_jerk > figures.body_jerk  # the wobble is the root's
    assert 0.0 <= figures.planted <= 1.0
