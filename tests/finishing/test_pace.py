"""The pace pass (choreo.finishing.pace): a whole song's travel brought toward its genre's pace."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing.pace import ANY_GENRE_PACE, REAL_PACE, PaceConfig, pace as pace_pass, target_pace, travel_scale
from choreo.motion.travel import ground_track, pace

from ..motion.helpers import FPS, wobbly_walk


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
    out = pace_pass(motion)
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
    assert pace_pass(short) is short  # a few seconds have no pace to speak of
    fixed = np.zeros(len(motion), bool)
    fixed[0] = True
    assert pace_pass(motion, fixed) is motion
    unlabelled = motion.replace(metadata={})
    assert pace_pass(unlabelled) is unlabelled
    assert pace_pass(motion.replace(metadata={"genre": "breaking"})).root_positions is motion.root_positions
    assert target_pace(None) == ANY_GENRE_PACE and target_pace("waltz") == REAL_PACE["waltz"]
