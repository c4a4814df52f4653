"""Tests of choreo.motion.stitch.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from choreo.motion import (
    Motion,
)
from tests.motion.helpers import counting_motion


@pytest.mark.survivor
def test_edits_copy_the_metadata():
    import choreo.motion.stitch as stitch

    motion = counting_motion(6, metadata={"genre": "waltz"})
    results = {
        "slice_frames": motion.slice_frames(1, 3),
        "concatenate": Motion.concatenate([motion, counting_motion(2)]),
        "resample same rate": motion.resample(30.0),
        "sample_frames": motion.sample_frames(np.array([0.5, 1.5])),
        "turned_and_moved": stitch.turned_and_moved(motion, 0.3, np.array([1.0, 0.0, 0.0])),
    }
    for name, result in results.items():
        assert result.metadata == {"genre": "waltz"}, name
        result.metadata["edited"] = True
        assert motion.metadata == {"genre": "waltz"}, name


@pytest.mark.survivor
def test_rotate_about_y_is_scipys_rotation():
    from choreo.motion.stitch import rotate_about_y

    points = np.array([[0.0, 0.0, 1.0], [1.0, 0.5, 0.0], [0.3, -0.2, -0.7]])
    for angle in [0.0, 0.4, -2.0]:
        expected = Rotation.from_euler("y", angle).apply(points)
        np.testing.assert_allclose(rotate_about_y(points, angle), expected, rtol=0, atol=1e-15)


# Frame 0: root at (1, 0.9, 2), hips across -z (facing +x, yaw 90 degrees); frame 1: root at
# (1.5, 0.95, 2), hips across +x (facing +z, yaw 0).
HAND_MADE = np.array([
    [[1.0, 0.9, 2.0], [1.0, 0.8, 1.9], [1.0, 0.8, 2.1]],
    [[1.5, 0.95, 2.0], [1.6, 0.85, 2.0], [1.4, 0.85, 2.0]],
])


@pytest.mark.survivor
def test_local_positions_of_a_hand_made_excerpt():
    from choreo.motion.stitch import local_positions

    # (p - (1, 0, 2)) turned by -90 degrees about y: (x, y, z) -> (-z, y, x)
    expected = [
        [[0.0, 0.9, 0.0], [0.1, 0.8, 0.0], [-0.1, 0.8, 0.0]],
        [[0.0, 0.95, 0.5], [0.0, 0.85, 0.6], [0.0, 0.85, 0.4]],
    ]
    np.testing.assert_allclose(local_positions(HAND_MADE), expected, rtol=0, atol=1e-12)


@pytest.mark.survivor
def test_frame_local_positions_of_a_hand_made_pair_of_poses():
    from choreo.motion.stitch import frame_local_positions

    expected = [
        [[0.0, 0.9, 0.0], [0.1, 0.8, 0.0], [-0.1, 0.8, 0.0]],
        [[0.0, 0.95, 0.0], [0.1, 0.85, 0.0], [-0.1, 0.85, 0.0]],
    ]
    np.testing.assert_allclose(frame_local_positions(HAND_MADE), expected, rtol=0, atol=1e-12)


@pytest.mark.survivor
def test_crossfade_ramps_by_k_plus_1_over_n_plus_1():
    from choreo.motion.stitch import crossfade

    outgoing = Motion(np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (3, 24, 1)))
    turn = Rotation.from_euler("y", np.pi / 2).as_quat(scalar_first=True)
    incoming_rotations = np.tile([1.0, 0, 0, 0], (5, 24, 1))
    incoming_rotations[:, 0] = turn
    incoming = Motion(np.tile([1.0, 0.0, 0.0], (5, 1)), incoming_rotations)
    out = crossfade(outgoing, incoming)
    np.testing.assert_allclose(out.root_positions[:, 0], [0.25, 0.5, 0.75, 1.0, 1.0], rtol=0, atol=1e-15)
    ramp = np.array([[0.25], [0.5], [0.75], [1.0], [1.0]])
    expected = Rotation.from_euler("y", np.pi / 2 * ramp).as_matrix()
    np.testing.assert_allclose(out.rotation_matrices()[:, 0], expected, rtol=0, atol=1e-12)
