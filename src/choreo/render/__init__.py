"""Previews: a shaded 3D dancer followed by the camera (MP4 with music, GIF, PNG strip) and plots."""

from .camera import CameraConfig, FollowCamera
from .figure import render_frame
from .video import RenderConfig, render_motion

__all__ = ["CameraConfig", "FollowCamera", "RenderConfig", "render_frame", "render_motion"]
