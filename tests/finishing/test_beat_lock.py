"""Beat lock: motion beats re-timed onto music beats, within speed bounds, given frames untouched."""

import itertools
import math

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import BeatLockConfig, beat_lock, lock_warp
from choreo.finishing.beat_lock import (
    _speed_ok,
    _speed_profile_integral,
    choose_pairs,
    feasible_aims,
    free_spans,
    knot_speeds,
    landed_beats,
    refined_warp,
    retimed_span,
    span_warp,
    stretch_progress,
    warp_through,
)
from choreo.metrics import beat_align_score, motion_beats
from choreo.motion import Motion, positions_at
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


def raised_cosine_integral(u, pieces, steps_per_frame=4000):
    """Integral from 0 to each u of the speed the pieces describe, by the midpoint rule on a fine
    grid: the speed written out literally (constant, or v0 + (v1 - v0) (1 - cos(pi t / w)) / 2)."""
    total = sum(w for w, _, _ in pieces)
    grid = np.linspace(0.0, total, int(round(total * steps_per_frame)) + 1)
    speed = np.empty(len(grid) - 1)
    for n, t in enumerate((grid[1:] + grid[:-1]) / 2):
        start = 0.0
        for k, (width, v0, v1) in enumerate(pieces):
            if t <= start + width or k == len(pieces) - 1:
                x = min(max(t - start, 0.0), width)
                speed[n] = v0 if width == 0 else v0 + (v1 - v0) * (1 - math.cos(math.pi * x / width)) / 2
                break
            start += width
    cumulative = np.concatenate([[0.0], np.cumsum(speed * np.diff(grid))])
    return np.interp(u, grid, cumulative)


def one_beat_joints(num_frames: int, beat: int) -> np.ndarray:
    """(T, 2, 3) joints whose mean speed has exactly one minimum, at frame ``beat`` (a parabola)."""
    i = np.arange(num_frames - 1)
    x = np.concatenate([[0.0], np.cumsum(0.002 + 0.0005 * (i - beat) ** 2)])
    joints = np.zeros((num_frames, 2, 3))
    joints[:, 0, 0] = x
    return joints


def swinging_dance_with_metadata(beat_frames, num_frames: int, metadata=None) -> Motion:
    """Arms swing and stop at each of ``beat_frames`` (as in swinging_dance above)."""
    phase = np.interp(np.arange(num_frames), np.concatenate([[0], beat_frames, [num_frames - 1]]),
                      np.arange(len(beat_frames) + 2, dtype=float))
    axis_angle = np.zeros((num_frames, 24, 3))
    for joint in (16, 17, 18, 19):
        axis_angle[:, joint, 2] = 0.8 * np.cos(np.pi * phase)
    return Motion(np.tile([0.0, 0.9, 0.0], (num_frames, 1)), rot.axis_angle_to_quaternion(axis_angle),
                  metadata=metadata or {})


LINEAR = dict(hold_frames=0.0, ramp_frames=0.0)  # a warp that is piecewise linear through its pairs


@pytest.mark.survivor
@pytest.mark.parametrize("source, output, ok", [
    (4.0, 2.0, True), (1.0, 2.0, True),  # exactly at the bounds 2 and 0.5
    (4.1, 2.0, False), (0.9, 2.0, False), (8.0, 4.0, True),  # 8 * 4 = 32 would be out of bounds
    (0.75, 0.75, True),  # less than one output frame, speed 1
    (1.0, 0.0, False), (-2.0, -2.0, False),  # no output frames, or backwards
])  # fmt: skip
def test_speed_ok_at_its_edges(source, output, ok):
    assert _speed_ok(source, output, BeatLockConfig(min_speed=0.5, max_speed=2.0)) is ok


