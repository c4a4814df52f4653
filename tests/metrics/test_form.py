"""The form measures (choreo.metrics.form) on synthetic dances whose form is known by construction:
phrases of smoothly wandering joint angles (forward kinematics on SMPL-24), arranged A B A B."""

from functools import lru_cache

import numpy as np
import pytest

from choreo.metrics.form import (dance_form_score, dance_bar_features, form_score, phrase_distance, return_ratio, seam_steps,
                                 self_similarity)
from choreo.motion import Motion
from choreo.motion.augment import mirrored, turned
from choreo.motion.stitch import rotate_about_y
from choreo.music.form import Form, Section

FPS = 30.0
BEAT = 0.5  # 120 bpm
BARS = 8  # bars a section, 4/4
SECTION = BARS * 4 * BEAT  # 16 s


def phrase(rng, frames, centre=None) -> Motion:
    """Joint angles wandering smoothly (a damped random walk) around a centre pose; the pelvis bobs."""
    centre = rng.normal(scale=0.4, size=(24, 3)) if centre is None else centre
    angles, x, v = np.zeros((frames, 24, 3)), centre.copy(), np.zeros((24, 3))
    for t in range(frames):
        v = 0.9 * v + rng.normal(scale=0.01, size=(24, 3)) - 0.002 * (x - centre)
        x = x + v
        angles[t] = x
    root = np.zeros((frames, 3))
    root[:, 1] = 0.95 + 0.02 * np.sin(np.arange(frames) / 5)
    return Motion.from_axis_angle(root, angles, fps=FPS)


@lru_cache(maxsize=None)
def dance(layout: str, seed: int = 0, mirror_returns: bool = False, character: bool = False) -> np.ndarray:
    """Sections in ``layout`` order; a repeated letter repeats its phrase, turned and moved elsewhere
    in the room (mirrored if asked). ``character``: every section danced afresh, but around its
    letter's own centre pose (a dancer who answers the same music in the same manner)."""
    rng = np.random.default_rng(seed)
    frames, made, centres, parts = int(SECTION * FPS), {}, {}, []
    for index, letter in enumerate(layout):
        if character:
            parts.append(phrase(rng, frames, centres.setdefault(letter, rng.normal(scale=0.4, size=(24, 3)))))
        elif letter in made:
            again = mirrored(made[letter]) if mirror_returns else made[letter]
            parts.append(turned(again, 70.0 * index).translated([0.5 * index, 0.0, -0.3 * index]))
        else:
            parts.append(made.setdefault(letter, phrase(rng, frames)))
    return Motion.concatenate(parts).joint_positions()


ABAB = Form(tuple(Section(i * SECTION, letter) for i, letter in enumerate("ABAB")), 4 * SECTION)
BEATS = np.arange(0.0, 4 * SECTION + 1e-9, BEAT)


def bar_lines(positions) -> np.ndarray:
    """The test song's bar lines (4/4 from the first beat), as frames, up to the dance's end."""
    lines = np.rint(BEATS[::4] * FPS).astype(int)
    return lines[lines <= len(positions)]


def test_copied_returns_have_a_low_return_ratio_and_fresh_ones_about_one():
    assert max(return_ratio(dance("ABAB"), FPS, ABAB, BEATS)) < 0.1
    fresh = return_ratio(dance("ABCD"), FPS, ABAB, BEATS)
    assert len(fresh) == 2 and all(0.6 < r < 1.6 for r in fresh)


def test_a_mirrored_return_is_low_only_when_compared_mirrored():
    positions = dance("ABAB", mirror_returns=True)
    first, back = (0.0, SECTION), (2 * SECTION, 3 * SECTION)
    straight = phrase_distance(positions, FPS, first, back, BEATS)
    unmirrored = phrase_distance(positions, FPS, first, back, BEATS, mirrored=True)
    assert unmirrored < 0.15 * straight
    assert min(return_ratio(positions, FPS, ABAB, BEATS)) > 0.6
    assert max(return_ratio(positions, FPS, ABAB, BEATS, mirrored=True)) < 0.2


def test_turning_and_moving_the_whole_dance_leaves_phrase_distances_alone():
    positions = dance("ABCD")
    moved = rotate_about_y(positions, 2.1) + np.array([3.0, 0.0, -1.5])
    for a, b in [((0.0, SECTION), (2 * SECTION, 3 * SECTION)), ((SECTION, 2 * SECTION), (3 * SECTION, 4 * SECTION))]:
        assert phrase_distance(moved, FPS, a, b, BEATS) == pytest.approx(phrase_distance(positions, FPS, a, b, BEATS),
                                                                          rel=1e-9)


def test_a_phrase_returning_at_another_tempo_is_aligned_beat_by_beat():
    rng = np.random.default_rng(3)
    first, other = phrase(rng, int(SECTION * FPS)), phrase(rng, int(SECTION * FPS))
    slow_beat = 0.6  # the return at 100 bpm: the same 32 beats in 19.2 s
    slow_frames = int(round(32 * slow_beat * FPS))
    slower = first.sample_frames(np.arange(slow_frames) * (SECTION * FPS) / slow_frames)
    positions = Motion.concatenate([first, other, slower]).joint_positions()
    beats = np.concatenate([np.arange(64) * BEAT, 2 * SECTION + np.arange(32) * slow_beat])
    a, back = (0.0, SECTION), (2 * SECTION, 2 * SECTION + 32 * slow_beat)
    by_beats = phrase_distance(positions, FPS, a, back, beats)
    by_seconds = phrase_distance(positions, FPS, a, back, None)  # no beats: aligned by time alone
    assert by_beats < 0.02 < 0.2 * by_seconds


