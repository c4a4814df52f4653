"""choreo.finishing.finish: every pass in order, given frames kept."""

from dataclasses import replace

import numpy as np
import pytest

from choreo.finishing import (AccentConfig, BeatLockConfig, FootLockConfig, FootstepsConfig, PaceConfig, RootPathConfig,
                              SpeedLimitConfig, accent, beat_lock, finish, foot_lock, footsteps, pace, root_path,
                              speed_limit)
from choreo.pipeline import Finishing

from ..motion.helpers import wobbly_walk


def test_finish_keeps_fixed_frames_with_the_new_passes():
    motion = wobbly_walk(speed=1.0)
    fixed = np.zeros(len(motion), bool)
    fixed[200:260] = True
    out = finish(motion, np.arange(0, len(motion), 15), constraints=fixed)
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])
    np.testing.assert_array_equal(out.rotations[fixed], motion.rotations[fixed])


def by_hand(motion, beats, on: Finishing, fixed, configs: dict):
    """The passes one by one, in the order finish() documents, each with its config."""
    motion = speed_limit(motion, fixed, configs["speed_limit"]) if on.speed_limit else motion
    motion = root_path(motion, fixed, configs["root_path"]) if on.root_path else motion
    motion = pace(motion, fixed, configs["pace"]) if on.pace else motion
    motion = accent(motion, fixed, configs["accent"]) if on.accent else motion
    motion = footsteps(motion, fixed, configs["footsteps"]) if on.footsteps else motion
    motion = beat_lock(motion, beats, fixed, configs["beat_lock"]).motion if on.beat_lock else motion
    motion = foot_lock(motion, fixed, configs["foot_lock"]) if on.foot_lock else motion
    if on.speed_limit and (on.beat_lock or on.foot_lock or on.footsteps):
        motion = speed_limit(motion, fixed, configs["speed_limit"])
    return motion


CONFIGS = {"speed_limit": SpeedLimitConfig(joint_speed=1.5), "root_path": RootPathConfig(cutoff_hz=1.5),
           "pace": PaceConfig(max_scale=1.5), "accent": AccentConfig(depth=0.4), "footsteps": FootstepsConfig(strength=0.3),
           "beat_lock": BeatLockConfig(max_shift_seconds=0.2), "foot_lock": FootLockConfig(speed_threshold=2.0)}
ONLY = dict(speed_limit=False, root_path=False, pace=False, accent=False, footsteps=False, beat_lock=False, foot_lock=False)


@pytest.mark.parametrize("on", [
    Finishing(),  # every default pass: each must get its own config
    Finishing(**{**ONLY, "speed_limit": True, "beat_lock": True}),  # the last speed limit after the beat lock alone
    Finishing(**{**ONLY, "speed_limit": True, "foot_lock": True}),  # ... after the foot lock alone
    Finishing(**{**ONLY, "speed_limit": True, "footsteps": True}),  # ... after the footsteps alone
    Finishing(**{**ONLY, "beat_lock": True}),  # no speed limit at all
    Finishing(**{**ONLY, "speed_limit": True}),  # the speed limit once
], ids=["defaults", "beat-lock", "foot-lock", "footsteps", "no-speed-limit", "speed-limit-only"])
def test_finish_runs_each_pass_in_order_with_the_config_finishing_gives_it(on):
    motion = wobbly_walk(seconds=32.0, speed=1.0, wobble=0.05)
    beats = np.arange(7, len(motion), 16)
    fixed = np.zeros(len(motion), bool)
    fixed[300:320] = True
    out = finish(motion, beats, replace(on, configs=CONFIGS), constraints=fixed)
    np.testing.assert_array_equal(out.rotations, by_hand(motion, beats, on, fixed, CONFIGS).rotations)
    np.testing.assert_array_equal(out.root_positions, by_hand(motion, beats, on, fixed, CONFIGS).root_positions)
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])


def test_each_config_changes_the_dance():
    """Otherwise the test above could not tell a config given from one ignored."""
    motion = wobbly_walk(seconds=32.0, speed=1.0, wobble=0.05)
    beats = np.arange(7, len(motion), 16)
    for name, config in CONFIGS.items():
        on = Finishing(**{**ONLY, name: True})
        plain, tuned = finish(motion, beats, on), finish(motion, beats, replace(on, configs={name: config}))
        assert not np.allclose(plain.joint_positions(), tuned.joint_positions(), atol=1e-6), name
