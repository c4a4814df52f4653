"""Constraints on a dance to be generated: which values are fixed, per frame, joint and root axis.

A :class:`Constraints` is model-free. It holds target root positions and joint rotations and
boolean masks saying which of them are known; generators turn it into whatever their sampler
needs (SGMD: a mask over its 151-d frame vectors, paper eqs. 8-10).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from ..errors import ParameterError
from ..motion import Motion, motion_to_vector
from ..motion.vector import CONTACT_SLICE, ROOT_SLICE, ROTATION_SLICE
from ..skeleton import SMPL24

ALL_JOINTS = tuple(range(SMPL24.num_joints))


@dataclass
class Constraints:
    """Known values of a ``num_frames`` dance at ``fps``; unknown entries are free for the generator."""

    num_frames: int
    fps: float
    root: np.ndarray  # (T, 3) target root positions in metres
    root_known: np.ndarray  # (T, 3) bool, per axis (a floor path fixes x and z only)
    rotations: np.ndarray  # (T, 24, 4) target local rotations, quaternions (w, x, y, z)
    joints_known: np.ndarray  # (T, 24) bool

    @classmethod
    def none(cls, num_frames: int, fps: float) -> "Constraints":
        if num_frames < 1:
            raise ParameterError("a dance needs at least one frame")
        rotations = np.zeros((num_frames, SMPL24.num_joints, 4))
        rotations[..., 0] = 1.0
        return cls(num_frames, float(fps), np.zeros((num_frames, 3)), np.zeros((num_frames, 3), bool), rotations,
                   np.zeros((num_frames, SMPL24.num_joints), bool))

    def fixed_frames(self) -> np.ndarray:
        """(T,) bool: frames with any given value; re-timing must leave them where they are."""
        return self.joints_known.any(axis=1) | self.root_known.any(axis=1)

    def frames_fixing(self, joints: Iterable[int]) -> np.ndarray:
        """(T,) bool: frames where any of ``joints`` has a given rotation (a pass that turns only
        those joints may change every other frame, root-path frames included)."""
        return self.joints_known[:, list(joints)].any(axis=1)

    # -- adding constraints ---------------------------------------------------------------------
    def fix_motion(self, motion: Motion, at: int = 0, joints: Iterable[int] = ALL_JOINTS, root: bool = True,
                   frames: np.ndarray | None = None) -> "Constraints":
        """Fix ``motion``'s frames (all, or the boolean/index ``frames`` of it) starting at frame ``at``."""
        motion = as_smpl(motion, self.fps)
        joints = check_joints(joints)
        index = np.arange(motion.num_frames) if frames is None else np.asarray(frames)
        if index.dtype == bool:
            index = np.flatnonzero(index)
        target = index + at
        if len(target) and (target.min() < 0 or target.max() >= self.num_frames):
            raise ParameterError(f"constrained frames {target.min()}..{target.max()} fall outside the dance's "
                                 f"0..{self.num_frames - 1}")
        self.rotations[target[:, None], np.asarray(joints)[None]] = motion.rotations[index][:, joints]
        self.joints_known[target[:, None], np.asarray(joints)[None]] = True
        if root:
            self.root[target] = motion.root_positions[index]
            self.root_known[target] = True
        return self

    def fix_root_path(self, xz: np.ndarray, height: np.ndarray | None = None) -> "Constraints":
        """Fix the root's floor position (and height, if given) on every frame: (T, 2) and (T,)."""
        xz = np.asarray(xz, dtype=np.float64)
        if xz.shape != (self.num_frames, 2) or not np.isfinite(xz).all():
            raise ParameterError(f"a root path must be {self.num_frames} finite (x, z) points, got shape {xz.shape}")
        self.root[:, [0, 2]] = xz
        self.root_known[:, [0, 2]] = True
        if height is not None:
            height = np.asarray(height, dtype=np.float64)
            if height.shape != (self.num_frames,) or not np.isfinite(height).all():
                raise ParameterError("root heights must be one finite value per frame")
            self.root[:, 1] = height
            self.root_known[:, 1] = True
        return self

    def free(self, frames: np.ndarray | slice, joints: Iterable[int] = ALL_JOINTS, root: bool = True) -> "Constraints":
        """Make ``frames`` x ``joints`` (and the root, if ``root``) unknown again: what inpainting regenerates."""
        rows = np.arange(self.num_frames)[frames]
        self.joints_known[np.ix_(rows, check_joints(joints))] = False
        if root:
            self.root_known[rows] = False
        return self

    # -- what generators read -------------------------------------------------------------------
    @property
    def is_empty(self) -> bool:
        return not (self.joints_known.any() or self.root_known.any())

    def known_fraction(self) -> float:
        return float(self.joints_known.mean())

    def describe(self) -> str:
        """What is given, in words for a summary line: a root path fixes no joint, so the joint
        share alone would read "0 %"."""
        given = []
        if self.joints_known.any():
            given.append(f"{100 * self.joints_known.mean():.0f} % of joint rotations")
        if self.root_known.any():
            frames = self.root_known.any(axis=1).mean()
            given.append(f"the {'floor path' if not self.root_known[:, 1].any() else 'root'} on {100 * frames:.0f} % of frames")
        return " and ".join(given) + " given" if given else "nothing given"

    def target_motion(self) -> Motion:
        return Motion(self.root, self.rotations, fps=self.fps)

    def frame_vectors(self) -> tuple[np.ndarray, np.ndarray]:
        """(T, 151) target frame vectors and the (T, 151) mask of their known channels.

        Contact channels count as known on frames whose every joint and root axis is known (they
        are derived from the motion there); elsewhere the generator decides them.
        """
        vectors = motion_to_vector(self.target_motion())
        mask = np.zeros_like(vectors, dtype=bool)
        mask[:, ROOT_SLICE] = self.root_known
        mask[:, ROTATION_SLICE] = np.repeat(self.joints_known, 6, axis=1)
        mask[:, CONTACT_SLICE] = (self.joints_known.all(1) & self.root_known.all(1))[:, None]
        return vectors, mask


def as_smpl(motion: Motion, fps: float) -> Motion:
    """``motion`` on the SMPL-24 skeleton at ``fps``, or a clear error."""
    if not motion.skeleton.same_topology(SMPL24):
        raise ParameterError(f"constraints need an SMPL-24 motion; this one has {motion.skeleton.num_joints} joints "
                             "in another hierarchy")
    if abs(motion.fps - fps) > 1e-6:
        motion = motion.resample(fps)
    return motion


def check_joints(joints: Iterable[int]) -> list[int]:
    joints = sorted(set(int(j) for j in joints))
    if not joints or joints[0] < 0 or joints[-1] >= SMPL24.num_joints:
        raise ParameterError(f"joint indices must lie in 0..{SMPL24.num_joints - 1}")
    return joints
