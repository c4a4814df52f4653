"""Training losses (paper eqs. 1-4 and 7): x0 reconstruction, FK joint positions, velocity, feet.

All but the reconstruction term are computed on de-normalised motion, where they mean something
physical: joint positions in metres through SMPL-24 forward kinematics, and feet that should stay
still on frames the model itself marks as in contact.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F

from choreo.motion.vector import CONTACT_SLICE, ROOT_SLICE, ROTATION_SLICE
from choreo.skeleton import FOOT_JOINTS, SMPL24, forward_kinematics_torch, rot6d_to_matrix

from .config import DiffusionConfig
from .normalizer import Normalizer

CONTACT_THRESHOLD = 0.95  # predicted contact above this pins the foot (EDGE)


@dataclass
class LossTerms:
    reconstruction: torch.Tensor
    velocity: torch.Tensor
    joints: torch.Tensor
    foot: torch.Tensor

    def total(self, config: DiffusionConfig) -> torch.Tensor:
        return (config.reconstruction_weight * self.reconstruction + config.velocity_weight * self.velocity
                + config.joint_weight * self.joints + config.foot_weight * self.foot)


def joint_positions(vectors: torch.Tensor) -> torch.Tensor:
    """(B, T, 151) de-normalised frame vectors -> (B, T, 24, 3) joint positions."""
    rotations = rot6d_to_matrix(vectors[..., ROTATION_SLICE].unflatten(-1, (24, 6)))
    offsets = torch.as_tensor(SMPL24.offsets, dtype=vectors.dtype, device=vectors.device)
    return forward_kinematics_torch(rotations, vectors[..., ROOT_SLICE], offsets, SMPL24.parents)


def diffusion_losses(predicted: torch.Tensor, target: torch.Tensor, normalizer: Normalizer,
                     weights: torch.Tensor | None = None) -> LossTerms:
    """predicted and target x0 in normalised space, (B, T, 151); ``weights`` (B,) weigh each
    window's terms (min-SNR weighting: ``snr_weights``), uniform when None."""
    reconstruction = _per_window(F.mse_loss(predicted, target, reduction="none"))
    velocity = _per_window(F.mse_loss(predicted[:, 1:] - predicted[:, :-1], target[:, 1:] - target[:, :-1], reduction="none"))
    predicted_motion, target_motion = normalizer.denormalize(predicted), normalizer.denormalize(target)
    predicted_joints, target_joints = joint_positions(predicted_motion), joint_positions(target_motion)
    joints = _per_window(F.mse_loss(predicted_joints, target_joints, reduction="none"))
    feet_velocity = predicted_joints[:, 1:, list(FOOT_JOINTS)] - predicted_joints[:, :-1, list(FOOT_JOINTS)]
    in_contact = (predicted_motion[:, :-1, CONTACT_SLICE] > CONTACT_THRESHOLD).to(predicted.dtype)
    foot = _per_window(feet_velocity.pow(2).sum(-1) * in_contact)  # no gradient through the contact mask
    weigh = (lambda term: term.mean()) if weights is None else (lambda term: (term * weights).mean())  # noqa: E731
    return LossTerms(weigh(reconstruction), weigh(velocity), weigh(joints), weigh(foot))


def _per_window(values: torch.Tensor) -> torch.Tensor:
    return values.flatten(1).mean(1)


def snr_weights(alpha_bar: torch.Tensor, gamma: float) -> torch.Tensor:
    """min(SNR(t), gamma) per window (Hang et al., "Efficient Diffusion Training via Min-SNR
    Weighting Strategy", 2023, for an x0 loss). Why here: an unweighted x0 loss is dominated by
    the high-noise steps, where the best guess is an average dance, and says little about the
    low-noise steps that decide a sample's last details (docs/results.md)."""
    return torch.clamp(alpha_bar / (1 - alpha_bar), max=gamma)
