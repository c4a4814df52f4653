"""`Motion`: the one motion type that crosses every boundary in choreo.

A motion is root positions plus local joint rotations on a skeleton at a frame rate. Joint
positions are derived by forward kinematics, never stored, so a motion cannot disagree with itself.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from typing import Iterator, Sequence

import numpy as np

from ..errors import ParameterError
from ..skeleton import SMPL24, Skeleton, forward_kinematics
from ..skeleton import rotations as rot

DEFAULT_FPS = 30.0
MIN_FPS, MAX_FPS = 1.0, 1000.0  # outside these, a frame rate is a damaged file, not a motion
MAX_COORDINATE = 1e5  # metres: 100 km from the origin is a damaged file, and formats lose precision beyond
MAX_BONE = 1e3  # metres: a rest offset past this is a damaged file (and BVH's unit guess would overflow on it)
FRAME_CHUNK = 4096  # frames converted at once where a whole song's intermediates would be large


def frame_chunks(num_frames: int) -> Iterator[slice]:
    """Slices of at most FRAME_CHUNK frames covering ``range(num_frames)``: an hour of dance
    converted at once would hold gigabytes of intermediates."""
    return (slice(first, first + FRAME_CHUNK) for first in range(0, num_frames, FRAME_CHUNK))


def source_name(path: str | os.PathLike) -> str:
    """What ``metadata["source"]`` holds for a motion read from ``path``: the file's name alone.
    Writers carry the metadata into every output (JSON, glb, the preview's title), and an absolute
    path would tell whoever receives one where the input lived (a home folder, a user name)."""
    return os.path.basename(os.fspath(path))


def file_metadata(stored) -> dict:
    """A file's stored metadata as a motion carries it: a dict (anything else: none), without a
    ``loop`` that is not one (choreo.looping reads its ``turn_degrees`` and ``travel_m`` when the
    dance is resampled or put in place: a damaged one would crash there, so it is no loop)."""
    metadata = dict(stored) if isinstance(stored, dict) else {}
    if "loop" in metadata and not _is_loop(metadata["loop"]):
        del metadata["loop"]
    return metadata


def _is_loop(loop) -> bool:
    def finite(value) -> bool:
        return type(value) in (int, float) and bool(np.isfinite(value))

    travel = loop.get("travel_m") if isinstance(loop, dict) else None
    return (isinstance(loop, dict) and finite(loop.get("turn_degrees")) and isinstance(travel, list)
            and len(travel) == 2 and all(finite(v) for v in travel))


@dataclass(eq=False)
class Motion:
    """A skeleton animation. Y up, metres.

    Attributes:
        root_positions: (T, 3) world position of joint 0.
        rotations: (T, J, 4) local joint rotations as unit quaternions (w, x, y, z); joint 0's is
            the global orientation.
        fps: frames per second.
        skeleton: the kinematic tree and bone offsets the rotations animate.
        metadata: free-form provenance (source file, genre, seed...), carried into writers.
    """

    root_positions: np.ndarray
    rotations: np.ndarray
    fps: float = DEFAULT_FPS
    skeleton: Skeleton = SMPL24
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        self.root_positions = np.asarray(self.root_positions, dtype=np.float64)
        self.rotations = np.asarray(self.rotations, dtype=np.float64)
        num_frames = self.root_positions.shape[0]
        if self.root_positions.shape != (num_frames, 3):
            raise ParameterError(f"root positions must have shape (T, 3), got {self.root_positions.shape}")
        expected = (num_frames, self.skeleton.num_joints, 4)
        if self.rotations.shape != expected:
            raise ParameterError(f"rotations must have shape {expected}, got {self.rotations.shape}")
        if not (np.isfinite(self.root_positions).all() and np.isfinite(self.rotations).all()):
            raise ParameterError("motion contains NaN or infinite values")
        if not MIN_FPS <= self.fps <= MAX_FPS:
            raise ParameterError(f"fps must be between {MIN_FPS:g} and {MAX_FPS:g}, got {self.fps:g}")
        if num_frames and np.abs(self.root_positions).max() > MAX_COORDINATE:
            raise ParameterError(f"root positions beyond {MAX_COORDINATE:g} m (wrong units, or a damaged file)")
        offsets = self.skeleton.offsets
        if not np.isfinite(offsets).all() or np.abs(offsets).max(initial=0.0) > MAX_BONE:
            raise ParameterError(f"bone offsets must be finite and under {MAX_BONE:g} m (a damaged file?)")
        norms = np.linalg.norm(self.rotations, axis=-1, keepdims=True)
        if (norms < 1e-8).any():
            raise ParameterError("motion contains a zero quaternion")
        self.rotations = self.rotations / norms

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def from_rotation_matrices(cls, root_positions, rotmats, **kwargs) -> "Motion":
        """From (T, J, 3, 3) local rotation matrices."""
        return cls(root_positions, rot.matrix_to_quaternion(np.asarray(rotmats, dtype=np.float64)), **kwargs)

    @classmethod
    def from_axis_angle(cls, root_positions, axis_angle, **kwargs) -> "Motion":
        """From (T, J, 3) or (T, J*3) axis-angle rotations, as SMPL/AIST++ store them."""
        axis_angle = np.asarray(axis_angle, dtype=np.float64)
        axis_angle = axis_angle.reshape(axis_angle.shape[0], -1, 3)
        return cls(root_positions, rot.axis_angle_to_quaternion(axis_angle), **kwargs)

    @classmethod
    def rest(cls, num_frames: int, fps: float = DEFAULT_FPS, skeleton: Skeleton = SMPL24,
             root_height: float | None = None) -> "Motion":
        """A motionless rest pose with the feet on the floor (y = 0) unless told otherwise."""
        rotations = np.zeros((num_frames, skeleton.num_joints, 4))
        rotations[..., 0] = 1.0
        if root_height is None:
            root_height = -skeleton.rest_positions()[:, 1].min()
        root = np.tile([0.0, root_height, 0.0], (num_frames, 1))
        return cls(root, rotations, fps=fps, skeleton=skeleton)

    # -- views --------------------------------------------------------------------------------
    @property
    def num_frames(self) -> int:
        return self.root_positions.shape[0]

    @property
    def num_joints(self) -> int:
        return self.skeleton.num_joints

    @property
    def duration(self) -> float:
        """Seconds covered, counting each frame as 1/fps long."""
        return self.num_frames / self.fps

    def __len__(self) -> int:
        return self.num_frames

    def rotation_matrices(self) -> np.ndarray:
        """(T, J, 3, 3) local rotation matrices."""
        return rot.quaternion_to_matrix(self.rotations)

    def axis_angle(self) -> np.ndarray:
        """(T, J, 3) local rotations as rotation vectors (a chunk of frames at a time, as joint_positions)."""
        out = np.empty((self.num_frames, self.num_joints, 3))
        for chunk in frame_chunks(self.num_frames):
            out[chunk] = rot.quaternion_to_axis_angle(self.rotations[chunk])
        return out

    def joint_positions(self, dtype=np.float64) -> np.ndarray:
        """(T, J, 3) world joint positions by forward kinematics, a chunk of frames at a time
        (an hour of dance would otherwise hold gigabytes of rotation matrices at once); ``dtype``
        float32 rounds each chunk as it is done (as ``.astype(np.float32)`` would, without a float64 copy)."""
        out = np.empty((self.num_frames, self.num_joints, 3), dtype)
        for chunk in frame_chunks(self.num_frames):
            out[chunk] = forward_kinematics(rot.quaternion_to_matrix(self.rotations[chunk]), self.root_positions[chunk],
                                            self.skeleton.offsets, self.skeleton.parents)
        return out

    # -- editing ------------------------------------------------------------------------------
    def replace(self, **changes) -> "Motion":
        return replace(self, **changes)

    def slice_frames(self, start: int | None = None, stop: int | None = None) -> "Motion":
        """Frames [start, stop) as a new motion (negative indices as in Python)."""
        window = slice(start, stop)
        return self.replace(root_positions=self.root_positions[window].copy(),
                            rotations=self.rotations[window].copy(), metadata=dict(self.metadata))

    def __getitem__(self, frames: slice) -> "Motion":
        if not isinstance(frames, slice) or frames.step not in (None, 1):
            raise ParameterError("motions are sliced with contiguous frame ranges, e.g. motion[30:90]")
        return self.slice_frames(frames.start, frames.stop)

    def slice_seconds(self, start: float = 0.0, stop: float | None = None) -> "Motion":
        first = int(round(start * self.fps))
        last = None if stop is None else int(round(stop * self.fps))
        return self.slice_frames(first, last)

    @staticmethod
    def concatenate(motions: Sequence["Motion"]) -> "Motion":
        """Join motions end to end; they must share frame rate and skeleton topology."""
        if not motions:
            raise ParameterError("nothing to concatenate")
        first = motions[0]
        for other in motions[1:]:
            if not np.isclose(other.fps, first.fps):
                raise ParameterError(f"cannot concatenate motions at {first.fps} and {other.fps} fps")
            if not other.skeleton.same_topology(first.skeleton):
                raise ParameterError("cannot concatenate motions on different skeletons")
        return first.replace(
            root_positions=np.concatenate([m.root_positions for m in motions]),
            rotations=np.concatenate([m.rotations for m in motions]),
            metadata=dict(first.metadata),
        )

    def resample(self, fps: float) -> "Motion":
        """The same motion at another frame rate: linear root, slerped rotations.

        Frame i of the result sits at time i / fps; the result covers the same duration (frames
        falling after the last source frame hold it).
        """
        if not fps > 0:
            raise ParameterError(f"fps must be positive, got {fps}")
        if np.isclose(fps, self.fps):
            return self.replace(metadata=dict(self.metadata))
        num_frames = max(1, int(round(self.num_frames * fps / self.fps)))
        source_time = np.arange(num_frames) * self.fps / fps  # in source frames
        return self.sample_frames(source_time).replace(fps=float(fps))

    def sample_frames(self, source_frames: np.ndarray) -> "Motion":
        """Frames at fractional source indices (clamped to the clip): linear root, slerped rotations.

        The building block of resampling and of time-warping (a warped clip is its frames read
        at a non-uniform pace).
        """
        lower, upper, weight = frames_between(source_frames, self.num_frames)
        root = (1 - weight)[:, None] * self.root_positions[lower] + weight[:, None] * self.root_positions[upper]
        rotations = np.empty((len(weight), self.num_joints, 4))
        for chunk in frame_chunks(len(weight)):  # a song's slerp temporaries at once would be large
            rotations[chunk] = rot.quaternion_slerp(
                self.rotations[lower[chunk]], self.rotations[upper[chunk]],
                np.broadcast_to(weight[chunk, None], (len(weight[chunk]), self.num_joints)).copy(),
            )
        return self.replace(root_positions=root, rotations=rotations, metadata=dict(self.metadata))

    def translated(self, offset: Sequence[float]) -> "Motion":
        return self.replace(root_positions=self.root_positions + np.asarray(offset, dtype=np.float64))

    def with_skeleton(self, skeleton: Skeleton) -> "Motion":
        """Same rotations on another skeleton of the same topology (e.g. the SMPL template)."""
        if not skeleton.same_topology(self.skeleton):
            raise ParameterError("skeletons differ in topology")
        return self.replace(skeleton=skeleton)


def frames_between(frames, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lower, upper, weight): the whole frames on either side of fractional ``frames``, clamped to
    ``count`` frames, and the upper one's weight; how every linear read between frames here starts."""
    frames = np.clip(np.asarray(frames, dtype=np.float64), 0, count - 1)
    lower = np.floor(frames).astype(int)
    return lower, np.minimum(lower + 1, count - 1), frames - lower


def positions_at(joint_positions: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """(len(frames), J, 3) joints at fractional ``frames`` (clipped to the motion), linearly
    interpolated: cheap where speeds, not rotations, are what is read."""
    frames = np.clip(np.asarray(frames, dtype=np.float64), 0, len(joint_positions) - 1)
    out = np.empty((len(frames), *joint_positions.shape[1:]), np.result_type(joint_positions, np.float64))
    for chunk in frame_chunks(len(frames)):  # the temporaries of a song are large
        lower, upper, weight = frames_between(frames[chunk], len(joint_positions))
        weight = weight[:, None, None]
        out[chunk] = (1 - weight) * joint_positions[lower] + weight * joint_positions[upper]
    return out
