"""The accent pass: motion beats marked more clearly, kept on their frames, given frames kept."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import AccentConfig, accent
from choreo.finishing.accent import accent_warp
from choreo.metrics.whole_song import beat_dip
from choreo.motion.beats import motion_beats

from ..motion.helpers import wobbly_walk


def swaying(seconds: float = 12.0):
    """A walk whose arms swing at 1 Hz: soft motion beats where they turn, twice a second."""
    return wobbly_walk(seconds=seconds, speed=0.5, wobble=0.0)


def test_the_warp_slows_at_the_beats_keeps_them_and_the_stretches_between():
    beats = np.array([10, 25, 45, 60])
    source = accent_warp(beats, 80, 0.2, np.zeros(80, bool))
    np.testing.assert_allclose(source[beats], beats)  # every beat on its frame, so every stretch keeps its length
    np.testing.assert_array_equal(source[:11], np.arange(11))  # the identity outside the first and last beat
    np.testing.assert_array_equal(source[60:], np.arange(60, 80))
    speed = np.diff(source)
    assert np.all(speed > 0)  # monotone: nothing plays backwards
    assert speed[10] < 0.85 and speed[24] < 0.85 and speed[17] > 1.15  # slow at the beats, fast between


def test_a_fixed_frame_keeps_its_whole_stretch_as_it_was():
    fixed = np.zeros(80, bool)
    fixed[30] = True
    source = accent_warp(np.array([10, 25, 45, 60]), 80, 0.3, fixed)
    np.testing.assert_array_equal(source[25:46], np.arange(25, 46))
    assert not np.allclose(source[11:25], np.arange(11, 25))


def test_the_dance_marks_its_beats_more_and_keeps_them_and_given_frames():
    motion = swaying()
    fixed = np.zeros(motion.num_frames, bool)
    fixed[150:170] = True
    out = accent(motion, fixed, AccentConfig(depth=0.3))
    before, after = motion.joint_positions(), out.joint_positions()
    assert beat_dip(after) > beat_dip(before) + 0.05
    beats = motion_beats(before)
    assert len(beats) > 10
    # the motion beats stay where they were (within a frame: the smoothed speed's minimum may tilt by rounding)
    moved = [np.abs(motion_beats(after) - b).min() for b in beats[1:-1]]
    assert max(moved) <= 1
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])
    np.testing.assert_array_equal(out.rotations[fixed], motion.rotations[fixed])
    assert out.num_frames == motion.num_frames


def test_depth_zero_is_the_dance_itself_and_bad_depths_are_refused():
    motion = swaying(seconds=3.0)
    assert accent(motion, None, AccentConfig(depth=0.0)) is motion
    for depth in (-0.1, 1.0, float("nan")):
        with pytest.raises(ParameterError):
            AccentConfig(depth=depth)


def test_dances_without_two_motion_beats_or_free_frames_are_left_as_they_are():
    motion = swaying(seconds=3.0)
    assert accent(motion, np.ones(motion.num_frames, bool)) is motion  # every frame given
    assert accent(motion.slice_frames(0, 2)).num_frames == 2
    still = wobbly_walk(seconds=2.0, speed=0.0, wobble=0.0)  # the arms swing, nothing else: one beat at most
    still.rotations[:] = still.rotations[:1]
    assert len(motion_beats(still.joint_positions())) < 2 and accent(still) is still


def test_a_backends_clip_timeline_follows_the_re_timing():
    from choreo.finishing.beat_lock import retimed_span

    motion = swaying(seconds=6.0)
    spans = [[0, 40], [41, 100], [101, 179]]
    motion.metadata = {"clips": [{"clip": str(i), "output_frames": list(span)} for i, span in enumerate(spans)]}
    out = accent(motion, None, AccentConfig(depth=0.9))
    source = accent_warp(motion_beats(motion.joint_positions()), motion.num_frames, 0.9, np.zeros(180, bool))
    expected = [retimed_span(span, source) for span in spans]
    assert [clip["output_frames"] for clip in out.metadata["clips"]] == expected != spans
    assert [clip["output_frames"] for clip in motion.metadata["clips"]] == spans  # the input's metadata untouched