@pytest.mark.survivor
@pytest.mark.parametrize("wanted, expected", [
    ([11, 25, 29], [11, 20, 29]),  # 25 would make 10 source frames play over 14: too slow; 11 and 29 fit
    ([10, 20, 35], [10, 20, 30]),  # the last stretch would be 10 over 15 (0.67): kept
    ([10, 20, 27], [10, 20, 27]),  # 10 over 7 (1.43): within this max_speed of 1.5
    ([4, 20, 30], [10, 20, 30]),  # the first stretch would be 10 over 16: kept
    ([10, 13, 30], [10, 20, 30]),  # the first stretch 10 over 3: kept (the second, 10 over 17, too)
    ([10, 26, 30], [10, 20, 30]),  # the second stretch 10 over 4: kept
    ([9, 20, 30], [9, 20, 30]),  # 10 over 11 (0.91): taken
])  # fmt: skip
def test_feasible_aims_keep_each_stretch_within_the_bounds(wanted, expected):
    pairs = [(10, 10), (20, 20), (30, 30)]
    config = BeatLockConfig(max_speed=1.5)  # 10 over 7 = 1.43 is allowed here
    aims = np.array([10.0, 20.0, 30.0])
    np.testing.assert_array_equal(feasible_aims(pairs, aims, np.array(wanted, float), config), expected)
    np.testing.assert_array_equal(aims, [10, 20, 30])  # the caller's aims are not changed


@pytest.mark.survivor
def test_feasible_aims_check_against_the_last_accepted_aims():
    # aims move one at a time: once 20 -> 18 is taken, 30 -> 26 is judged against 18 (8 over 8)
    pairs = [(10, 10), (20, 20), (30, 30)]
    got = feasible_aims(pairs, np.array([10.0, 20.0, 30.0]), np.array([10.0, 18.0, 26.0]), BeatLockConfig())
    np.testing.assert_array_equal(got, [10, 18, 26])
    # a single pair has no stretch between pairs: any aim is taken
    np.testing.assert_array_equal(feasible_aims([(40, 40)], np.array([40.0]), np.array([37.0]), BeatLockConfig()), [37])


@pytest.mark.survivor
@pytest.mark.parametrize("mask, spans", [
    ([0, 0, 1, 0, 0], [(0, 2), (2, 4)]),  # stretches exactly two frames long on both sides
    ([0, 0, 0, 0, 0, 1], [(0, 5)]),  # the last frame fixed: no stretch after it
    ([1, 0, 0, 0, 0, 1], [(0, 5)]),
    ([1, 1, 1], []),
    ([0, 1, 0, 1], [(1, 3)]), ([0, 1, 1, 0], []),  # no stretch of two frames in the second
    ([0, 0, 0], [(0, 2)]),
])  # fmt: skip
def test_free_spans_by_hand(mask, spans):
    assert free_spans(np.array(mask, bool)) == spans


@pytest.mark.survivor
def test_warp_through_ignores_knots_on_a_span_end():
    config = BeatLockConfig(**LINEAR)
    for knot in ([(3.0, 0.0)], [(45.0, 49.0)]):  # output frame 0 and 49: the span's own ends
        np.testing.assert_array_equal(warp_through(knot, 50, np.zeros(50, bool), config), np.arange(50.0))
    # one knot inside: piecewise linear through it
    np.testing.assert_allclose(warp_through([(20.0, 24.0)], 50, np.zeros(50, bool), config),
                               np.interp(np.arange(50), [0, 24, 49], [0, 20, 49]), atol=1e-12)


@pytest.mark.survivor
def test_lock_warp_keeps_the_pairs_of_every_span():
    fixed = np.zeros(120, bool)
    fixed[50:60] = True
    source, pairs = lock_warp(np.array([20, 80]), np.array([25, 85]), 120, fixed, 30.0, BeatLockConfig(**LINEAR))
    assert pairs == [(20, 25), (80, 85)]
    np.testing.assert_allclose(source, np.interp(np.arange(120), [0, 25, 50, 59, 85, 119], [0, 20, 50, 59, 80, 119]),
                               atol=1e-12)


