"""What --in-place leaves of a dance's travel and of its sway.

    python -m experiments.in_place_sway dance.npz [more.npz ...]

Per file: the ground track's farthest distance from the start (choreo.motion.travel) before and
after choreo.motion.delivery.in_place, and the share of the sway around the track (its standard
deviation along x and z) that is left.
"""

import sys

import numpy as np

from choreo.formats import read_motion
from choreo.motion.delivery import in_place
from choreo.motion.travel import ground_track, track_reach


def sway(motion) -> np.ndarray:
    return (motion.root_positions[:, [0, 2]] - ground_track(motion.root_positions, motion.fps)).std(0)


print("| dance | seconds | reach before (m) | reach after (m) | sway left (x, z) |")
print("| --- | ---: | ---: | ---: | --- |")
for path in sys.argv[1:]:
    motion = read_motion(path)
    still = in_place(motion)
    reach = [track_reach(ground_track(m.root_positions, m.fps)) for m in (motion, still)]
    left = sway(still) / sway(motion)
    print(f"| {path} | {motion.duration:.1f} | {reach[0]:.2f} | {reach[1]:.3f} | {left[0]:.2f}, {left[1]:.2f} |")
