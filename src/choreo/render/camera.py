"""A perspective camera that follows the dancer: smoothed root, fixed height and viewing angle."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d


@dataclass(frozen=True, kw_only=True)
class CameraConfig:
    distance: float = 3.6  # metres from the followed point
    height: float = 1.4  # eye height above the floor
    azimuth_degrees: float = 25.0  # around the vertical axis, 0 = looking along -z
    field_of_view_degrees: float = 40.0
    follow_seconds: float = 0.6  # smoothing of the followed root, so the camera does not jitter
    look_height: float = 0.9  # the height it aims at


class FollowCamera:
    """World points (..., 3), Y up, to pixel coordinates and depths, frame by frame."""

    def __init__(self, root_path: np.ndarray, fps: float, width: int, height: int, config: CameraConfig = CameraConfig()):
        self.config, self.width, self.height = config, width, height
        sigma = max(config.follow_seconds * fps, 1e-6)
        self.targets = np.stack([gaussian_filter1d(root_path[:, 0], sigma, mode="nearest"),
                                 np.full(len(root_path), config.look_height),
                                 gaussian_filter1d(root_path[:, 2], sigma, mode="nearest")], axis=1)
        azimuth = np.radians(config.azimuth_degrees)
        self.offset = np.array([np.sin(azimuth) * config.distance, config.height - config.look_height,
                                np.cos(azimuth) * config.distance])
        self.focal = 0.5 * height / np.tan(np.radians(config.field_of_view_degrees) / 2)

    def basis(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """(eye position, 3x3 world-to-camera rotation: rows right, up, forward)."""
        eye = self.targets[frame] + self.offset
        forward = self.targets[frame] - eye
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, [0.0, 1.0, 0.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        return eye, np.stack([right, up, forward])

    def project(self, points: np.ndarray, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """(..., 2) pixel coordinates and (...,) depths in metres along the view direction."""
        eye, rotation = self.basis(frame)
        camera = (points - eye) @ rotation.T
        depth = np.maximum(camera[..., 2], 1e-3)
        pixels = np.stack([self.width / 2 + self.focal * camera[..., 0] / depth,
                           self.height / 2 - self.focal * camera[..., 1] / depth], axis=-1)
        return pixels, depth

    def pixels_per_metre(self, depth: np.ndarray) -> np.ndarray:
        return self.focal / depth