def all_chains(dance, music, start, stop, fps, config):
    """(total, chain) for every monotone chain of (motion beat, music beat) pairs, scored as the
    module docstring says, by enumeration."""
    reach = config.max_shift_seconds * fps
    candidates = [(d, m) for d in sorted(dance) for m in sorted(music) if abs(m - d) <= reach]
    rank = {d: i for i, d in enumerate(sorted(dance))}
    number = {m: k for k, m in enumerate(sorted(music))}

    def cost(a, b):
        s, t = b[0] - a[0], b[1] - a[1]
        if s <= 0 or t <= 0 or not config.min_speed <= s / t <= config.max_speed:
            return None
        return config.speed_cost * abs(math.log(s / t))

    chains = [(0.0, [])]
    for size in range(1, len(candidates) + 1):
        for chain in itertools.combinations(candidates, size):
            total, previous = 0.0, (start, start)
            for n, node in enumerate(chain):
                c = cost(previous, node)
                if c is None or (n > 0 and rank[node[0]] - rank[previous[0]] > config.max_skip):
                    break
                total += 1.0 - c + (config.pulse_bonus if n > 0 and number[node[1]] - number[previous[1]] in (1, 2) else 0.0)
                previous = node
            else:
                c = cost(previous, (stop, stop))
                if c is not None:
                    chains.append((total - c, list(chain)))
    return chains


@pytest.mark.survivor
def test_choose_pairs_finds_the_best_chain_of_an_exhaustive_search():
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(300):
        dance = sorted(set(rng.integers(5, 115, rng.integers(1, 6)).tolist()))
        music = sorted(set(rng.integers(5, 115, rng.integers(1, 6)).tolist()))
        config = BeatLockConfig(speed_cost=float(rng.choice([0.0, 0.5, 2.0, 3.0])),
                                pulse_bonus=float(rng.choice([0.0, 0.4, 1.0])), max_skip=int(rng.choice([1, 2, 6])),
                                max_shift_seconds=float(rng.choice([0.3, 0.5, 1.0])))
        chains = sorted(all_chains(dance, music, 0, 120, 30.0, config), key=lambda c: -c[0])
        if len(chains) > 1 and chains[0][0] - chains[1][0] < 1e-6:
            continue  # a tie: either is right
        got = choose_pairs(np.array(dance), np.array(music), 0, 120, 30.0, config)
        assert got == chains[0][1], (dance, music, config, chains[:2])
        checked += 1
    assert checked >= 200


@pytest.mark.survivor
def test_choose_pairs_hand_cases():
    config = BeatLockConfig()
    # the only music beat 20 frames (beyond 0.5 s) before or after the beat: out of reach, although in speed
    assert choose_pairs(np.array([100]), np.array([80]), 0, 200, 30.0, config) == []
    assert choose_pairs(np.array([100]), np.array([120]), 0, 200, 30.0, config) == []
    assert choose_pairs(np.array([100]), np.array([115]), 0, 200, 30.0, config) == [(100, 115)]  # exactly 0.5 s
    # speeds exactly at the bounds: 30 source frames over 40 (0.75), 133 over 100 (1.33)
    assert choose_pairs(np.array([30]), np.array([40]), 0, 100, 30.0, config) == [(30, 40)]
    assert choose_pairs(np.array([133]), np.array([100]), 0, 300, 100.0, config) == [(133, 100)]
    # beats one frame apart: 1 + 1 + pulse 1 beats a single pair
    assert choose_pairs(np.array([20, 21]), np.array([20, 21]), 0, 60, 30.0, config) == [(20, 20), (21, 21)]
    # the pulse bonus counts from the first candidate too: (20, 20) -> (40, 40) scores 1 + 1 + 1 = 3,
    # (20, 23) -> (40, 40) 3 - 0.5 |log(20 / 23)| - 0.5 |log(20 / 17)| = 2.85
    assert choose_pairs(np.array([20, 40]), np.array([20, 23, 40]), 0, 60, 30.0, config) == [(20, 20), (40, 40)]
    # a single pair at speed 1 scores 1 > 0 (the identity)
    assert choose_pairs(np.array([50]), np.array([50]), 0, 100, 30.0, config) == [(50, 50)]
    # speed cost 3: 1 - 3 |log 0.8| - 3 |log 1.25| = -0.34 < 0: the identity wins
    assert choose_pairs(np.array([40]), np.array([50]), 0, 100, 30.0, BeatLockConfig(speed_cost=3.0)) == []


