"""Footsteps: each foot stands until the body has moved away from it, then steps to where the dance
puts it, as procedural foot placement in games does.

Generated dancers glide: their ankles travel with the root instead of alternating between
standing and swinging (docs/results.md, "Feet"). Neither backend can learn the timing of steps from
M2D (its motion is not aligned with its music), and a pin on the frames where a foot happens to be
slow cannot invent the steps that are missing. So the steps are planned here, from the dance
itself: a foot stays where it landed until the place the dance wants it is ``trigger`` metres
away, then it swings there in ``swing_seconds`` (one foot at a time, the one left furthest
behind first) and lands where the dance has it at the end of the swing. The legs reach the
planned ankle positions by two-bone IK (hip and knee; choreo.skeleton.legs), each foot keeping the
orientation the dance gave it; the root and the upper body are not touched. How far each ankle is
taken toward the plan depends on the dance's genre: Latin dancers step where waltz dancers glide.
Frames a user fixed are left as they are, the correction fading in and out over ``blend_seconds``
around them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..motion.filters import fixed_weights
from ..motion.motion import frame_chunks
from ..skeleton import SMPL24
from ..skeleton.legs import LEGS, TURNED_JOINTS, legs_reaching

if TYPE_CHECKING:
    from ..constraints import Constraints

HORIZONTAL = np.array([1.0, 0.0, 1.0])  # Y is up


@dataclass(frozen=True, kw_only=True)
class FootstepsConfig:
    trigger: float = 0.06  # metres: a standing foot this far (horizontally) from where the dance wants it steps
    swing_seconds: float = 0.25  # how long a step takes in the air
    lift: float = 0.04  # metres the ankle rises at the middle of a step
    blend_seconds: float = 0.3  # fade of the correction next to frames a user fixed
    strength: float | None = None  # how far each ankle goes toward the plan; None: its genre's (GENRE_STRENGTH)

    def __post_init__(self):
        if self.trigger <= 0 or self.swing_seconds <= 0 or self.lift < 0 or self.blend_seconds <= 0:
            raise ParameterError("footsteps: trigger, swing and blend must be positive, lift >= 0")
        if self.strength is not None and not 0.0 <= self.strength <= 1.0:
            raise ParameterError(f"footsteps: strength must be in [0, 1], got {self.strength}")


# How far each ankle goes from where the dance puts it to where the plan does. All the way, feet stand far
# more often than real dancers' and FID_g rises. Real Latin dancers' feet follow the body less than waltz
# dancers' (foot~root over the train split: `python scripts/real_speed_limits.py`), so a Latin dance takes
# more of the plan. Both shares chosen on the validation clips: docs/results.md, "Feet".
GENRE_STRENGTH = {"cha-cha": 0.75, "rumba": 0.75}
DEFAULT_STRENGTH = 0.65  # any other genre, a free-text style, a schedule of styles, no style


def stepping_strength(motion: Motion, config: FootstepsConfig) -> float:
    """The config's strength, or the one of the dance's genre (its metadata's ``genre``, set by a backend)."""
    if config.strength is not None:
        return config.strength
    return GENRE_STRENGTH.get(motion.metadata.get("genre"), DEFAULT_STRENGTH)


def plan_steps(wanted: np.ndarray, fps: float, config: FootstepsConfig = FootstepsConfig()) -> np.ndarray:
    """(T, 2, 3) ankle positions that step: ``wanted`` (T, 2, 3), where the dance puts the left
    and right ankle, followed by feet that stand still between steps."""
    frames = len(wanted)
    swing = max(2, round(config.swing_seconds * fps))
    planned = np.empty_like(wanted)
    anchors = wanted[0].copy()
    stepping = None  # (foot, first frame, landing frame, from, to)
    for t in range(frames):
        if stepping is None:
            drift = np.linalg.norm((wanted[t] - anchors) * HORIZONTAL, axis=-1)
            foot = int(np.argmax(drift))
            if drift[foot] > config.trigger:
                land = min(t + swing, frames - 1)
                stepping = (foot, t, land, anchors[foot].copy(), wanted[land, foot].copy())
        planned[t] = anchors
        if stepping is not None:
            foot, first, land, start, end = stepping
            s = (t - first) / max(land - first, 1)
            ease = s * s * (3 - 2 * s)  # smoothstep: the foot leaves and lands at rest
            planned[t, foot] = start + (end - start) * ease + [0.0, config.lift * np.sin(np.pi * s), 0.0]
            if t >= land:
                anchors[foot], stepping = end, None
    return planned


def footsteps(motion: Motion, fixed: "Constraints | np.ndarray | None" = None,
              config: FootstepsConfig = FootstepsConfig()) -> Motion:
    """The dance with feet that stand and step. Frames in ``fixed`` (a (T,) mask) stay unchanged;
    given :class:`Constraints`, the frames where a leg's rotation is given do (a root path or an
    arm fixes no leg, and the pass turns only the legs)."""
    if hasattr(fixed, "frames_fixing"):
        fixed = fixed.frames_fixing(TURNED_JOINTS)
    fixed = np.zeros(motion.num_frames, bool) if fixed is None else np.asarray(fixed, bool)
    if fixed.shape != (motion.num_frames,):
        raise ParameterError(f"fixed frames must be a ({motion.num_frames},) mask, got {fixed.shape}")
    if motion.num_frames < 3 or tuple(motion.skeleton.parents) != tuple(SMPL24.parents) or fixed.all():
        return motion  # another skeleton's legs are not where SMPL-24's are
    positions = motion.joint_positions()
    wanted = positions[:, [leg[2] for leg in LEGS]]
    weight = stepping_strength(motion, config) * fixed_weights(fixed, motion.fps, config.blend_seconds)[:, None, None]
    targets = wanted + (plan_steps(wanted, motion.fps, config) - wanted) * weight
    rotations = motion.rotations.copy()
    for chunk in frame_chunks(motion.num_frames):  # a song's rotation matrices at once would be large
        rotations[chunk] = legs_reaching(motion.rotations[chunk], positions[chunk], targets[chunk],
                                         motion.skeleton.parents)
    rotations[fixed] = motion.rotations[fixed]  # exactly as given, not merely within rounding
    del positions, targets  # before the new motion's checks copy the rotations once more
    return motion.replace(rotations=rotations, metadata=dict(motion.metadata))
