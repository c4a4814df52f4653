"""Training losses (paper eqs. 1-4 and 7): x0 reconstruction, FK joint positions, velocity, feet.

All but the reconstruction term are computed on de-normalised motion, where they mean something
physical: joint positions in metres through SMPL-24 forward kinematics, and feet that should stay
still on frames marked as in contact: by the model itself (EDGE) or by the data (MDM), which the
model cannot switch off by predicting no contact (docs/sgmd.md, "Feet").
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F

from choreo.motion.vector import CONTACT_SLICE, ROOT_SLICE, ROTATION_SLICE
from choreo.skeleton import FOOT_JOINTS, LOWER_BODY_JOINTS, SMPL24, forward_kinematics_torch, rot6d_to_matrix

from .config import CONTACT_SOURCES, DiffusionConfig
from .normalizer import Normalizer

CONTACT_THRESHOLD = 0.95  # predicted contact above this pins the foot (EDGE)
LEG_POINTS = (4, 5, 7, 8, 10, 11)  # knees, ankles, feet: what a step moves
FPS = 30.0  # foot speeds in the stepping term are in m/s at the training frame rate


@dataclass
class LossTerms:
    reconstruction: torch.Tensor
    velocity: torch.Tensor
    joints: torch.Tensor
    foot: torch.Tensor
    stepping: torch.Tensor  # the feet's world speeds against the data's, in (m/s)^2
    root_speed: torch.Tensor  # the root's horizontal speed against the data's, in (m/s)^2
    pace: torch.Tensor  # each window's pace against the data's, in (m/s)^2
    legs: torch.Tensor  # knees, ankles and feet around the pelvis: positions in m^2 plus speeds in (m/s)^2
    legs_speed: torch.Tensor  # each window's mean speed of those joints around the pelvis, in (m/s)^2

    def total(self, config: DiffusionConfig) -> torch.Tensor:
        total = (config.reconstruction_weight * self.reconstruction + config.velocity_weight * self.velocity
                 + config.joint_weight * self.joints + config.foot_weight * self.foot)
        for weight, term in ((config.stepping_weight, self.stepping), (config.root_speed_weight, self.root_speed),
                             (config.pace_weight, self.pace), (config.legs_weight, self.legs),
                             (config.legs_speed_weight, self.legs_speed)):
            if weight:  # the terms most runs leave off
                total = total + weight * term
        return total


def joint_positions(vectors: torch.Tensor) -> torch.Tensor:
    """(B, T, 151) de-normalised frame vectors -> (B, T, 24, 3) joint positions."""
    rotations = rot6d_to_matrix(vectors[..., ROTATION_SLICE].unflatten(-1, (24, 6)))
    offsets = torch.as_tensor(SMPL24.offsets, dtype=vectors.dtype, device=vectors.device)
    return forward_kinematics_torch(rotations, vectors[..., ROOT_SLICE], offsets, SMPL24.parents)


def leg_channels(frame_dim: int) -> torch.Tensor:
    """(frame_dim,) bool: the 6D rotation channels of the legs (hips, knees, ankles, toes)."""
    legs = torch.zeros(frame_dim, dtype=torch.bool)
    for joint in LOWER_BODY_JOINTS[1:]:  # not the pelvis: it carries the facing, which the network already reads
        start = ROTATION_SLICE.start + 6 * joint
        legs[start: start + 6] = True
    return legs


def diffusion_losses(predicted: torch.Tensor, target: torch.Tensor, normalizer: Normalizer,
                     weights: torch.Tensor | None = None, contact_source: str = "predicted",
                     leg_weight: float = 1.0, clean_share: torch.Tensor | None = None) -> LossTerms:
    """predicted and target x0 in normalised space, (B, T, 151); ``weights`` (B,) weigh each
    window's terms (min-SNR weighting: ``snr_weights``), uniform when None; ``contact_source``:
    which contact labels pin the feet in the foot term (CONTACT_SOURCES); ``leg_weight``: the
    legs' rotation channels weigh this much in the reconstruction term (1: like every channel)."""
    squared = F.mse_loss(predicted, target, reduction="none")
    if leg_weight != 1.0:
        squared = squared * torch.where(leg_channels(predicted.shape[-1]).to(predicted.device), leg_weight, 1.0)
    reconstruction = _per_window(squared)
    velocity = _per_window(F.mse_loss(predicted[:, 1:] - predicted[:, :-1], target[:, 1:] - target[:, :-1], reduction="none"))
    predicted_motion, target_motion = normalizer.denormalize(predicted), normalizer.denormalize(target)
    predicted_joints, target_joints = joint_positions(predicted_motion), joint_positions(target_motion)
    joints = _per_window(F.mse_loss(predicted_joints, target_joints, reduction="none"))
    feet_velocity = foot_velocity(predicted_joints)
    if contact_source not in CONTACT_SOURCES:
        raise ValueError(f"contact_source must be one of {CONTACT_SOURCES}, got {contact_source!r}")
    contacts = predicted_motion if contact_source == "predicted" else target_motion
    in_contact = (contacts[:, :-1, CONTACT_SLICE] > CONTACT_THRESHOLD).to(predicted.dtype)
    foot = _per_window(feet_velocity.pow(2).sum(-1) * in_contact)  # no gradient through the contact mask
    stepping = _per_window((feet_velocity - foot_velocity(target_joints)).mul(FPS).pow(2).sum(-1))
    root_speed = _per_window((horizontal_root_speed(predicted_motion) - horizontal_root_speed(target_motion)).pow(2))
    pace = (window_pace(predicted_motion) - window_pace(target_motion)).pow(2)
    predicted_legs = legs_around_pelvis(predicted_motion, predicted_joints)
    target_legs = legs_around_pelvis(target_motion, target_joints)
    legs = legs_error(predicted_legs, target_legs)
    if clean_share is not None:
        legs = legs * clean_share
    legs_speed = (mean_speed(predicted_legs) - mean_speed(target_legs)).pow(2)
    weigh = (lambda term: term.mean()) if weights is None else (lambda term: (term * weights).mean())  # noqa: E731
    return LossTerms(weigh(reconstruction), weigh(velocity), weigh(joints), weigh(foot), weigh(stepping), weigh(root_speed),
                     weigh(pace), weigh(legs), weigh(legs_speed))


