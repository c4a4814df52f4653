"""choreo.motion.delivery: a finished dance at another frame rate, without its travel, or with its
travel on a root bone."""

import numpy as np
import pytest

from choreo.errors import MotionFormatError, ParameterError
from choreo.motion import Motion
from choreo.motion.delivery import ROOT_BONE, at_fps, delivered, floor_height, in_place, with_root_bone
from choreo.motion.delivery_options import check_fps, check_travel
from choreo.motion.filters import low_pass
from choreo.motion.travel import ground_track
from choreo.skeleton import SMPL24, Skeleton, quaternion_multiply, quaternion_to_matrix

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


def circling_dancer(seconds: float = 60.0, radius: float = 2.0, twist_degrees: float = 30.0) -> Motion:
    """A dancer going once round a circle facing where it goes, swaying 5 cm at 1.5 Hz and twisting
    its hips by ``twist_degrees`` at 2 Hz: travel, facing and what an engine's capsule should not inherit."""
    frames = int(seconds * FPS)
    t = np.arange(frames) / FPS
    angle = 2 * np.pi * t / seconds
    root = np.stack([radius * np.sin(angle), np.full(frames, 0.9), radius * np.cos(angle)], -1)
    root[:, 0] += 0.05 * np.sin(2 * np.pi * 1.5 * t)
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 0, 1] = angle + np.pi / 2 + np.radians(twist_degrees) * np.sin(2 * np.pi * 2.0 * t)
    axis_angle[:, 4, 0] = 0.4 * np.clip(np.sin(2 * np.pi * 1.0 * t), 0, None)  # a knee bending: one foot lifts
    return Motion.from_axis_angle(root, axis_angle, fps=FPS)


def heading(quaternions: np.ndarray) -> np.ndarray:
    """Unwrapped turn about Y of (T, 4) rotations (of +Z, projected on the floor)."""
    forward = quaternion_to_matrix(quaternions)[:, :, 2]
    return np.unwrap(np.arctan2(forward[:, 0], forward[:, 2]))


def test_the_root_bone_stands_on_the_floor_and_carries_the_travel_smoothly():
    dancer = circling_dancer()
    under, hips = with_root_bone(dancer)
    bone = under.root_positions
    lowest = dancer.joint_positions()[..., 1].min(axis=1)
    assert np.abs(bone[:, 1] - np.median(lowest)).max() < 1e-9 and np.ptp(bone[:, 1]) == 0  # the floor, as the feet find it
    assert abs(floor_height(dancer) - (0.9 - 0.956)) < 0.01
    track = ground_track(dancer.root_positions, FPS)
    np.testing.assert_allclose(bone[[0, -1]][:, [0, 2]], track[[0, -1]], atol=0.01)  # the whole way round
    assert np.linalg.norm(bone[:, [0, 2]] - track, axis=-1).max() < 0.05
    smooth = low_pass(bone[:, [0, 2]], FPS, 1.0)
    assert np.linalg.norm(bone[:, [0, 2]] - smooth, axis=-1).max() < 0.01  # within 1 cm of its own 1 Hz low-pass
    assert np.linalg.norm(hips[:, [0, 2]], axis=-1).max() < 0.5  # the hips stay near it
    assert np.ptp(hips[:, 0]) > 0.08  # and keep their sway: the bone does not follow it


def test_the_dance_under_the_root_bone_is_the_same_dance():
    dancer = circling_dancer(seconds=10.0)
    under, hips = with_root_bone(dancer)
    assert under.skeleton.names == (ROOT_BONE, *SMPL24.names)
    assert under.skeleton.parents == (-1, 0, *(p + 1 for p in SMPL24.parents[1:]))
    standing = -SMPL24.rest_positions()[:, 1].min()
    np.testing.assert_allclose(under.skeleton.offsets[1], [0.0, standing, 0.0])  # the rest pose stands on the bone
    np.testing.assert_allclose(under.skeleton.offsets[2:], SMPL24.offsets[1:])
    turn = quaternion_to_matrix(under.rotations[:, 0])
    world = under.root_positions + np.einsum("tij,tj->ti", turn, hips)
    np.testing.assert_allclose(world, dancer.root_positions, atol=1e-9)
    pelvis = quaternion_multiply(under.rotations[:, 0], under.rotations[:, 1])
    np.testing.assert_allclose(quaternion_to_matrix(pelvis), quaternion_to_matrix(dancer.rotations[:, 0]), atol=1e-9)
    np.testing.assert_allclose(under.rotations[:, 2:], dancer.rotations[:, 1:])


def test_the_root_bone_turns_with_the_dancer_but_not_with_the_hips_twist():
    dancer = circling_dancer(twist_degrees=30.0)
    under, _ = with_root_bone(dancer)
    facing = heading(under.rotations[:, 0])
    steady = heading(circling_dancer(twist_degrees=0.0).rotations[:, 0])  # once round, facing where it goes
    middle = slice(len(facing) // 10, -len(facing) // 10)  # the ends keep their frame's own heading
    assert np.abs(facing - steady)[middle].max() < np.radians(2)  # the 30 degree twist stays in the hips
    np.testing.assert_allclose(under.rotations[:, 0, [1, 3]], 0.0, atol=1e-12)  # a turn about Y only


def test_a_skeleton_that_already_has_a_root_joint_is_refused():
    names = ("root", *SMPL24.names[1:])
    dancer = Motion.rest(3, skeleton=Skeleton(names, SMPL24.parents, SMPL24.offsets))
    with pytest.raises(MotionFormatError, match="already has a joint named 'root'"):
        with_root_bone(dancer)


def test_in_place_and_root_motion_are_refused_together():
    check_travel(True, False)
    check_travel(False, True)
    with pytest.raises(ParameterError, match="^--in-place and --root-motion exclude each other"):
        check_travel(True, True)


def test_delivery_is_checked_when_made_and_delivers_as_delivered():
    from choreo.errors import ParameterError
    from choreo.motion.delivery_options import Delivery

    with pytest.raises(ParameterError, match="--fps must be 10 to 240, got 5"):
        Delivery(fps=5)
    with pytest.raises(ParameterError, match="exclude each other"):
        Delivery(in_place=True, root_motion=True)
    motion = circling_dancer(4.0)
    at_60 = Delivery(fps=60, in_place=True).of(motion)
    expected = delivered(motion, 60, True)
    assert at_60.fps == 60 and np.array_equal(at_60.root_positions, expected.root_positions)
