"""Constraints on the graph's walk: a root path to follow, poses to pass through, frames to keep,
and, where no root path is given, the floor: a walk that strays further than ``floor_radius`` from
its start is priced back towards it.

The dynamic graph picks one node per second. Under constraints each candidate node is also
priced by how far from the given root positions it would carry the dancer and how unlike the
given poses it is, so the walk heads along the path and into the keys: Kovar, Gleicher and
Pighin's path synthesis on motion graphs ("Motion Graphs", 2002), done greedily a second at a
time like the rest of the walk. Whatever the walk cannot reach exactly, the core's displacement
map bends the assembled dance onto afterwards (``choreo.constraints.displace_motion``).

To price a node's root the guide follows where the assembly will play each segment: a segment
that continues the current one keeps its placement, any other is turned and moved so that its
first frame stands where the current segment would have gone next, facing the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from choreo.constraints import Constraints
from choreo.motion import Motion
from choreo.motion.motion import frames_between
from choreo.motion.stitch import facing_yaw, frame_local_positions, rotate_about_y
from choreo.skeleton import SMPL24

from .config import NODE_FRAMES, GraphConfig
from .repertoire import Repertoire

MAX_PRICED_FRAMES = 5  # given frames priced per second (evenly chosen): bounds the cost of a step


@dataclass(frozen=True)
class Placement:
    """Where a segment is played: turned by ``angle`` about +y, then moved by ``offset`` (y = 0)."""

    angle: float
    offset: np.ndarray  # (3,)


class Guide:
    """The constraints' costs for each second's candidate nodes, and the placement of the walk."""

    def __init__(self, constraints: Constraints, repertoire: Repertoire, config: GraphConfig):
        self.repertoire, self.config = repertoire, config
        self.num_frames = constraints.num_frames
        self.root_known = constraints.root_known[:, [0, 2]].all(1)
        self.root = constraints.root * np.array([1.0, 0.0, 1.0])  # floor positions
        self.posed = constraints.joints_known.all(1) & constraints.root_known[:, 1]
        self.poses = None  # (T, 24, 3) where poses are given: a free walk or a path has none to hold
        facing = np.zeros(self.num_frames)
        if self.posed.any():  # forward kinematics on the posed frames only (a path has none)
            self.poses = np.zeros((self.num_frames, SMPL24.num_joints, 3), np.float32)
            given = Motion(constraints.root[self.posed], constraints.rotations[self.posed], fps=constraints.fps,
                           skeleton=SMPL24.with_offsets(repertoire.offsets))
            positions = given.joint_positions()
            self.poses[self.posed] = frame_local_positions(positions)
            facing[self.posed] = facing_yaw(positions)
        self.start = self.start_placement(facing)
        self.constrained = not constraints.is_empty
        self.floored = config.keeps_floor and not self.root_known.any()
        self.placement: Placement | None = None
        self.candidates: tuple[np.ndarray, np.ndarray] | None = None  # (angles, offsets) of the last step

    def start_placement(self, facing: np.ndarray) -> tuple[np.ndarray, float]:
        """Where the first node starts (x, 0, z) and which way it faces: the first given root
        position and, if that frame's pose is given, its facing (else the origin, facing +z)."""
        known = np.flatnonzero(self.root_known)
        if not len(known):
            return np.zeros(3), 0.0
        return self.root[known[0]].copy(), float(facing[known[0]])

    def cost(self, t: int, clips: np.ndarray, frames: np.ndarray, follows: np.ndarray, current) -> np.ndarray:
        """(C,) extra cost of each candidate node for second ``t``: ``clips`` (C,), the clip frames
        each would play (C, 30), and which of them continue the ``current`` node's segment."""
        self.candidates = self.placements(clips, frames[:, 0], follows, current)
        span = np.arange(t * NODE_FRAMES, min((t + 1) * NODE_FRAMES, self.num_frames))
        cost = np.zeros(len(clips))
        rooted = priced(span[self.root_known[span]])
        if len(rooted) and self.config.path_cost:
            placed = self.placed_roots(clips, frames[:, rooted - t * NODE_FRAMES], *self.candidates)
            cost += self.config.path_cost * np.square(placed - self.root[rooted]).sum(-1).mean(-1)
        posed = priced(span[self.posed[span]])
        if len(posed) and self.config.key_cost:
            played = np.clip(np.rint(frames[:, posed - t * NODE_FRAMES]).astype(int), 0, self.repertoire.poses.shape[1] - 1)
            poses = self.repertoire.poses[clips[:, None], played].astype(np.float32)  # (C, F, 24, 3)
            cost += self.config.key_cost * np.square(poses - self.poses[posed]).sum(-1).mean((-1, -2))
        if self.floored:
            ends = self.placed_roots(clips, frames[:, -1:], *self.candidates)[:, 0]
            beyond = np.maximum(np.linalg.norm(ends - self.start[0], axis=-1) - self.config.floor_radius, 0.0)
            cost += self.config.floor_cost * np.square(beyond)
        return cost

    def root_error(self, motion: Motion) -> float | None:
        """Mean floor distance (m) from ``motion``'s root to the given root where one is given:
        how far the walk itself came from the path before any bending."""
        if not self.root_known.any():
            return None
        gap = (motion.root_positions - self.root) * np.array([1.0, 0.0, 1.0])
        return float(np.linalg.norm(gap[self.root_known], axis=-1).mean())

    def chose(self, best: int) -> None:
        """The walk took candidate ``best`` of the last :meth:`cost`: its placement is now the walk's."""
        angles, offsets = self.candidates
        self.placement = Placement(float(angles[best]), offsets[best].copy())

    def placements(self, clips: np.ndarray, first: np.ndarray, follows: np.ndarray, current):
        """(angles (C,), offsets (C, 3)) each candidate would be played with (see the module doc)."""
        repertoire = self.repertoire
        if current is None or self.placement is None:
            target, yaw = self.start
        else:
            rate = max(float(current.frames[-1] - current.frames[-2]), 0.5)
            ahead = np.array([[float(current.frames[-1]) + rate]])
            target = self.placed_roots(np.array([current.clip]), ahead, np.array([self.placement.angle]),
                                       self.placement.offset[None])[0, 0]
            yaw = self.placement.angle + float(facing_at(repertoire, np.array([current.clip]), ahead[0])[0])
        angles = yaw - facing_at(repertoire, clips, first)
        starts = rotate_about_y(roots_at(repertoire, clips[:, None], first[:, None])[:, 0], angles)
        offsets = (target - starts) * np.array([1.0, 0.0, 1.0])
        if current is not None and self.placement is not None:
            angles[follows], offsets[follows] = self.placement.angle, self.placement.offset
        return angles, offsets

    def placed_roots(self, clips: np.ndarray, frames: np.ndarray, angles: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """(C, F, 3) floor positions (y = 0) of the root on clip ``frames`` (C, F) when played so."""
        roots = roots_at(self.repertoire, clips[:, None], frames)
        return (rotate_about_y(roots, angles[:, None]) + offsets[:, None]) * np.array([1.0, 0.0, 1.0])


def roots_at(repertoire: Repertoire, clips: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Root positions (..., 3) of ``clips`` at fractional ``frames`` (broadcast together), as the
    assembly plays them: rounding the frames drifted the placement a few cm per jump."""
    before, after, weight = frames_between(frames, repertoire.root_positions.shape[1])
    start = repertoire.root_positions[clips, before].astype(np.float64)
    return start + (repertoire.root_positions[clips, after] - start) * weight[..., None]


def facing_at(repertoire: Repertoire, clips: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Headings (radians) of ``clips`` at fractional ``frames``, turning the short way between frames."""
    before, after, weight = frames_between(frames, repertoire.facing.shape[1])
    start = repertoire.facing[clips, before]
    turn = np.angle(np.exp(1j * (repertoire.facing[clips, after] - start)))
    return start + turn * weight


def priced(frames: np.ndarray) -> np.ndarray:
    """At most ``MAX_PRICED_FRAMES`` of ``frames``, evenly spread, first and last included."""
    if len(frames) <= MAX_PRICED_FRAMES:
        return frames
    return frames[np.rint(np.linspace(0, len(frames) - 1, MAX_PRICED_FRAMES)).astype(int)]
