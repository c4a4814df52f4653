"""Footsteps (choreo.finishing.footsteps): feet that stand until the body leaves them, then step."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import finish
from choreo.finishing.footsteps import (DEFAULT_STRENGTH, GENRE_STRENGTH, HORIZONTAL, FootstepsConfig, footsteps,
                                        plan_steps)
from choreo.metrics.stepping import stepping
from choreo.motion import Motion
from choreo.motion.filters import fixed_weights
from choreo.pipeline import Finishing
from choreo.skeleton.legs import LEGS

FPS = 30.0


def glider(seconds: float = 4.0, speed: float = 0.6, seed: int = 0) -> Motion:
    """A body gliding forward at ``speed`` with slightly bent, gently moving legs: the generated
    dancer's fault in its plainest form."""
    frames = int(seconds * FPS)
    rng = np.random.default_rng(seed)
    axis_angle = np.zeros((frames, 24, 3))
    for hip, knee, _ in LEGS:
        axis_angle[:, hip, 0] = -0.3 + 0.05 * np.sin(np.arange(frames) / 7 + hip)
        axis_angle[:, knee, 0] = 0.5 + 0.05 * np.sin(np.arange(frames) / 5 + knee)
    axis_angle[:, 16:22] += rng.normal(scale=0.05, size=(frames, 6, 3))  # arms that move
    root = np.zeros((frames, 3))
    root[:, 1] = 0.88
    root[:, 2] = speed * np.arange(frames) / FPS
    return Motion.from_axis_angle(root, axis_angle, fps=FPS)


def test_planned_feet_stand_between_steps_and_step_one_at_a_time():
    wanted = glider().joint_positions()[:, [7, 8]]
    config = FootstepsConfig()
    planned = plan_steps(wanted, FPS, config)
    moving = np.linalg.norm(np.diff(planned, axis=0) * HORIZONTAL, axis=-1) > 1e-9  # (T-1, 2)
    assert not (moving[:, 0] & moving[:, 1]).any()  # never both feet in the air
    assert moving[:, 0].any() and moving[:, 1].any()  # both feet step
    assert 0.3 < moving.any(axis=1).mean() < 0.9  # standing phases between steps
    drift = np.linalg.norm((planned - wanted) * HORIZONTAL, axis=-1)
    # a foot waits at most for the other's swing, then swings itself: never further behind than that
    assert drift.max() < config.trigger + 2 * 0.6 * config.swing_seconds + 0.02


def test_a_body_that_stays_keeps_its_feet_still():
    still = glider(speed=0.0)
    wanted = still.joint_positions()[:, [7, 8]]
    drift = np.linalg.norm((wanted - wanted[:1]) * HORIZONTAL, axis=-1).max()  # the legs sway a little
    planned = plan_steps(wanted, FPS, FootstepsConfig(trigger=drift + 0.01))
    assert np.abs(planned - wanted[:1]).max() < 1e-12  # no step: both feet where they began


FULL = FootstepsConfig(strength=1.0)


def test_steps_move_only_the_legs_and_reach_their_targets():
    motion = glider()
    out = footsteps(motion, config=FULL)
    before, after = motion.joint_positions(), out.joint_positions()
    np.testing.assert_array_equal(out.root_positions, motion.root_positions)
    upper = [j for j in range(24) if j not in (1, 2, 4, 5, 7, 8, 10, 11)]
    np.testing.assert_allclose(after[:, upper], before[:, upper], atol=1e-9)
    planned = plan_steps(before[:, [7, 8]], FPS, FULL)
    leg = np.linalg.norm(before[0, 4] - before[0, 1]) + np.linalg.norm(before[0, 7] - before[0, 4])
    reachable = np.linalg.norm(planned - before[:, [1, 2]], axis=-1) < leg - 0.01
    assert reachable.mean() > 0.8
    assert np.linalg.norm(after[:, [7, 8]] - planned, axis=-1)[reachable].max() < 1e-6  # met where the leg reaches
    feet_world = lambda m: m.rotation_matrices()  # noqa: E731
    from choreo.skeleton.kinematics import global_rotations
    parents = motion.skeleton.parents
    np.testing.assert_allclose(global_rotations(feet_world(out), parents)[:, [7, 8]],
                               global_rotations(feet_world(motion), parents)[:, [7, 8]], atol=1e-6)  # feet keep their turn


def test_steps_turn_a_glide_into_stepping():
    motion = glider()
    glide, walk = stepping(motion.joint_positions(), FPS), stepping(footsteps(motion, config=FULL).joint_positions(), FPS)
    assert glide.planted_share < 0.1 and glide.support_slide > 0.85
    assert walk.planted_share > 0.5 and walk.support_slide < 0.3


def test_strength_takes_the_ankles_part_of_the_way():
    motion = glider()
    before = motion.joint_positions()[:, [7, 8]]
    planned = plan_steps(before, FPS, FULL)
    for strength in (0.0, 0.6):
        after = footsteps(motion, config=FootstepsConfig(strength=strength)).joint_positions()[:, [7, 8]]
        wanted = before + strength * (planned - before)
        assert np.median(np.linalg.norm(after - wanted, axis=-1)) < 1e-6  # where the leg reaches
    with pytest.raises(ParameterError):
        FootstepsConfig(strength=1.5)


