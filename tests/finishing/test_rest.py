"""The rest pass: the dancer waits through a song's opening silence and stops in its closing one."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import RestConfig, finish, rest
from choreo.motion import Motion
from choreo.motion.beats import mean_joint_speed
from choreo.pipeline import Finishing

from ..motion.helpers import wobbly_walk

FPS = 30


def walk():
    return wobbly_walk(seconds=12.0, speed=0.5, wobble=0.0)  # 360 frames, arms swinging at 1 Hz


def test_the_dancer_stops_after_the_music_and_waits_before_it_and_dances_the_same_between():
    motion = walk()
    out = rest(motion, (60, 270))  # two silent seconds first, three last
    speed = mean_joint_speed(out.joint_positions()) * FPS
    # the poses held are the stillest within 0.5 s (15 frames) of the music's ends, reached over 1 s of easing
    assert np.all(speed[:30] < 1e-9) and np.all(speed[300:] < 1e-9)  # standing still in the silences
    middle = slice(90, 240)  # the dance's own timing, frame for frame
    np.testing.assert_array_equal(out.rotations[middle], motion.rotations[middle])
    np.testing.assert_array_equal(out.root_positions[middle], motion.root_positions[middle])
    assert out.metadata["rest"] == {"waits_until": 2.0, "rests_from": 9.0}


def test_it_slows_to_a_stop_and_sets_off_without_a_jump():
    motion = walk()
    out = rest(motion, (60, 270))
    before, after = mean_joint_speed(motion.joint_positions()), mean_joint_speed(out.joint_positions())
    assert after.max() <= before.max() + 1e-9  # re-timed at playback speeds of at most 1: nothing is faster
    root_steps = np.linalg.norm(np.diff(out.root_positions, axis=0), axis=-1)
    assert root_steps.max() <= np.linalg.norm(np.diff(motion.root_positions, axis=0), axis=-1).max() + 1e-9
    slowing = after[235:300]  # the ease into the final pose is gradual, not a cut
    assert np.sum((slowing > 0.2 * before.max()) & (slowing < 0.8 * before.max())) >= 5


def test_the_pose_held_has_both_feet_on_the_floor_even_where_a_raised_leg_is_stiller():
    t = np.arange(360) / FPS
    axis_angle = np.zeros((360, 24, 3))
    axis_angle[:, 16:22] = 0.3 * np.sin(2 * np.pi * t)[:, None, None]  # the walk's arms
    axis_angle[262:, 1, 0] = -1.2  # the left leg lifted from frame 262 on and held: past the lift, the stillest frames
    lifted = Motion.from_axis_angle(walk().root_positions, axis_angle, fps=FPS)
    ankles = lifted.joint_positions()[:, [7, 8], 1]
    standing = np.median(ankles.min(axis=1))
    assert ankles[275:].max() - standing > 0.2  # the leg is well up where the music ends
    held = rest(lifted, (60, 270)).joint_positions()[-1, [7, 8], 1]
    assert np.all(held - standing < 0.03)  # the dancer stops on both feet, not frozen on one leg


def test_short_silences_are_danced_through_and_a_song_without_one_is_unchanged():
    motion = walk()
    assert rest(motion, (20, 345)) is motion  # 0.7 s and 0.5 s: under a second each
    assert rest(motion, (0, 360)) is motion
    assert rest(motion, None) is motion
    assert rest(motion, (170, 174)) is motion  # a click, not music: no time to set off and stop


def test_a_short_burst_of_music_gets_quicker_eases_and_stillness_around_it():
    motion = walk()
    out = rest(motion, (150, 190))  # 1.3 s of music in 12 s
    speed = mean_joint_speed(out.joint_positions())
    assert np.all(speed[:135] < 1e-9) and np.all(speed[205:] < 1e-9)
    assert speed[160:180].min() > 0.5 * mean_joint_speed(motion.joint_positions()).mean()  # dancing in between


def test_an_end_with_a_fixed_frame_keeps_its_timing_and_the_other_rests():
    motion = walk()
    fixed = np.zeros(len(motion), bool)
    fixed[340] = True  # a key in the closing silence
    out = rest(motion, (60, 270), fixed)
    np.testing.assert_array_equal(out.rotations[90:], motion.rotations[90:])
    assert np.all(mean_joint_speed(out.joint_positions())[:30] < 1e-9)
    assert out.metadata["rest"] == {"waits_until": 2.0, "rests_from": 12.0}


def test_finish_rests_only_when_told_where_the_music_is_and_the_pass_is_on():
    motion = walk()
    beats = np.arange(70, 270, 15)
    rested = finish(motion, beats, audible=(60, 270))
    assert np.all(mean_joint_speed(rested.joint_positions())[300:] < 1e-9)
    plain = finish(motion, beats)
    off = finish(motion, beats, Finishing(rest=False), audible=(60, 270))
    np.testing.assert_array_equal(off.rotations, plain.rotations)
    assert "rest" not in plain.metadata


def test_bad_settings_are_refused():
    with pytest.raises(ParameterError):
        RestConfig(ease_seconds=0)
    with pytest.raises(ParameterError):
        rest(walk(), (60, 270), np.zeros(3, bool))


def test_finish_keeps_a_seed_motion_given_in_the_opening_silence_exactly():
    motion = walk()
    fixed = np.zeros(len(motion), bool)
    fixed[:20] = True  # a seed motion over the first frames, in the silence before the music
    out = finish(motion, np.arange(70, 270, 15), constraints=fixed, audible=(60, 270))
    np.testing.assert_array_equal(out.rotations[fixed], motion.rotations[fixed])
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])
    assert out.metadata["rest"]["waits_until"] == 0.0 and out.metadata["rest"]["rests_from"] == 9.0
