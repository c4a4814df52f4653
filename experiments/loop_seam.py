"""How seamless --loop's dances are, played over and over.

    python -m experiments.loop_seam loop.npz [more.npz ...]

Per file: the step from the last frame into the next cycle's first (the first frame turned and
moved by the per-cycle turn and travel in the metadata, i.e. in root-local space) against the
dance's own 95th-percentile frame step (mean over joints of each joint's move), the change in
velocity there against the 95th percentile of the dance's changes, and the feet's slide (the
slower foot's horizontal speed, m/s) over the last 2 s against the rest.
"""

import sys

import numpy as np

from choreo.formats import read_motion
from choreo.metrics.loops import seam
from choreo.metrics.stepping import foot_speeds


def figures(motion) -> dict:
    step, velocity = seam(motion)
    left, right = foot_speeds(motion.joint_positions(), motion.fps)
    slower = np.minimum(left, right)
    tail = int(2 * motion.fps)
    return {"seconds": motion.duration, "step": step, "velocity": velocity,
            "slide_end": slower[-tail:].mean(), "slide_rest": slower[:-tail].mean()}


if __name__ == "__main__":
    print("| dance | seconds | seam step / p95 | velocity change / p95 | slide, last 2 s (m/s) | slide, the rest |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for path in sys.argv[1:]:
        found = figures(read_motion(path))
        print(f"| {path} | {found['seconds']:.1f} | {found['step']:.2f} | {found['velocity']:.2f} "
              f"| {found['slide_end']:.3f} | {found['slide_rest']:.3f} |")