@pytest.mark.survivor
def test_choose_pairs_resolves_ties_to_the_first_candidate():
    flat = BeatLockConfig(speed_cost=0.0, pulse_bonus=0.0)  # every pair scores 1
    assert choose_pairs(np.array([20]), np.array([20, 22]), 0, 60, 30.0, flat) == [(20, 20)]
    assert choose_pairs(np.array([20, 40]), np.array([20, 22, 40]), 0, 60, 30.0, flat) == [(20, 20), (40, 40)]


@pytest.mark.survivor
def test_span_warp_holds_a_constant_speed_around_its_pair_and_none_at_the_span_ends():
    # span 10..70, one pair: source 37 plays at output 40; holds of 10 frames, no ramps. By hand:
    # stretches 27 over 30 (0.9) and 33 over 30 (1.1), held speed sqrt(0.99) for 10 frames either
    # side of the pair, the rest of each stretch at the plateau that ends it on its pair.
    v = math.sqrt(0.99)
    p0, p1 = (27 - 10 * v) / 20, (33 - 10 * v) / 20
    expected = np.interp(np.arange(10, 71), [10, 30, 50, 70], [10, 10 + 20 * p0, 10 + 20 * p0 + 20 * v, 70])
    assert 10 + 20 * p0 + 20 * v + 20 * p1 == pytest.approx(70)  # the last plateau ends the span on its end
    got = span_warp([(37, 40)], 10, 70, BeatLockConfig(hold_frames=10.0, ramp_frames=0.0))
    np.testing.assert_allclose(got, expected, atol=1e-12)
    assert got[0] == 10 and got[-1] == 70


@pytest.mark.survivor
def test_knot_speeds_by_hand():
    config = BeatLockConfig()
    np.testing.assert_allclose(knot_speeds(np.array([0.0, 27, 60, 96]), np.array([0.0, 30, 60, 90]), config),
                               [0.9, math.sqrt(0.9 * 1.1), math.sqrt(1.1 * 1.2), 1.2])
    np.testing.assert_allclose(knot_speeds(np.array([0.0, 18, 60]), np.array([0.0, 30, 60]), config),
                               [0.75, math.sqrt(0.6 * 1.4), 1.33])  # 0.6 and 1.4 clipped to the bounds


