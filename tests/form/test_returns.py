"""choreo.form.returns: a returning section danced as its first occurrence, re-timed onto its own
beats, placed where the dancer stands, joined without a seam."""

import numpy as np

from choreo.form.returns import JOIN_SECONDS, plan_returns, source_frames, with_returns
from choreo.metrics.form import phrase_distance, return_ratio, seam_steps
from choreo.motion import Motion
from choreo.music.form import parse_form

FPS = 30.0
SECTION = 8.0  # seconds: four bars at 120 bpm
BEATS = np.arange(0.0, 4 * SECTION, 0.5)
ABAB = parse_form("0=A,8=B,16=A,24=B", duration=4 * SECTION)


def wandering(seed: int, seconds: float = 4 * SECTION) -> Motion:
    """Smooth random joint rotations and a wandering root: a dance with no returns of its own."""
    rng = np.random.default_rng(seed)
    frames = int(seconds * FPS)
    steps = rng.normal(scale=0.02, size=(frames, 24, 3))
    axis_angle = np.cumsum(steps, axis=0)
    axis_angle -= np.linspace(0, 1, frames)[:, None, None] * axis_angle[-1]  # no drift over the dance
    root = np.cumsum(rng.normal(scale=0.005, size=(frames, 3)), axis=0) + [0.0, 0.9, 0.0]
    root[:, 1] = 0.9
    axis_angle[:, 0, 1] += np.linspace(0, 3.0, frames)  # the dancer turns as it goes
    return Motion.from_axis_angle(root, axis_angle, fps=FPS)


def test_a_return_maps_beat_onto_beat_and_stops_where_its_source_ends():
    beats = np.array([0, 15, 30, 45, 60, 80, 100, 120, 140], dtype=float)  # the tempo changes at frame 60
    start, frames = source_frames((60, 140), (0, 60), beats)
    assert start == 60
    assert np.allclose(frames[[0, 20, 40]], [0, 15, 30])  # beat k of the return onto beat k of the first
    assert frames[-1] <= 59 and len(frames) == 79  # the source's 4 beats, slower: 79 frames of the 80


def test_the_plan_leaves_afresh_what_the_user_fixed_or_the_style_changes():
    frames = int(4 * SECTION * FPS)
    assert [(r.section, r.first) for r in plan_returns(ABAB, BEATS, FPS, frames)] == [(2, 0), (3, 1)]
    fixed = np.zeros(frames, bool)
    fixed[int(20 * FPS)] = True
    assert [r.section for r in plan_returns(ABAB, BEATS, FPS, frames, fixed=fixed)] == [3]
    schedule = [(0.0, 16.0, "waltz"), (16.0, None, "rumba")]
    assert plan_returns(ABAB, BEATS, FPS, frames, schedule=schedule) == []
    mirrored = [r.mirrored for r in plan_returns(parse_form("0=A,8=A,16=A,24=A", 32.0), BEATS, FPS, frames, mirror=True)]
    assert mirrored == [True, False, True]


def test_a_returned_section_is_its_first_occurrence_placed_where_the_dancer_is_and_joined_smoothly():
    dance = wandering(0)
    plan = plan_returns(ABAB, BEATS, FPS, dance.num_frames)
    returned = with_returns(dance, plan)
    positions = returned.joint_positions()
    assert max(return_ratio(positions, FPS, ABAB, BEATS)) < 0.1
    assert min(return_ratio(dance.joint_positions(), FPS, ABAB, BEATS)) > 0.5
    joins = [int(round(t * FPS)) for entry in returned.metadata["returns"] for t in entry["seconds"]][:-1]
    assert all(step <= 1.0 and change <= 1.5 for step, change in seam_steps(positions, joins))
    untouched = plan[0].start - int(JOIN_SECONDS * FPS)  # before the bend into the first return
    assert np.allclose(returned.root_positions[:untouched], dance.root_positions[:untouched])
    start = plan[0].start
    assert np.allclose(returned.root_positions[start, [0, 2]], dance.root_positions[start, [0, 2]], atol=1e-6)


def test_exactness_blends_and_zero_leaves_the_dance_as_it_was():
    dance = wandering(1)
    plan = plan_returns(ABAB, BEATS, FPS, dance.num_frames)
    assert with_returns(dance, plan, exactness=0.0) is dance
    halfway = with_returns(dance, plan, exactness=0.5).joint_positions()
    exact, fresh = with_returns(dance, plan).joint_positions(), dance.joint_positions()
    span = (16.0, 24.0)
    half_to_first = phrase_distance(halfway, FPS, (0.0, 8.0), span, BEATS)
    assert phrase_distance(exact, FPS, (0.0, 8.0), span, BEATS) < half_to_first < phrase_distance(fresh, FPS, (0.0, 8.0), span, BEATS)


def test_a_given_path_keeps_its_place_and_a_mirrored_return_is_the_mirror_image():
    dance = wandering(2)
    plan = plan_returns(ABAB, BEATS, FPS, dance.num_frames, mirror=True)
    on_path = with_returns(dance, plan, keep_path=True)
    assert np.allclose(on_path.root_positions[:, [0, 2]], dance.root_positions[:, [0, 2]])
    positions = with_returns(dance, plan).joint_positions()
    assert phrase_distance(positions, FPS, (0.0, 8.0), (16.0, 24.0), BEATS, mirrored=True) < 0.05
    assert phrase_distance(positions, FPS, (0.0, 8.0), (16.0, 24.0), BEATS) > 0.05