def test_a_loop_does_not_pass_for_a_form():
    one_bar = phrase(np.random.default_rng(4), int(4 * BEAT * FPS))
    loop = Motion.concatenate([one_bar] * (4 * BARS)).joint_positions()
    assert all(np.isnan(return_ratio(loop, FPS, ABAB, BEATS)))  # A is danced as B: there is nothing to return to
    jittered = loop + np.random.default_rng(4).normal(scale=0.002, size=loop.shape)
    assert not any(r < 0.35 for r in return_ratio(jittered, FPS, ABAB, BEATS))


def music_self_similarity(seed=100) -> np.ndarray:
    """Bars of A B A B: each letter's timbre, its bars' own harmony (weaker), a little noise."""
    rng = np.random.default_rng(seed)
    timbre = {letter: rng.normal(size=16) for letter in "AB"}
    harmony = {letter: rng.normal(size=(BARS, 16)) for letter in "AB"}
    bars = [timbre[s.label] + 0.5 * harmony[s.label][k] + 0.3 * rng.normal(size=16)
            for s in ABAB.sections for k in range(BARS)]
    return self_similarity(np.array(bars), same_below=0.0)


def dance_self_similarity(positions) -> np.ndarray:
    return self_similarity(dance_bar_features(positions, bar_lines(positions)))


def test_form_score_ranks_copied_returns_over_a_fresh_dance_over_a_looped_phrase():
    music = music_self_similarity()
    copied = form_score(dance_self_similarity(dance("ABAB")), music)
    fresh = form_score(dance_self_similarity(dance("ABAB", character=True)), music)
    one_bar = phrase(np.random.default_rng(5), int(4 * BEAT * FPS))
    loop = Motion.concatenate([one_bar] * (4 * BARS)).joint_positions()
    loop += np.random.default_rng(5).normal(scale=0.002, size=loop.shape)  # capture jitter
    looped = form_score(dance_self_similarity(loop), music)
    four_bars = phrase(np.random.default_rng(6), int(16 * BEAT * FPS))
    looped_four = form_score(dance_self_similarity(Motion.concatenate([four_bars] * BARS).joint_positions()), music)
    assert copied > fresh + 0.15
    assert fresh > looped == 0.0
    assert copied > looped_four + 0.25


def test_the_form_score_of_a_dance_reads_the_bars_it_covers_whole():
    music = music_self_similarity()
    positions = dance("ABAB")
    whole = form_score(dance_self_similarity(positions), music)
    assert dance_form_score(positions, bar_lines(positions)[:-1], music) == pytest.approx(whole)
    assert dance_form_score(positions[: len(positions) // 2], bar_lines(positions)[:-1], music) != pytest.approx(whole)
    assert dance_form_score(positions[:100], bar_lines(positions)[:-1], music) is None  # under four whole bars


def test_a_constant_self_similarity_scores_zero_not_nan():
    music = music_self_similarity()
    assert form_score(np.ones_like(music), music) == 0.0
    assert form_score(music, music) == pytest.approx(1.0)
    assert np.isnan(form_score(np.ones((3, 3)), np.eye(3)))  # no pair two bars apart but one
    with pytest.raises(Exception):
        form_score(np.ones((3, 3)), np.ones((4, 4)))


def test_bar_features_see_a_phrase_danced_elsewhere_and_facing_elsewhere_as_the_same():
    positions = dance("ABAB")
    features = dance_bar_features(positions, bar_lines(positions))
    assert features.shape == (4 * BARS, 8 * 24 * 3)
    assert np.abs(features[2 * BARS + 1:3 * BARS - 1] - features[1:BARS - 1]).max() < 1e-6
    assert np.linalg.norm(features[BARS + 1] - features[1]) > 0.5


def random_walk(seed, frames=600):
    """Smooth joint trajectories: velocities that wander."""
    rng = np.random.default_rng(seed)
    velocity = np.cumsum(rng.normal(scale=0.002, size=(frames, 24, 3)), axis=0)
    velocity -= velocity.mean(axis=0)
    return np.cumsum(velocity, axis=0) + rng.normal(size=(1, 24, 3))


def test_seam_steps_flag_a_jump_and_not_a_smooth_join():
    smooth = random_walk(7)
    (step, change), = seam_steps(smooth, [300])
    assert step < 1 and change < 1
    jumped = smooth.copy()
    jumped[300:] += np.array([0.3, 0.0, 0.0])
    (step, change), = seam_steps(jumped, [300])
    assert step > 1 and change > 1
    assert all(np.isnan(seam_steps(smooth, [0])[0]))


def test_seam_steps_at_a_loops_seam_are_the_loop_seam_figures():
    from choreo.metrics.loops import seam
    from choreo.motion.seam import next_cycle
    from tests.conftest import wandering_dance

    loop = wandering_dance(1, frames=90).replace(metadata={"loop": {"turn_degrees": 30.0, "travel_m": [0.2, 0.1]}})
    positions = Motion.concatenate([loop, next_cycle(loop, 2)]).joint_positions()
    assert seam_steps(positions, [loop.num_frames])[0] == pytest.approx(seam(loop), rel=1e-12)
