"""Inverse kinematics: SMPL-24 rotations that reproduce observed joint positions.

Positions-only datasets (M2D) must become rotations before the 151-d frame vector exists. The
fit has two stages: an analytic start that swings every observed bone onto its observed direction,
then a joint optimisation (6D rotations, differentiable FK, L-BFGS) of position error plus a
temporal smoothness term and a weak pull toward the rest pose for joints nothing observes (the
spine between belly and neck, the collars, twists).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ..skeleton import SMPL24, Skeleton, forward_kinematics_torch, matrix_to_quaternion, rot6d_to_matrix


@dataclass(frozen=True)
class IKConfig:
    iterations: int = 100  # L-BFGS iterations after the analytic start
    smoothness_weight: float = 1e-3  # on frame-to-frame change of the 6D parameters
    rest_prior_weight: float = 1e-5  # pulls unobserved degrees of freedom toward the rest pose


@dataclass
class IKResult:
    rotations: np.ndarray  # (T, 24, 4) local quaternions
    root_positions: np.ndarray  # (T, 3)
    skeleton: Skeleton  # the bone lengths the fit used
    per_joint_error: np.ndarray  # (K,) mean error per observed joint, metres


def nearest_observed_ancestor(joint: int, observed: set[int], parents=SMPL24.parents) -> int:
    parent = parents[joint]
    while parent >= 0 and parent not in observed:
        parent = parents[parent]
    return parent


def fit_bone_lengths(targets: np.ndarray, joints: list[int], base: Skeleton = SMPL24) -> Skeleton:
    """``base`` with each observed chain scaled to the median observed length of that chain.

    For an observed joint j whose nearest observed ancestor is a, all SMPL offsets on the path
    a -> j are scaled by median|p_j - p_a| / |rest(j) - rest(a)|. Medians over frames absorb the
    frame-to-frame length noise of marker-based capture.
    """
    offsets = base.offsets.copy()
    rest = base.rest_positions()
    observed = set(joints)
    column = {j: k for k, j in enumerate(joints)}
    for j in joints:
        a = nearest_observed_ancestor(j, observed, base.parents)
        if a < 0:
            continue
        measured = np.median(np.linalg.norm(targets[:, column[j]] - targets[:, column[a]], axis=-1))
        template = np.linalg.norm(rest[j] - rest[a])
        node = j
        while node != a:
            offsets[node] = base.offsets[node] * measured / template
            node = base.parents[node]
    return base.with_offsets(offsets)


def normalise_bone_lengths(targets: np.ndarray, joints: list[int], skeleton: Skeleton) -> np.ndarray:
    """Targets rebuilt from the root outward with every observed chain at ``skeleton``'s length.

    Marker data has bones that stretch by centimetres from frame to frame; rotations cannot
    express that, only directions. Keeping each observed direction and fixing its length makes
    the remaining fit error measure what rotations cannot reach, not capture noise.
    """
    column = {j: k for k, j in enumerate(joints)}
    rest = skeleton.rest_positions()
    observed = set(joints)
    out = targets.copy()
    for j in sorted(joints):
        a = nearest_observed_ancestor(j, observed, skeleton.parents)
        if a < 0:
            continue
        direction = targets[:, column[j]] - targets[:, column[a]]
        direction /= np.maximum(np.linalg.norm(direction, axis=-1, keepdims=True), 1e-9)
        out[:, column[j]] = out[:, column[a]] + direction * np.linalg.norm(rest[j] - rest[a])
    return out


def _best_rotation(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotations R minimising sum |R a_i - b_i|^2 for (T, N, 3) vectors (Kabsch).

    With one vector pair this is the smallest swing; its twist is then left at zero.
    """
    if source.shape[1] == 1:  # add a vector orthogonal to the pair so the SVD has a unique answer
        helper = np.cross(source[:, 0], target[:, 0])
        parallel = np.linalg.norm(helper, axis=-1) < 1e-9 * np.linalg.norm(source[:, 0], axis=-1)
        if parallel.any():  # any perpendicular axis works when the vectors already agree
            other = np.where(np.abs(source[:, 0, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
            helper[parallel] = np.cross(source[:, 0], other)[parallel]
        source = np.concatenate([source, helper[:, None]], axis=1)
        target = np.concatenate([target, helper[:, None]], axis=1)
    covariance = np.einsum("tni,tnj->tij", source, target)
    u, _, vt = np.linalg.svd(covariance)
    d = np.sign(np.linalg.det(np.swapaxes(vt, -1, -2) @ np.swapaxes(u, -1, -2)))
    fix = np.broadcast_to(np.eye(3), covariance.shape).copy()
    fix[:, 2, 2] = d
    return np.swapaxes(vt, -1, -2) @ fix @ np.swapaxes(u, -1, -2)


def analytic_start(targets: np.ndarray, joints: list[int], skeleton: Skeleton) -> np.ndarray:
    """(T, 24, 3, 3) local rotations: each observed joint turns its observed descendants into place.

    Unobserved joints keep their parent's orientation (identity local rotation); the observed
    joint above them accounts for the whole chain, e.g. the belly turns neck and shoulders at once.
    """
    frames = len(targets)
    column = {j: k for k, j in enumerate(joints)}
    rest = skeleton.rest_positions()
    observed = set(joints)
    identity = np.broadcast_to(np.eye(3), (frames, 3, 3))
    global_rot = np.broadcast_to(np.eye(3), (frames, 24, 3, 3)).copy()
    local = global_rot.copy()
    for j in range(24):
        parent = skeleton.parents[j]
        parent_rot = global_rot[:, parent] if parent >= 0 else identity
        below = [c for c in joints if c != j and nearest_observed_ancestor(c, observed, skeleton.parents) == j]
        if j in column and below:
            rest_vectors = np.einsum("tij,nj->tni", parent_rot, rest[below] - rest[j])
            seen = targets[:, [column[c] for c in below]] - targets[:, column[j]][:, None]
            global_rot[:, j] = _best_rotation(rest_vectors, seen) @ parent_rot
        else:
            global_rot[:, j] = parent_rot
        local[:, j] = np.swapaxes(parent_rot, -1, -2) @ global_rot[:, j]
    return local


def fit_rotations(targets: np.ndarray, joints: list[int], root_guess: np.ndarray, skeleton: Skeleton,
                  config: IKConfig = IKConfig()) -> IKResult:
    """Fit local rotations and root positions to ``targets`` (T, K, 3) observed at SMPL ``joints``."""
    start = analytic_start(targets, joints, skeleton)
    rot6d = torch.tensor(start[..., :2, :].reshape(len(targets), 24, 6), dtype=torch.float64, requires_grad=True)
    root = torch.tensor(root_guess, dtype=torch.float64, requires_grad=True)
    rest6d = torch.tensor([1.0, 0, 0, 0, 1, 0], dtype=torch.float64)
    target = torch.tensor(targets, dtype=torch.float64)
    offsets = torch.tensor(skeleton.offsets, dtype=torch.float64)
    index = list(joints)
    optimiser = torch.optim.LBFGS([rot6d, root], lr=1.0, max_iter=config.iterations, history_size=20,
                                  line_search_fn="strong_wolfe", tolerance_grad=1e-12, tolerance_change=1e-15)

    def objective():
        optimiser.zero_grad()
        positions = forward_kinematics_torch(rot6d_to_matrix(rot6d), root, offsets, skeleton.parents)
        data = ((positions[:, index] - target) ** 2).sum(-1).mean()
        smooth = ((rot6d[1:] - rot6d[:-1]) ** 2).sum(-1).mean() + ((root[1:] - root[:-1]) ** 2).sum(-1).mean()
        prior = ((rot6d - rest6d) ** 2).sum(-1).mean()
        loss = data + config.smoothness_weight * smooth + config.rest_prior_weight * prior
        loss.backward()
        return loss

    if config.iterations > 0:
        optimiser.step(objective)
    with torch.no_grad():
        rotmats = rot6d_to_matrix(rot6d)
        positions = forward_kinematics_torch(rotmats, root, offsets, skeleton.parents)
        errors = torch.linalg.norm(positions[:, index] - target, dim=-1).mean(0).numpy()
    return IKResult(matrix_to_quaternion(rotmats.numpy()), root.detach().numpy().copy(), skeleton, errors)
