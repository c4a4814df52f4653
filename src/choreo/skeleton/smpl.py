"""The SMPL-24 skeleton: joint names, parents and the neutral body's rest offsets.

Inside choreo every motion uses this skeleton, Y up, metres. The rest offsets are the SMPL neutral
template's joint positions relative to their parents (the table EDGE and DGSDP use), so motion we
write matches what AIST++-trained tools expect. +X is the body's left, +Z is where it faces.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

JOINT_NAMES = (
    "pelvis", "l_hip", "r_hip", "spine1", "l_knee", "r_knee", "spine2", "l_ankle", "r_ankle",
    "spine3", "l_foot", "r_foot", "neck", "l_collar", "r_collar", "head", "l_shoulder",
    "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist", "l_hand", "r_hand",
)  # fmt: skip

PARENTS = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21)

REST_OFFSETS = (
    (0.0, 0.0, 0.0),
    (0.05858135, -0.08228004, -0.01766408),
    (-0.06030973, -0.09051332, -0.01354254),
    (0.00443945, 0.12440352, -0.03838522),
    (0.04345142, -0.38646945, 0.008037),
    (-0.04325663, -0.38368791, -0.00484304),
    (0.00448844, 0.1379564, 0.02682033),
    (-0.01479032, -0.42687458, -0.037428),
    (0.01905555, -0.4200455, -0.03456167),
    (-0.00226458, 0.05603239, 0.00285505),
    (0.04105436, -0.06028581, 0.12204243),
    (-0.03483987, -0.06210566, 0.13032329),
    (-0.0133902, 0.21163553, -0.03346758),
    (0.07170245, 0.11399969, -0.01889817),
    (-0.08295366, 0.11247234, -0.02370739),
    (0.01011321, 0.08893734, 0.05040987),
    (0.12292141, 0.04520509, -0.019046),
    (-0.11322832, 0.04685326, -0.00847207),
    (0.2553319, -0.01564902, -0.02294649),
    (-0.26012748, -0.01436928, -0.03126873),
    (0.26570925, 0.01269811, -0.00737473),
    (-0.26910836, 0.00679372, -0.00602676),
    (0.08669055, -0.01063603, -0.01559429),
    (-0.0887537, -0.00865157, -0.01010708),
)

# Joints the field's metrics and losses refer to by index.
LEFT_ANKLE, RIGHT_ANKLE, LEFT_FOOT, RIGHT_FOOT = 7, 8, 10, 11
FOOT_JOINTS = (LEFT_ANKLE, RIGHT_ANKLE, LEFT_FOOT, RIGHT_FOOT)  # order of the 4 contact channels
LEFT_ANKLE_FOOT, RIGHT_ANKLE_FOOT = (LEFT_ANKLE, LEFT_FOOT), (RIGHT_ANKLE, RIGHT_FOOT)
LOWER_BODY_JOINTS = (0, 1, 2, 4, 5, 7, 8, 10, 11)
UPPER_BODY_JOINTS = tuple(j for j in range(24) if j not in LOWER_BODY_JOINTS)


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A kinematic tree: names, parent indices (parents come before children) and rest offsets."""

    names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray = field(repr=False)  # (J, 3) metres, each joint relative to its parent

    def __post_init__(self):
        offsets = np.asarray(self.offsets, dtype=np.float64).reshape(len(self.names), 3)
        object.__setattr__(self, "offsets", offsets)
        if len(self.parents) != len(self.names):
            raise ValueError("one parent per joint is required")
        if any(p >= i for i, p in enumerate(self.parents)):
            raise ValueError("parents must precede their children")

    @property
    def num_joints(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def children(self, joint: int) -> list[int]:
        return [i for i, p in enumerate(self.parents) if p == joint]

    def bone_lengths(self) -> np.ndarray:
        """(J,) length of the bone from each joint's parent to the joint (0 for the root)."""
        return np.linalg.norm(self.offsets, axis=-1)

    def rest_positions(self) -> np.ndarray:
        """(J, 3) joint positions in the rest pose with the root at the origin."""
        positions = np.zeros_like(self.offsets)
        for j, p in enumerate(self.parents):
            if p >= 0:
                positions[j] = positions[p] + self.offsets[j]
        return positions

    def with_offsets(self, offsets: np.ndarray) -> "Skeleton":
        """The same tree with other bone vectors (e.g. a performer's measured proportions)."""
        return Skeleton(self.names, self.parents, np.asarray(offsets, dtype=np.float64))

    def same_topology(self, other: "Skeleton") -> bool:
        return self.names == other.names and self.parents == other.parents


SMPL24 = Skeleton(JOINT_NAMES, PARENTS, np.array(REST_OFFSETS))
