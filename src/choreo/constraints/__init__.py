"""Constraints for controllable generation: keyframes, seed motion, inpainting, body parts, paths."""

from .mask import ALL_JOINTS, Constraints, as_smpl
from .parse import (JOINT_SETS, parse_frame_range, parse_joints, parse_style_schedule, parse_time_key, path_to_frames,
                    read_pose, read_root_path)

__all__ = ["ALL_JOINTS", "Constraints", "JOINT_SETS", "as_smpl", "parse_frame_range", "parse_joints",
           "parse_style_schedule", "parse_time_key", "path_to_frames", "read_pose", "read_root_path"]