@pytest.mark.survivor
@pytest.mark.parametrize("length, source_length, first, last, holds, settings, pieces", [
    # a stretch shorter than four ramps: ramps of length / 4; plateau 0.9 by hand
    (16.0, 14.8, 1.0, 1.0, (0.0, 0.0), {}, ((0, 1, 1), (4, 1, 0.9), (8, 0.9, 0.9), (4, 0.9, 1), (0, 1, 1))),
    # holds of 10 + 10 beside two ramps of 5 in 22 frames: shrunk to 6 each, plateau 0.9
    (22.0, 23.2, 1.1, 1.1, (10.0, 10.0), {}, ((6, 1.1, 1.1), (5, 1.1, 0.9), (0, 0.9, 0.9), (5, 0.9, 1.1), (6, 1.1, 1.1))),
    # plenty of room: holds kept at 10 and 4, plateau 1
    (60.0, 61.25, 1.1, 1.0, (10.0, 4.0), {}, ((10, 1.1, 1.1), (5, 1.1, 1), (36, 1, 1), (5, 1, 1), (4, 1, 1))),
    # the holds' first two fractions put the plateau under 0.75; half holds give 0.78
    (40.0, 39.0, 1.3, 1.3, (10.0, 10.0), {}, ((5, 1.3, 1.3), (5, 1.3, 0.78), (20, 0.78, 0.78), (5, 0.78, 1.3), (5, 1.3, 1.3))),
    # ... and a quarter gives 0.8
    (40.0, 37.0, 1.3, 1.3, (10.0, 10.0), {}, ((2.5, 1.3, 1.3), (5, 1.3, 0.8), (25, 0.8, 0.8), (5, 0.8, 1.3), (2.5, 1.3, 1.3))),
    # a plateau exactly at a bound is taken (6 / 8 = 0.75; 12 / 8 = 1.5)
    (16.0, 14.0, 1.0, 1.0, (4.0, 4.0), dict(ramp_frames=0.0), ((4, 1, 1), (8, 0.75, 0.75), (4, 1, 1))),
    (16.0, 20.0, 1.0, 1.0, (4.0, 4.0), dict(ramp_frames=0.0, max_speed=1.5), ((4, 1, 1), (8, 1.5, 1.5), (4, 1, 1))),
    # holds of 0.3 in a stretch of 1.6 frames (ramps 0.4): they fit, plateau 1
    (1.6, 1.8, 1.2, 1.2, (0.3, 0.3), {}, ((0.3, 1.2, 1.2), (0.4, 1.2, 1), (0.2, 1, 1), (0.4, 1, 1.2), (0.3, 1.2, 1.2))),
])  # fmt: skip
def test_stretch_progress_against_its_speed_written_out(length, source_length, first, last, holds, settings, pieces):
    u = np.linspace(0.0, length, 33)
    got = stretch_progress(u, length, source_length, first, last, holds, BeatLockConfig(**settings))
    np.testing.assert_allclose(got, raised_cosine_integral(u, pieces), atol=2e-7)
    assert got[-1] == pytest.approx(source_length, abs=1e-9)


@pytest.mark.survivor
def test_stretch_progress_falls_back_to_one_constant_speed():
    # no fraction of the holds gets the plateau to 0.75: (30 - 13) / 30 = 0.57 at a quarter
    u = np.linspace(0.0, 40.0, 9)
    got = stretch_progress(u, 40.0, 30.0, 1.3, 1.3, (10.0, 10.0), BeatLockConfig())
    np.testing.assert_allclose(got, u * 0.75)


@pytest.mark.survivor
def test_speed_profile_integral_of_short_ramps():
    pieces = ((1.0, 1.0, 0.8), (2.0, 0.8, 0.8), (0.5, 0.8, 1.2))
    u = np.array([0.0, 0.25, 0.5, 1.0, 2.0, 3.0, 3.2, 3.5])
    np.testing.assert_allclose(_speed_profile_integral(u, pieces), raised_cosine_integral(u, pieces), atol=1e-8)
    # half-way through the first ramp, by hand: 0.5 - 0.1 (0.5 - 1 / pi)
    assert _speed_profile_integral(np.array([0.5]), pieces)[0] == pytest.approx(0.5 - 0.1 * (0.5 - 1 / math.pi))


@pytest.mark.survivor
def test_landed_beats_with_one_beat_and_with_none():
    np.testing.assert_array_equal(landed_beats(one_beat_joints(100, 43), np.array([10.0, 80.0])), [43.0, 43.0])
    still = np.zeros((50, 2, 3))  # no motion: no beat
    got = landed_beats(still, np.array([10.0, 20.0]))
    assert got.shape == (2,) and np.all(got == np.inf)


@pytest.mark.survivor
def test_a_beat_that_lands_three_frames_late_is_re_aimed_three_frames_early():
    # the pair says source 40 -> output 40, but the joints' own beat is at 43 (a miss of +3):
    # one round aims the pair at 37, a straight warp through (40 -> 37), and the beat lands
    joints, fixed = one_beat_joints(100, 43), np.zeros(100, bool)
    for refinements in (1, 3):
        got = refined_warp(joints, [(40, 40)], fixed, np.arange(100.0), BeatLockConfig(refinements=refinements, **LINEAR))
        np.testing.assert_allclose(got, np.interp(np.arange(100), [0, 37, 99], [0, 40, 99]), atol=1e-12)


