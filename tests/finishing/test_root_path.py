"""The root path pass (choreo.finishing.root_path): the root's travel low-passed, given frames exact."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing.root_path import RootPathConfig, root_path
from choreo.metrics.whole_song import median_jerk
from choreo.motion.travel import pace

from ..motion.helpers import FPS, wobbly_walk


def test_root_path_pass_removes_wobble_and_keeps_fixed_frames_exactly():
    motion = wobbly_walk()
    fixed = np.zeros(len(motion), bool)
    fixed[100:130] = True
    out = root_path(motion, fixed, RootPathConfig(cutoff_hz=2.5))
    assert median_jerk(out.root_positions[:, None], FPS) < 0.2 * median_jerk(motion.root_positions[:, None], FPS)
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])
    np.testing.assert_allclose(out.rotations, motion.rotations, atol=1e-12)  # only the root moves
    assert pace(out.root_positions, FPS) == pytest.approx(pace(motion.root_positions, FPS), rel=0.01)
    with pytest.raises(ParameterError):
        RootPathConfig(cutoff_hz=0)
