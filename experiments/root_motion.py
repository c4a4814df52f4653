"""What --root-motion's root bone does on whole dances, as read back from the BVH a user gets.

    python -m experiments.root_motion dance.npz [more.npz ...]

Per file (written with choreo.formats.write_motion(..., root_motion=True) and parsed back): the root
bone's height against the floor the feet find (the lowest joint's median height), how far its path
strays from its own 1 Hz low-pass (smoothness), from the dance's 1 Hz ground track and, at the end,
from where the track ends (the travel it carries), the hips' farthest horizontal distance from it,
and the largest error of the joint positions read back through it.
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

from choreo.formats import read_bvh_raw, read_motion, write_motion
from choreo.motion.filters import low_pass
from choreo.motion.travel import ground_track
from tests.formats.helpers import file_forward_kinematics

print("| dance | seconds | root bone above the floor (cm) | from its 1 Hz low-pass (cm) | from the 1 Hz track (cm) "
      "| travel missed at the end (cm) | hips from the bone (m) | joints read back (mm) |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for path in sys.argv[1:]:
    motion = read_motion(path)
    with tempfile.TemporaryDirectory() as folder:
        written = Path(folder) / "root.bvh"
        write_motion(motion, written, root_motion=True)
        positions, _ = file_forward_kinematics(read_bvh_raw(written))
        back = read_motion(written)
    bone, hips = positions[0], positions[1]
    joints = motion.joint_positions()
    floor = np.median(joints[..., 1].min(axis=1))
    path_xz = bone[:, [0, 2]]
    track = ground_track(motion.root_positions, motion.fps)
    smooth = np.linalg.norm(path_xz - low_pass(path_xz, motion.fps, 1.0), axis=-1).max()
    apart = np.linalg.norm(path_xz - track, axis=-1)
    hips_apart = np.linalg.norm(hips[:, [0, 2]] - path_xz, axis=-1).max()
    error = np.abs(back.joint_positions() - joints).max()
    print(f"| {path} | {motion.duration:.1f} | {100 * np.abs(bone[:, 1] - floor).max():.2f} | {100 * smooth:.2f} "
          f"| {100 * apart.max():.1f} | {100 * apart[-1]:.2f} | {hips_apart:.2f} | {1000 * error:.2f} |")
