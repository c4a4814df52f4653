"""Foot lock: a planted foot's drift moves onto the root; fixed frames stay; moving feet are left alone."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import FootLockConfig, foot_lock
from choreo.finishing.foot_lock import planted_drift, root_correction
from choreo.metrics import foot_contact_score
from choreo.motion import Motion


def gliding(speed: float, frames: int = 90) -> Motion:
    """A dancer standing still in the rest pose while the whole body glides along x at ``speed`` m/s."""
    root = np.zeros((frames, 3))
    root[:, 0] = speed * np.arange(frames) / 30.0
    root[:, 1] = 0.9
    return Motion.rest(frames).replace(root_positions=root)


def horizontal_foot_steps(motion: Motion) -> np.ndarray:
    feet = motion.joint_positions()[:, [7, 8]] * [1.0, 0.0, 1.0]
    return np.linalg.norm(np.diff(feet, axis=0), axis=-1)


def test_drift_of_planted_feet_is_measured_horizontally():
    drift = planted_drift(gliding(0.3).joint_positions(), 30.0, 0.6)
    np.testing.assert_allclose(drift[:, 0], 0.01)  # 0.3 m/s = 1 cm per frame
    np.testing.assert_allclose(drift[:, 1:], 0.0)
    assert not planted_drift(gliding(1.5).joint_positions(), 30.0, 0.6).any()  # too fast to be planted


def test_sliding_feet_are_held_while_the_correction_lasts():
    dance = gliding(0.3)
    locked = foot_lock(dance)
    before, after = horizontal_foot_steps(dance), horizontal_foot_steps(locked)
    assert after[0] == pytest.approx(0.0, abs=1e-9)  # the first step is cancelled entirely
    tau = FootLockConfig().recovery_seconds * 30
    assert after[: int(tau)].mean() < 0.5 * before[: int(tau)].mean()
    # the correction leaks back: on a steady glide the body settles a fixed distance behind its own
    # path (the geometric series of 1 cm steps kept at exp(-1/tau) per frame), instead of stopping
    offset = 0.01 / (1 - np.exp(-1 / tau))
    assert np.abs(locked.root_positions[-1, 0] - dance.root_positions[-1, 0]) == pytest.approx(offset, rel=0.02)


def test_root_correction_matches_a_literal_loop():
    drift = np.zeros((5, 3))
    drift[:, 0] = [0.01, 0.02, 0.0, -0.01, 0.0]
    keep = np.exp(-1 / (0.5 * 30))
    expected, c = [0.0], 0.0
    for d in drift[:, 0]:
        c = keep * c - d
        expected.append(c)
    np.testing.assert_allclose(root_correction(drift, 30.0, np.zeros(6, bool), 0.5)[:, 0], expected)


def test_fixed_frames_keep_their_root_and_the_path_ramps_between_them():
    dance = gliding(0.3)
    fixed = np.zeros(dance.num_frames, bool)
    fixed[[0, 45, 89]] = True
    locked = foot_lock(dance, fixed)
    np.testing.assert_array_equal(locked.root_positions[fixed], dance.root_positions[fixed])
    steps = np.linalg.norm(np.diff(locked.root_positions, axis=0), axis=-1)
    assert steps.max() < 0.02  # no jump at the fixed frames
    assert not np.allclose(locked.root_positions, dance.root_positions)


def test_foot_lock_lowers_pfc_of_a_gliding_dancer():
    dance = gliding(0.3)
    root = dance.root_positions.copy()
    root[:, 0] += 0.05 * np.sin(np.arange(dance.num_frames) / 3.0)  # the root accelerates, so PFC counts the glide
    dance = dance.replace(root_positions=root)
    assert foot_contact_score(foot_lock(dance).joint_positions()) < 0.5 * foot_contact_score(dance.joint_positions())


def test_bad_settings_are_refused():
    with pytest.raises(ParameterError):
        FootLockConfig(recovery_seconds=0)
    with pytest.raises(ParameterError):
        foot_lock(gliding(0.3), np.zeros(3, bool))