def legs_around_pelvis(vectors: torch.Tensor, joints: torch.Tensor) -> torch.Tensor:
    """(B, T, 151) de-normalised frame vectors and their (B, T, 24, 3) joints -> (B, T, 6, 3) knees,
    ankles and feet relative to the pelvis, turned so the pelvis faces +Z: the steps themselves,
    whatever way the dancer faces and however the root travels."""
    pelvis = rot6d_to_matrix(vectors[..., ROTATION_SLICE.start: ROTATION_SLICE.start + 6])
    heading = F.normalize(pelvis[..., [0, 2], 2], dim=-1, eps=1e-6)  # the pelvis's +Z on the floor: (sin, cos) of its yaw
    sin, cos = heading[..., None, 0], heading[..., None, 1]
    around = joints[:, :, list(LEG_POINTS)] - joints[:, :, :1]
    x, y, z = around.unbind(-1)
    return torch.stack((cos * x - sin * z, y, sin * x + cos * z), -1)


def legs_error(predicted: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """(B,) the legs around the pelvis (``legs_around_pelvis``, (B, T, 6, 3)) against the data's:
    squared position error in m^2 plus squared speed error in (m/s)^2. Why: the x0 term weighs a
    toe's rotation like a hip's and the joints term is dominated by the root's travel, so neither
    sees a foot that rides on the body instead of stepping (docs/sgmd.md, "Legs")."""
    positions = _per_window((predicted - target).pow(2))
    speeds = _per_window(((predicted[:, 1:] - predicted[:, :-1]) - (target[:, 1:] - target[:, :-1])).mul(FPS).pow(2))
    return positions + speeds


def mean_speed(points: torch.Tensor) -> torch.Tensor:
    """(B, T, P, 3) points in m -> (B,) each window's mean speed in m/s. A speed, not a velocity: where
    the network cannot tell when a foot moves, the velocity a squared error pulls towards is a foot
    standing still, while the mean speed is the data's (as ``horizontal_root_speed`` for the root)."""
    step = (points[:, 1:] - points[:, :-1]) * FPS
    return torch.sqrt(step.pow(2).sum(-1) + 1e-8).flatten(1).mean(1)


def horizontal_root_speed(vectors: torch.Tensor) -> torch.Tensor:
    """(B, T, 151) de-normalised frame vectors -> (B, T - 1) the root's horizontal speed in m/s.

    A speed, not a velocity: where the data may travel any way, the mean velocity a squared error
    pulls towards is near standing still (what the stepping term did to the whole dancer,
    docs/sgmd.md), while the mean speed is the data's pace."""
    root = vectors[..., ROOT_SLICE]
    step = (root[:, 1:] - root[:, :-1])[..., [0, 2]] * FPS
    return torch.sqrt(step.pow(2).sum(-1) + 1e-8)


def window_pace(vectors: torch.Tensor) -> torch.Tensor:
    """(B, T, 151) de-normalised frame vectors -> (B,) each window's pace in m/s: the root's floor path
    averaged over a second (no sway or wobble, as ``choreo.motion.travel``'s 1 Hz ground track), its
    length over its duration. What a pace condition names: a term on it rewards a network for
    travelling the pace it is told, where a frame-by-frame speed term rewarded smoothing the root."""
    floor = vectors[..., ROOT_SLICE][..., [0, 2]].transpose(1, 2)  # (B, 2, T)
    track = F.avg_pool1d(floor, min(int(FPS), max(1, floor.shape[-1] // 2)), stride=1)  # a short window keeps a path
    step = track[..., 1:] - track[..., :-1]
    return torch.sqrt(step.pow(2).sum(1) + 1e-8).mean(-1) * FPS


def foot_velocity(joints: torch.Tensor) -> torch.Tensor:
    """(B, T, 24, 3) joint positions -> (B, T - 1, 4, 3) foot joints' displacement per frame."""
    feet = joints[:, :, list(FOOT_JOINTS)]
    return feet[:, 1:] - feet[:, :-1]


def _per_window(values: torch.Tensor) -> torch.Tensor:
    return values.flatten(1).mean(1)


def snr_weights(alpha_bar: torch.Tensor, gamma: float) -> torch.Tensor:
    """min(SNR(t), gamma) per window (Hang et al., "Efficient Diffusion Training via Min-SNR
    Weighting Strategy", 2023, for an x0 loss). Why here: an unweighted x0 loss is dominated by
    the high-noise steps, where the best guess is an average dance, and says little about the
    low-noise steps that decide a sample's last details (docs/results.md)."""
    return torch.clamp(alpha_bar / (1 - alpha_bar), max=gamma)