@pytest.mark.survivor
def test_a_beat_four_frames_off_is_left_alone():
    joints, identity = one_beat_joints(100, 44), np.arange(100.0)
    got = refined_warp(joints, [(40, 40)], np.zeros(100, bool), identity, BeatLockConfig(**LINEAR))
    np.testing.assert_array_equal(got, identity)


@pytest.mark.survivor
@pytest.mark.parametrize("settings", [dict(max_speed=1.05),  # 40 over 37 = 1.08: too fast
                                      dict(min_speed=0.96)])  # 59 over 62 = 0.95: too slow
def test_a_re_aim_out_of_bounds_keeps_the_warp_before_it(settings):
    joints, identity = one_beat_joints(100, 43), np.arange(100.0)
    got = refined_warp(joints, [(40, 40)], np.zeros(100, bool), identity, BeatLockConfig(refinements=1, **settings, **LINEAR))
    np.testing.assert_array_equal(got, identity)


@pytest.mark.survivor
@pytest.mark.parametrize("num_frames, settings", [(68, dict(min_speed=0.9)),  # 27 over 30: exactly the minimum
                                                  (100, dict(max_speed=40 / 37))])  # exactly the maximum
def test_a_re_aim_exactly_at_a_bound_is_taken(num_frames, settings):
    joints = one_beat_joints(num_frames, 43)
    got = refined_warp(joints, [(40, 40)], np.zeros(num_frames, bool), np.arange(float(num_frames)),
                       BeatLockConfig(refinements=1, **settings, **LINEAR))
    end = num_frames - 1
    np.testing.assert_allclose(got, np.interp(np.arange(num_frames), [0, 37, end], [0, 40, end]), atol=1e-12)


@pytest.mark.survivor
def test_beat_lock_result_metadata_and_clips_by_hand():
    clips = [{"name": "a", "output_frames": [0, 35]}, {"name": "b", "output_frames": [36, 119]}]
    dance = swinging_dance_with_metadata(np.array([30, 60, 90]), 120, {"genre": "house", "clips": clips})
    np.testing.assert_array_equal(motion_beats(dance.joint_positions()), [29, 59, 89])  # the metric's beats
    config = BeatLockConfig(refinements=0, **LINEAR)
    result = beat_lock(dance, np.array([34, 64, 94]), config=config)
    assert result.pairs == [(29, 34), (59, 64), (89, 94)]
    assert result.motion_beats == 3
    np.testing.assert_allclose(result.source_frames, np.interp(np.arange(120), [0, 34, 64, 94, 119], [0, 29, 59, 89, 119]),
                               atol=1e-12)
    # output frame i shows source i - 5 from 34 to 94: source 35.5 is crossed between 40 and 41
    assert result.motion.metadata["clips"] == [{"name": "a", "output_frames": [0, 40]},
                                               {"name": "b", "output_frames": [41, 119]}]
    assert result.motion.metadata["genre"] == "house"
    assert result.motion.metadata["beat_lock"].endswith(" of 3 motion beats locked within a frame of a music beat (3 aimed)")
    assert dance.metadata["clips"][0]["output_frames"] == [0, 35]  # the input is not changed


@pytest.mark.survivor
def test_beat_lock_without_pairs_reports_zero_landed():
    dance = swinging_dance_with_metadata(np.array([20, 50, 80]), 110)
    result = beat_lock(dance, np.array([105]))  # 25 frames from the last motion beat: out of reach
    assert result.pairs == []
    assert result.motion.metadata["beat_lock"] == "0 of 3 motion beats locked within a frame of a music beat (0 aimed)"
    np.testing.assert_array_equal(result.source_frames, np.arange(110.0))


