"""What the skeleton's mutation run (scripts/mutation_score.py skeleton) found untested: the tree's
own checks and helpers, world orientations, rotations of 2-D batches, and that numpy inputs never
reach for torch."""

import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from choreo.skeleton import SMPL24, Skeleton, forward_kinematics, global_rotations
from choreo.skeleton.rotations import elementary_rotation, euler_to_matrix, matrix_to_quaternion


def chain(parents=(-1, 0, 1), offsets=None) -> Skeleton:
    return Skeleton(("a", "b", "c"), tuple(parents), np.eye(3) if offsets is None else offsets)


def test_a_skeleton_keeps_its_offsets_as_float64_and_checks_its_tree():
    tree = chain(offsets=[[0, 0, 0], [0, 1, 0], [2, 0, 0]])  # lists of ints in
    assert tree.offsets.dtype == np.float64 and tree.offsets.shape == (3, 3)
    with pytest.raises(ValueError, match="^one parent per joint is required$"):
        Skeleton(("a", "b"), (-1,), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="^parents must precede their children$"):
        chain(parents=(-1, 2, 1))
    with pytest.raises(ValueError, match="^parents must precede their children$"):
        chain(parents=(-1, 1, 1))  # a joint that is its own parent


def test_skeleton_helpers():
    tree = chain(parents=(-1, 0, 0), offsets=[[0, 0, 0], [0, 3, 4], [1, 0, 0]])
    assert tree.index("c") == 2 and tree.children(0) == [1, 2] and tree.children(2) == []
    np.testing.assert_allclose(tree.bone_lengths(), [0.0, 5.0, 1.0])
    moved = tree.with_offsets(np.array([[0, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=int))
    assert moved.offsets.dtype == np.float64 and moved.same_topology(tree)
    assert not tree.same_topology(chain(parents=(-1, 0, 1)))  # same names, other parents
    assert not tree.same_topology(Skeleton(("a", "b", "d"), (-1, 0, 0), np.zeros((3, 3))))


def test_global_rotations_compose_down_the_tree_and_agree_with_forward_kinematics():
    rng = np.random.default_rng(0)
    local = Rotation.random(2 * 24, random_state=1).as_matrix().reshape(2, 24, 3, 3)
    world = global_rotations(local, SMPL24.parents)
    for j, p in enumerate(SMPL24.parents):
        expected = local[:, j] if p < 0 else world[:, p] @ local[:, j]
        np.testing.assert_allclose(world[:, j], expected, atol=1e-12)
    np.testing.assert_allclose(world[:, 0], local[:, 0])  # the root's own
    np.testing.assert_allclose(world[:, 6], local[:, 0] @ local[:, 3] @ local[:, 6], atol=1e-12)  # pelvis, spine1, spine2
    root = rng.normal(size=(2, 3))
    positions = forward_kinematics(local, root, SMPL24.offsets, SMPL24.parents)
    for j, p in enumerate(SMPL24.parents):
        if p >= 0:  # a joint sits at its parent plus the parent's world rotation of its offset
            np.testing.assert_allclose(positions[:, j], positions[:, p] + world[:, p] @ SMPL24.offsets[j], atol=1e-12)


def test_elementary_and_euler_rotations_of_two_dimensional_batches():
    angles = np.random.default_rng(2).uniform(-3, 3, size=(4, 5))
    for axis in "XYZ":
        matrices = elementary_rotation(angles, axis)
        assert matrices.shape == (4, 5, 3, 3)
        expected = Rotation.from_euler(axis.lower(), angles.reshape(-1, 1)).as_matrix().reshape(4, 5, 3, 3)
        np.testing.assert_allclose(matrices, expected, atol=1e-12)
    triples = np.random.default_rng(3).uniform(-3, 3, size=(4, 5, 3))
    expected = Rotation.from_euler("ZXY", triples.reshape(-1, 3)).as_matrix().reshape(4, 5, 3, 3)
    np.testing.assert_allclose(euler_to_matrix(triples, "ZXY"), expected, atol=1e-12)


def test_a_half_turn_and_the_identity_convert_exactly():
    half_turn = np.diag([1.0, -1.0, -1.0])  # w = 0: the square root of exactly zero
    q = matrix_to_quaternion(half_turn)
    np.testing.assert_allclose(np.abs(q), [0.0, 1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(matrix_to_quaternion(np.eye(3)), [1.0, 0.0, 0.0, 0.0], atol=1e-15)
    small = Rotation.from_rotvec([0.3, 0.0, 0.0]).as_matrix()  # a trace-derived term between 0 and 1
    np.testing.assert_allclose(np.abs(matrix_to_quaternion(small)), np.abs(Rotation.from_matrix(small).as_quat()[[3, 0, 1, 2]]),
                               atol=1e-12)


def test_numpy_rotations_never_import_torch():
    code = ("import sys, numpy as np; from choreo.skeleton.rotations import quaternion_to_matrix, matrix_to_quaternion; "
            "matrix_to_quaternion(quaternion_to_matrix(np.array([1.0, 0, 0, 0]))); "
            "print('torch' in sys.modules, 'array_api_compat.numpy' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "False"]  # numpy itself, not the compat wrapper (0.2 s of imports)


def test_forward_kinematics_computes_in_float64():
    local = np.broadcast_to(np.eye(3, dtype=np.float32), (2, 24, 3, 3))
    positions = forward_kinematics(local, np.zeros((2, 3), np.float32), SMPL24.offsets.astype(np.float32), SMPL24.parents)
    assert positions.dtype == np.float64


def test_the_gradient_through_a_half_turn_is_finite():
    torch = pytest.importorskip("torch")
    matrix = torch.tensor(np.diag([1.0, -1.0, -1.0]), requires_grad=True)  # w = sqrt(0)
    matrix_to_quaternion(matrix).sum().backward()
    assert torch.isfinite(matrix.grad).all()