def test_the_default_strength_is_the_dance_genres():
    motion = glider()
    assert GENRE_STRENGTH["cha-cha"] > DEFAULT_STRENGTH  # Latin feet follow the body less: more of the plan
    for genre, strength in (("cha-cha", GENRE_STRENGTH["cha-cha"]), ("waltz", DEFAULT_STRENGTH), (None, DEFAULT_STRENGTH)):
        dance = motion.replace(metadata={"genre": genre})
        np.testing.assert_array_equal(footsteps(dance).rotations,
                                      footsteps(dance, config=FootstepsConfig(strength=strength)).rotations)
    np.testing.assert_array_equal(footsteps(motion).rotations,  # a motion no backend labelled
                                  footsteps(motion, config=FootstepsConfig(strength=DEFAULT_STRENGTH)).rotations)
    assert not np.array_equal(footsteps(motion.replace(metadata={"genre": "cha-cha"})).rotations, footsteps(motion).rotations)


def test_fixed_frames_stay_exact_and_the_correction_fades_in():
    motion = glider()
    fixed = np.zeros(motion.num_frames, bool)
    fixed[:20] = fixed[-10:] = True
    out = footsteps(motion, fixed)
    np.testing.assert_array_equal(out.rotations[fixed], motion.rotations[fixed])
    weights = fixed_weights(fixed, FPS, 0.3)
    assert weights[19] == 0 and weights[20] == pytest.approx(1 / 9) and weights[60] == 1
    assert footsteps(motion, np.ones(motion.num_frames, bool)) is motion


def test_fixed_weights_ramp_from_the_nearest_fixed_frame():
    rng = np.random.default_rng(3)
    for _ in range(50):
        fixed = rng.random(int(rng.integers(1, 400))) < rng.choice([0.005, 0.05, 0.5])
        frames = np.arange(len(fixed))
        if fixed.any():  # what the weights were before: a frames x fixed-frames table
            nearest = np.abs(frames[:, None] - np.flatnonzero(fixed)[None]).min(axis=1)
            expected = np.clip(nearest / 9.0, 0.0, 1.0)
        else:
            expected = np.ones(len(fixed))
        np.testing.assert_array_equal(fixed_weights(fixed, FPS, 0.3), expected)


def test_other_skeletons_and_short_dances_pass_through():
    from choreo.skeleton import Skeleton

    motion = glider(seconds=1.0)
    assert footsteps(motion.slice_frames(0, 2)) .num_frames == 2
    parents = list(motion.skeleton.parents)
    parents[7] = 0  # an ankle hanging from the pelvis: not SMPL-24's legs
    other = Skeleton(motion.skeleton.names, tuple(parents), motion.skeleton.offsets)
    odd = Motion(motion.root_positions, motion.rotations, fps=FPS, skeleton=other)
    assert footsteps(odd) is odd
    with pytest.raises(ParameterError):
        footsteps(motion, np.zeros(3, bool))
    with pytest.raises(ParameterError):
        FootstepsConfig(trigger=0)


def test_finish_runs_the_planner_when_asked():
    motion = glider()
    plain = finish(motion, np.array([]), Finishing(beat_lock=False, speed_limit=False, footsteps=False, root_path=False,
                                                   pace=False, accent=False))
    stepped = finish(motion, np.array([]), Finishing(beat_lock=False, speed_limit=False, root_path=False))  # on by default
    assert plain is motion
    before, after = (stepping(m.joint_positions(), FPS) for m in (motion, stepped))
    assert after.planted_share > 0.2 > before.planted_share and after.support_slide < 0.5 * before.support_slide


def test_long_dances_are_turned_a_chunk_at_a_time_with_the_same_result(monkeypatch):
    import choreo.motion.motion as module  # every chunked loop takes its size from choreo.motion.motion.frame_chunks

    motion = glider(seconds=2.0)
    whole = footsteps(motion)
    monkeypatch.setattr(module, "FRAME_CHUNK", 7)
    np.testing.assert_array_equal(footsteps(motion).rotations, whole.rotations)


def test_a_root_path_leaves_the_legs_free_to_step_but_given_legs_stay():
    from choreo.constraints import Constraints

    motion = glider()
    constraints = Constraints.none(motion.num_frames, FPS)
    constraints.root[:], constraints.root_known[:] = motion.root_positions, True  # a root path
    constraints = constraints.fix_motion(motion.slice_frames(0, 10), joints=[4], root=False)  # and the left knee, 10 frames
    fixed, legs = constraints.fixed_frames(), constraints.frames_fixing((1, 2, 4, 5, 7, 8))
    assert fixed.all() and legs.sum() == 10
    out = finish(motion, np.array([]), Finishing(), constraints)  # the pass finds the legs' frames itself
    np.testing.assert_array_equal(out.root_positions, motion.root_positions)
    np.testing.assert_array_equal(out.rotations[legs], motion.rotations[legs])
    assert stepping(out.joint_positions(), FPS).planted_share > stepping(motion.joint_positions(), FPS).planted_share + 0.2
