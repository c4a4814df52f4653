"""Motion file formats: BVH, NPZ (AIST++ keys), AIST++ pkl, JSON, joint-position npy, glTF binary."""

from .aistpp import AISTPP_FPS, read_aistpp_pkl, write_aistpp_pkl
from .bvh import BvhData, parse_bvh, read_bvh, read_bvh_raw, write_bvh
from .gltf import read_glb, write_glb
from .registry import (FORMATS, MotionFormat, check_output_format, list_formats, read_joint_positions, read_motion,
                       write_motion, write_motions)

__all__ = [
    "AISTPP_FPS", "BvhData", "FORMATS", "MotionFormat", "list_formats", "parse_bvh", "read_aistpp_pkl",
    "read_bvh", "read_bvh_raw", "read_glb", "write_glb", "read_joint_positions", "read_motion", "write_aistpp_pkl", "write_bvh",
    "write_motion", "write_motions", "check_output_format",
]  # fmt: skip