@pytest.mark.survivor
def test_beat_lock_takes_a_mask_of_ones_and_zeros_and_names_a_wrong_one():
    dance = swinging_dance_with_metadata(np.array([20, 50, 80]), 110)
    fixed = [1] * 10 + [0] * 100  # ints, as a mask
    result = beat_lock(dance, np.array([25, 55, 85]), fixed)
    np.testing.assert_array_equal(result.source_frames[:10], np.arange(10.0))
    np.testing.assert_array_equal(result.motion.root_positions[:10], dance.root_positions[:10])
    np.testing.assert_array_equal(result.motion.rotations[:10], dance.rotations[:10])
    with pytest.raises(ParameterError, match=r"^fixed frames must be a \(110,\) mask, got \(9,\)$"):
        beat_lock(dance, np.array([25]), np.zeros(9, bool))


def shallow_beat_joints(num_frames: int, beat: int) -> np.ndarray:
    joints = np.zeros((num_frames, 2, 3))
    i = np.arange(num_frames - 1)
    joints[:, 0, 0] = np.concatenate([[0.0], np.cumsum(0.002 + 0.0001 * (i - beat) ** 2)])
    return joints


@pytest.mark.survivor
def test_a_re_aim_that_lands_no_closer_keeps_the_first_warp():
    # a shallow minimum at 43: aimed 3 frames early, the warp's change of speed tilts it to 42,
    # still 2 frames off; no round has more beats on target, so the first (given) warp stays
    joints, identity = shallow_beat_joints(60, 43), np.arange(60.0)
    config = BeatLockConfig(refinements=1, **LINEAR)
    warped = positions_at(joints, np.interp(np.arange(60), [0, 37, 59], [0, 40, 59]))
    np.testing.assert_array_equal(motion_beats(warped), [42])  # the premise: 2 frames off after the re-aim
    np.testing.assert_array_equal(refined_warp(joints, [(40, 40)], np.zeros(60, bool), identity, config), identity)


@pytest.mark.survivor
def test_a_re_aim_too_fast_next_to_a_fixed_frame_is_refused():
    # span 0..40 between fixed frames; the joints' beat is at 35, two frames before the pair's
    # music beat 37: re-aimed at 39, the last step (source 38 -> 40 over one output frame) would
    # play at speed 2: the round stops and the given warp stays
    fixed = np.zeros(80, bool)
    fixed[[0, 40]] = True
    identity = np.arange(80.0)
    got = refined_warp(one_beat_joints(80, 35), [(38, 37)], fixed, identity, BeatLockConfig(**LINEAR))
    np.testing.assert_array_equal(got, identity)


SPEEDS = r"^beat lock speeds must satisfy 0 < min <= 1 <= max, got "


LIMITS = "^beat lock: shift, hold and ramp must be >= 0 and max_skip >= 1$"


@pytest.mark.survivor
@pytest.mark.parametrize("settings", [dict(min_speed=1.0, max_speed=1.0), dict(max_shift_seconds=0.0),
                                      dict(hold_frames=0.0), dict(ramp_frames=0.0), dict(max_skip=1)])
def test_beat_lock_accepts_its_boundaries(settings):
    BeatLockConfig(**settings)


@pytest.mark.survivor
@pytest.mark.parametrize("settings, message", [
    (dict(min_speed=0.0), SPEEDS + "0.0, 1.33$"), (dict(min_speed=1.01), SPEEDS), (dict(max_speed=0.99), SPEEDS),
    (dict(max_shift_seconds=-0.1), LIMITS), (dict(hold_frames=-1.0), LIMITS), (dict(ramp_frames=-0.5), LIMITS),
    (dict(max_skip=0), LIMITS),
])  # fmt: skip
def test_beat_lock_refuses_past_them(settings, message):
    with pytest.raises(ParameterError, match=message):
        BeatLockConfig(**settings)


@pytest.mark.survivor
def test_retimed_spans_stay_inside_the_dance():
    source = np.arange(10.0)
    assert retimed_span([12, 20], source) == [9, 9]  # a span past the end collapses onto the last frame
    assert retimed_span([5, 40], source) == [5, 9]
