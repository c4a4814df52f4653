"""Inverse kinematics: SMPL-24 local rotations (and a root path) that reproduce observed joint positions.

Datasets that ship only joint positions (M2D) must become rotations before generators can train on
them. Nothing here knows about a particular dataset: the caller says which SMPL joints it observed
(``joints``) and gives their positions per frame (``targets``, metres, Y up).

The fit has three parts:

1. :func:`performer_skeleton` - SMPL-24 with its bones rescaled to the performer. A marker set's
   joint spacing rarely matches SMPL's template (and varies by centimetres from frame to frame), so
   each bone chain between two observed joints is scaled to the median observed distance. When
   the root itself is not observed, the shape of the joints hanging directly off it (e.g. two hips
   and a lower-back marker) is taken from the data as a Procrustes mean, because no single scale
   can match SMPL's narrow, low-set hip joints to markers on the outside of the hips.
2. :func:`initial_pose` - an analytic start: every observed joint turns the template vectors to its
   observed descendants onto the observed ones (Kabsch; a minimal swing for a single child), the
   root's orientation and position come from the rigid fit of its own group of observed joints.
3. :func:`fit_rotations` - joint refinement of all frames at once: 6D rotations and root positions
   through differentiable forward kinematics, minimised with L-BFGS. The loss is position error
   plus a frame-to-frame smoothness term on the rotations and a weak pull toward the rest pose,
   which is what decides the degrees of freedom no marker sees (bone twists, the unobserved spine
   joints between observed ones, hands past the wrist).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import torch

from ..errors import ParameterError
from ..skeleton import SMPL24, Skeleton, forward_kinematics_torch, matrix_to_quaternion, rot6d_to_matrix

IDENTITY_6D = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0)


@dataclass(frozen=True, kw_only=True)
class IKConfig:
    """Knobs of the refinement; the defaults fit M2D to ~1-2 cm at ~2.5 ms per frame on one core."""

    iterations: int = 150  # L-BFGS iterations (one optimiser step over all frames)
    smoothness_weight: float = 1e-3  # frame-to-frame change of the 6D rotation parameters
    rest_prior_weight: float = 1e-5  # distance of every joint's 6D rotation from identity
    history_size: int = 10  # L-BFGS memory
    float64: bool = False  # float32 is ~2x faster and far more precise than marker noise


@dataclass
class IKResult:
    """Fitted motion on ``skeleton`` and how far it lands from the targets."""

    rotations: np.ndarray  # (T, J, 4) local quaternions, w first
    root_positions: np.ndarray  # (T, 3) metres
    skeleton: Skeleton  # the skeleton the rotations were fitted on
    errors: np.ndarray  # (T, K) distance of each observed joint from its target, metres

    @property
    def mean_error(self) -> float:
        """Mean per-joint position error over frames and observed joints (metres)."""
        return float(self.errors.mean())


# -- tree helpers ------------------------------------------------------------------------------

def nearest_observed_ancestor(joint: int, observed: set[int], parents: Sequence[int]) -> int:
    """The closest ancestor of ``joint`` that has a target, or -1 when there is none."""
    parent = parents[joint]
    while parent >= 0 and parent not in observed:
        parent = parents[parent]
    return parent


def observed_groups(joints: Sequence[int], parents: Sequence[int]) -> dict[int, list[int]]:
    """For every observed joint (and -1 for "no observed ancestor"), the observed joints right below it."""
    observed = set(joints)
    groups: dict[int, list[int]] = {}
    for j in joints:
        groups.setdefault(nearest_observed_ancestor(j, observed, parents), []).append(j)
    return groups


def bone_path(ancestor: int, joint: int, parents: Sequence[int]) -> list[int]:
    """Joints whose offsets make up the path from ``ancestor`` down to ``joint`` (ancestor excluded)."""
    path = []
    while joint != ancestor:
        if joint < 0:
            raise ParameterError(f"joint {ancestor} is not an ancestor")
        path.append(joint)
        joint = parents[joint]
    return path[::-1]


def _check_targets(targets: np.ndarray, joints: Sequence[int], skeleton: Skeleton) -> np.ndarray:
    targets = np.asarray(targets, dtype=np.float64)
    if targets.ndim != 3 or targets.shape[1:] != (len(joints), 3) or len(targets) == 0:
        raise ParameterError(f"targets must have shape (T, {len(joints)}, 3), got {targets.shape}")
    if len(set(joints)) != len(joints) or not all(0 <= j < skeleton.num_joints for j in joints):
        raise ParameterError(f"observed joints must be distinct skeleton indices, got {list(joints)}")
    if not np.isfinite(targets).all():
        raise ParameterError("targets contain NaN or infinite values")
    return targets


# -- rotations between vector sets -------------------------------------------------------------

def swing(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(T, 3, 3) smallest rotations turning direction ``source`` (T, 3) onto ``target`` (T, 3).

    A bone seen through one child gives no twist; the smallest swing keeps the twist it inherits
    from its parent, which is what keeps a chain of single bones from spinning frame to frame.
    """
    a = source / np.maximum(np.linalg.norm(source, axis=-1, keepdims=True), 1e-12)
    b = target / np.maximum(np.linalg.norm(target, axis=-1, keepdims=True), 1e-12)
    axis = np.cross(a, b)
    cos = np.einsum("ti,ti->t", a, b)
    skew = np.zeros(a.shape + (3,))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    skew -= np.swapaxes(skew, -1, -2)
    opposite = cos < -1 + 1e-9
    scale = 1.0 / np.where(opposite, 1.0, 1.0 + cos)
    result = np.eye(3) + skew + skew @ skew * scale[:, None, None]
    if opposite.any():  # half turn about any axis perpendicular to a
        helper = np.where(np.abs(a[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        perpendicular = np.cross(a, helper)
        perpendicular /= np.linalg.norm(perpendicular, axis=-1, keepdims=True)
        half_turn = 2 * np.einsum("ti,tj->tij", perpendicular, perpendicular) - np.eye(3)
        result[opposite] = half_turn[opposite]
    return result


def kabsch(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotations R minimising sum_i |R source_i - target_i|^2 for (T, N, 3) vector sets."""
    covariance = np.einsum("tni,tnj->tij", target, source)
    u, _, vt = np.linalg.svd(covariance)
    sign = np.sign(np.linalg.det(u @ vt))
    sign[sign == 0] = 1.0
    fix = np.broadcast_to(np.eye(3), covariance.shape).copy()
    fix[:, 2, 2] = sign
    return u @ fix @ vt


def _turn(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Kabsch for two or more vectors, the minimal swing for one."""
    return swing(source[:, 0], target[:, 0]) if source.shape[1] == 1 else kabsch(source, target)


# -- the performer's skeleton ------------------------------------------------------------------

def procrustes_mean_shape(points: np.ndarray, template: np.ndarray, iterations: int = 3) -> np.ndarray:
    """(N, 3) mean shape of (T, N, 3) point sets, centred and oriented like ``template`` (N, 3).

    Each frame is rotated (not scaled) onto the current mean; the mean is then turned back onto the
    template so the result lives in the template's frame (x left, y up, z forward for SMPL).
    """
    centred = points - points.mean(axis=1, keepdims=True)
    reference = template - template.mean(axis=0)
    mean = reference
    for _ in range(iterations):
        rotations = kabsch(centred, np.broadcast_to(mean, centred.shape))
        mean = np.einsum("tij,tnj->tni", rotations, centred).mean(axis=0)
    to_template = kabsch(mean[None], reference[None])[0]
    return mean @ to_template.T


def _solve_private_scale(shared: np.ndarray, private: np.ndarray, length: float) -> float:
    """t >= 0 with |shared + t * private| = length (the chain's own bones absorb the difference)."""
    a = float(private @ private)
    if a < 1e-12:
        return 1.0
    b = float(shared @ private)
    c = float(shared @ shared) - length**2
    disc = b * b - a * c
    if disc < 0:
        return max(-b / a, 0.0)  # closest reachable length
    return max((-b + np.sqrt(disc)) / a, 0.0)


def _root_group_offsets(targets: np.ndarray, column: dict[int, int], groups: dict[int, list[int]],
                        base: Skeleton) -> tuple[dict[int, np.ndarray], dict[int, float]]:
    """Offsets (and bone scales) of the joints below an unobserved root, from their mean shape.

    Empty when the root is observed or fewer than two joints hang below it.
    """
    members = [j for j in groups.get(-1, []) if j != 0]
    if 0 in column or len(members) < 2:
        return {}, {}
    rest = base.rest_positions()
    shape = procrustes_mean_shape(targets[:, [column[j] for j in members]], rest[members])
    template = rest[members] - rest[members].mean(axis=0)
    size = float(np.sqrt((shape**2).sum() / max((template**2).sum(), 1e-12)))
    root_place = (rest[0] - rest[members].mean(axis=0)) * size
    offsets, scales = {}, {}
    for j, point in zip(members, shape):
        path = bone_path(0, j, base.parents)
        scales.update({bone: size for bone in path})
        offsets[j] = point - root_place - sum((base.offsets[b] * size for b in path[:-1]), np.zeros(3))
    return offsets, scales


def _chain_scales(targets: np.ndarray, column: dict[int, int], groups: dict[int, list[int]],
                  base: Skeleton) -> dict[int, float]:
    """Scale of every bone on a chain between two observed joints (see :func:`performer_skeleton`)."""
    rest = base.rest_positions()
    chains = {j: bone_path(a, j, base.parents) for a, members in groups.items() if a >= 0 for j in members}
    lengths, ratios = {}, {}
    for j, path in chains.items():
        a = base.parents[path[0]]
        lengths[j] = np.median(np.linalg.norm(targets[:, column[j]] - targets[:, column[a]], axis=-1))
        ratios[j] = lengths[j] / max(np.linalg.norm(rest[j] - rest[a]), 1e-9)
    users: dict[int, list[float]] = {}
    for j, path in chains.items():
        for bone in path:
            users.setdefault(bone, []).append(ratios[j])
    scales = {bone: float(np.median(values)) for bone, values in users.items() if len(values) > 1}
    for j, path in chains.items():
        private = [b for b in path if len(users[b]) == 1]
        shared_vector = sum((base.offsets[b] * scales[b] for b in path if b in scales), np.zeros(3))
        private_vector = sum((base.offsets[b] for b in private), np.zeros(3))
        t = _solve_private_scale(shared_vector, private_vector, lengths[j])
        scales.update({bone: t for bone in private})
    return scales


def performer_skeleton(targets: np.ndarray, joints: Sequence[int], base: Skeleton = SMPL24) -> Skeleton:
    """``base`` with its bones fitted to the performer's median proportions in ``targets``.

    - A chain from an observed joint ``a`` down to its observed descendant ``j`` is scaled so that
      |rest(j) - rest(a)| equals the median observed |p_j - p_a|. Bones shared by several chains
      (SMPL's spine2/spine3 lie on the way to the neck and both shoulders) take the median of those
      chains' scales; each chain's own bones then absorb the rest, so every chain length is exact.
      A chain through unobserved joints is measured as it bends, so it comes out a little short.
    - Joints with no observed ancestor (the root's group when the root has no target) take their
      offsets from the Procrustes mean shape of their observed positions; the root keeps its
      template place relative to that group, scaled with it.
    - Bones on no chain (hands, say) follow their parent bone's scale.
    """
    targets = _check_targets(targets, joints, base)
    column = {j: k for k, j in enumerate(joints)}
    groups = observed_groups(joints, base.parents)
    shaped, scales = _root_group_offsets(targets, column, groups, base)
    scales.update(_chain_scales(targets, column, groups, base))
    offsets = base.offsets.copy()
    for j in range(1, base.num_joints):  # parents come first, so a parent's scale is already settled
        if j not in scales:
            scales[j] = scales.get(base.parents[j], 1.0)
        offsets[j] = shaped[j] if j in shaped else base.offsets[j] * scales[j]
    return base.with_offsets(offsets)


# -- analytic start ----------------------------------------------------------------------------

def initial_pose(targets: np.ndarray, joints: Sequence[int],
                 skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """(T, J, 3, 3) local rotations and (T, 3) root positions that roughly reproduce ``targets``.

    Each observed joint gets the rotation that best turns the template vectors to its observed
    descendants onto the observed vectors; unobserved joints keep their parent's orientation, so
    the observed joint above them swings the whole chain (the lower back turns neck and shoulders).
    """
    targets = _check_targets(targets, joints, skeleton)
    frames, num_joints = len(targets), skeleton.num_joints
    column = {j: k for k, j in enumerate(joints)}
    parents = skeleton.parents
    groups = observed_groups(joints, parents)
    rest = skeleton.rest_positions()
    global_rot = np.broadcast_to(np.eye(3), (frames, num_joints, 3, 3)).copy()

    if 0 in column:
        root = targets[:, column[0]].copy()
        top = groups.get(0, [])
        if top:
            seen = targets[:, [column[c] for c in top]] - root[:, None]
            global_rot[:, 0] = _turn(np.broadcast_to(rest[top] - rest[0], seen.shape), seen)
    else:
        top = groups.get(-1, [])
        seen = targets[:, [column[c] for c in top]]
        seen_centre = seen.mean(axis=1)
        rest_centre = rest[top].mean(axis=0)
        if len(top) >= 2:
            template = np.broadcast_to(rest[top] - rest_centre, seen.shape)
            global_rot[:, 0] = kabsch(template, seen - seen_centre[:, None])
        root = seen_centre - np.einsum("tij,j->ti", global_rot[:, 0], rest_centre - rest[0])

    for j in range(1, num_joints):
        parent_rot = global_rot[:, parents[j]]
        below = groups.get(j, []) if j in column else []
        if below:
            seen = targets[:, [column[c] for c in below]] - targets[:, column[j]][:, None]
            template = np.einsum("tij,nj->tni", parent_rot, rest[below] - rest[j])
            global_rot[:, j] = _turn(template, seen) @ parent_rot
        else:
            global_rot[:, j] = parent_rot
    local = global_rot.copy()
    for j in range(1, num_joints):
        local[:, j] = np.swapaxes(global_rot[:, parents[j]], -1, -2) @ global_rot[:, j]
    return local, root


# -- refinement --------------------------------------------------------------------------------

@contextlib.contextmanager
def one_torch_thread():
    """Run torch on one thread, restoring the setting after.

    The fit is thousands of tiny (T, 3, 3) operations: threads add no speed, and on a machine whose
    cores are shared their synchronisation made a loss evaluation 60x slower in our measurements.
    """
    previous = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(previous)


def fit_rotations(targets: np.ndarray, joints: Sequence[int], skeleton: Skeleton,
                  config: IKConfig = IKConfig(), weights: Sequence[float] | None = None) -> IKResult:
    """Fit local rotations and root positions of ``skeleton`` to ``targets`` (T, K, 3) at ``joints``.

    ``weights`` (K,) scales each observed joint's share of the position loss (default all 1).
    """
    targets = _check_targets(targets, joints, skeleton)
    dtype = torch.float64 if config.float64 else torch.float32
    local, root_start = initial_pose(targets, joints, skeleton)
    frames = len(targets)
    start6d = local[..., :2, :].reshape(frames, skeleton.num_joints, 6)
    rot6d = torch.tensor(start6d, dtype=dtype, requires_grad=True)
    root = torch.tensor(root_start, dtype=dtype, requires_grad=True)
    target = torch.tensor(targets, dtype=dtype)
    offsets = torch.tensor(skeleton.offsets, dtype=dtype)
    weight = torch.ones(len(joints), dtype=dtype) if weights is None else torch.tensor(weights, dtype=dtype)
    weight = weight / weight.mean()
    index = list(joints)
    rest6d = torch.tensor(IDENTITY_6D, dtype=dtype)

    def positions() -> torch.Tensor:
        return forward_kinematics_torch(rot6d_to_matrix(rot6d), root, offsets, skeleton.parents)

    def loss_value() -> torch.Tensor:
        data = (((positions()[:, index] - target) ** 2).sum(-1) * weight).mean()
        smooth = ((rot6d[1:] - rot6d[:-1]) ** 2).sum(-1).mean() if frames > 1 else rot6d.sum() * 0
        prior = ((rot6d - rest6d) ** 2).sum(-1).mean()
        return data + config.smoothness_weight * smooth + config.rest_prior_weight * prior

    with one_torch_thread():
        _minimise(loss_value, [rot6d, root], config)
        with torch.no_grad():
            rotmats = rot6d_to_matrix(rot6d).double()
            fitted = forward_kinematics_torch(rotmats, root.double(), offsets.double(), skeleton.parents)
            errors = torch.linalg.norm(fitted[:, index] - torch.tensor(targets), dim=-1).numpy()
            quaternions = matrix_to_quaternion(rotmats).numpy()
    return IKResult(quaternions, root.detach().double().numpy().copy(), skeleton, errors)


def _minimise(loss_value, parameters: list[torch.Tensor], config: IKConfig) -> None:
    """Run L-BFGS for ``config.iterations`` iterations on ``loss_value()``."""
    if config.iterations <= 0:
        return
    optimiser = torch.optim.LBFGS(parameters, lr=1.0, max_iter=config.iterations,
                                  history_size=config.history_size, line_search_fn="strong_wolfe",
                                  tolerance_grad=1e-10, tolerance_change=1e-14)

    def closure():
        optimiser.zero_grad()
        loss = loss_value()
        loss.backward()
        return loss

    optimiser.step(closure)
