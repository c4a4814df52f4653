"""Constraints for controllable generation: keyframes, seed motion, inpainting, body parts, paths."""

from .mask import ALL_JOINTS, Constraints, as_smpl
from .parse import (JOINT_SETS, parse_frame_range, parse_joints, parse_style_schedule, parse_time_key, path_to_frames,
                    read_pose, read_root_path)
from .recipes import along_path, between_poses, inpainting, seed_motion

__all__ = ["ALL_JOINTS", "Constraints", "JOINT_SETS", "along_path", "as_smpl", "between_poses", "inpainting",
           "parse_frame_range", "parse_joints", "parse_style_schedule", "parse_time_key", "path_to_frames", "read_pose",
           "read_root_path", "seed_motion"]
