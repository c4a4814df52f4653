"""Blender as the real client: its own BVH importer reads our files as we meant them.

Installs Blender from the distribution's packages when it is missing and this user may (root with
apt-get); otherwise skipped. Marked slow: the install takes about a minute.
"""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from choreo.formats import write_motion
from choreo.motion import Motion
from choreo.skeleton import JOINT_NAMES

SCRIPT = Path(__file__).parents[1] / "blender" / "import_bvh.py"


def blender_executable() -> str:
    found = shutil.which("blender")
    if found:
        return found
    if os.geteuid() != 0 or not shutil.which("apt-get"):
        pytest.skip("Blender is not installed and cannot be installed here")
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    subprocess.run(["apt-get", "update", "-q"], env=env, capture_output=True, timeout=600)
    done = subprocess.run(["apt-get", "install", "-y", "-q", "--no-install-recommends", "blender"], env=env,
                          capture_output=True, text=True, timeout=1200)
    if done.returncode != 0 or not shutil.which("blender"):
        pytest.skip(f"could not install Blender: {done.stderr.strip().splitlines()[-1:] or done.returncode}")
    return shutil.which("blender")


@pytest.mark.slow
@pytest.mark.parametrize("root_motion", [False, True])
def test_blender_imports_our_bvh_exactly(root_motion, tmp_path):
    rng = np.random.default_rng(0)
    frames = 40
    axis_angle = np.cumsum(rng.normal(scale=0.05, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.02, size=(frames, 3)), axis=0) + [0.3, 0.95, -0.2]
    motion = Motion.from_axis_angle(root, axis_angle, fps=30)
    write_motion(motion, tmp_path / "dance.bvh", root_motion=root_motion)
    result = subprocess.run([blender_executable(), "--background", "--factory-startup", "--python-exit-code", "1",
                             "--python", str(SCRIPT), "--",
                             str(tmp_path / "dance.bvh"), str(tmp_path / "seen.json")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and (tmp_path / "seen.json").exists(), result.stdout[-2000:] + result.stderr[-2000:]
    seen = json.loads((tmp_path / "seen.json").read_text())
    bones = set(JOINT_NAMES) | ({"root"} if root_motion else set())
    assert len(seen["bones"]) == len(bones) and set(seen["bones"]) == bones
    assert seen["frame_end"] - seen["frame_start"] + 1 == frames
    assert seen["fps"] == pytest.approx(30.0)
    heads = np.array(seen["heads"])  # (frames, bones, 3), Blender's Z-up: (x, y, z) = (x, -z, y) in ours
    joints = [k for k, name in enumerate(seen["bones"]) if name in JOINT_NAMES]
    ours = motion.joint_positions()[:, [JOINT_NAMES.index(seen["bones"][k]) for k in joints]]
    ours_in_blender = np.stack([ours[..., 0], -ours[..., 2], ours[..., 1]], axis=-1)
    assert np.abs(heads[:, joints] - ours_in_blender).max() < 1e-3  # under a millimetre
    if root_motion:  # the root bone on the floor, where the feet are
        floor = np.median(motion.joint_positions()[..., 1].min(axis=1))
        assert np.abs(heads[:, seen["bones"].index("root"), 2] - floor).max() < 1e-3
