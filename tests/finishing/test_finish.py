"""choreo.finishing.finish: every pass in order, given frames kept."""

import numpy as np

from choreo.finishing import finish

from ..motion.helpers import wobbly_walk


def test_finish_keeps_fixed_frames_with_the_new_passes():
    motion = wobbly_walk(speed=1.0)
    fixed = np.zeros(len(motion), bool)
    fixed[200:260] = True
    out = finish(motion, np.arange(0, len(motion), 15), constraints=fixed)
    np.testing.assert_array_equal(out.root_positions[fixed], motion.root_positions[fixed])
    np.testing.assert_array_equal(out.rotations[fixed], motion.rotations[fixed])
