"""The motion repertoire: 8 s clips the graph may dance, with what the search needs precomputed.

Per clip: root positions and joint rotations (to play it), each frame's pose seen from the
dancer (to price transitions), the style vector and motion-beat count of its middle 4 s (to
select it) and its 8 s tempo-density (to warp it). Stored as a plain .npz (no pickles); since
format 2 each frame of motion once, however many overlapping clips play it, and the poses are
computed from the stored rotations when the file is read.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import torch

from choreo.errors import InputError, MotionFormatError
from choreo.fileio import atomic_path, input_file
from choreo.formats.safe_arrays import load_npz
from choreo.motion import Motion
from choreo.motion.stitch import LEFT_HIP, RIGHT_HIP, frame_local_positions, heading_of, local_positions
from choreo.skeleton import SMPL24
from choreo.skeleton.rotations import quaternion_to_matrix

from .config import CLIP_FRAMES, FPS, WINDOW_FRAMES
from .data import beat_count, excerpt_starts
from .model import ChoreoGraphModel

FORMAT_VERSION = 2  # written: per-frame arrays pooled, each clip an offset into the pool
READABLE_VERSIONS = (1, 2)  # 1: every clip's frames in full (four times the frames for clips 2 s apart)
POOLED = {"root_positions": np.float32, "rotations": np.float16}  # per-frame arrays stored in format 2, as stored
MIDDLE = slice((CLIP_FRAMES - WINDOW_FRAMES) // 2, (CLIP_FRAMES + WINDOW_FRAMES) // 2)


@dataclass
class Repertoire:
    names: np.ndarray  # (N,) "source@start_frame"
    genres: np.ndarray  # (N,) genre or ""
    root_positions: np.ndarray  # (N, 240, 3) float32
    rotations: np.ndarray  # (N, 240, 24, 4) float32 unit quaternions (float16 on disk)
    offsets: np.ndarray  # (24, 3) the skeleton every clip is played on
    poses: np.ndarray  # (N, 240, 24, 3) float16, each frame local to itself
    style: np.ndarray  # (N, style_dim) float32, middle 4 s
    beat_counts: np.ndarray  # (N,) float32, middle 4 s
    tempo: np.ndarray  # (N, 240) float32 tempo-density
    source: np.ndarray  # () str: how it was built

    def __len__(self) -> int:
        return len(self.names)

    def clip_motion(self, index: int) -> Motion:
        return Motion(self.root_positions[index], self.rotations[index], fps=FPS,
                      skeleton=SMPL24.with_offsets(self.offsets))

    @cached_property
    def origins(self) -> tuple[np.ndarray, np.ndarray]:
        """Per clip, an id of the motion it was cut from and the frame it starts at there (from
        the "source@start" names): clips cut from one motion overlap, and this says where."""
        def split(name: str) -> tuple[str, int]:
            source, _, start = name.rpartition("@")
            return (source, int(start)) if source and start.isdigit() else (name, 0)

        sources, starts = zip(*(split(str(name)) for name in self.names))
        _, ids = np.unique(np.array(sources), return_inverse=True)
        return ids.astype(np.int64), np.array(starts, np.int64)

    @cached_property
    def facing(self) -> np.ndarray:
        """(N, 240) each frame's heading about +y, as ``facing_yaw`` gives it from the joints: the
        hips hang off the pelvis, so their left-right axis is the pelvis rotation's."""
        across = self.offsets[LEFT_HIP] - self.offsets[RIGHT_HIP]
        return heading_of(quaternion_to_matrix(self.rotations[:, :, 0]) @ across)

    def genre_mask(self, genre: str | None) -> np.ndarray:
        return np.ones(len(self), bool) if genre is None else self.genres == genre

    def save(self, path: str | Path) -> None:
        arrays = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in (*POOLED, "poses")}
        pool, clip_starts = pooled_frames(self)  # rotations as float16: 0.06 degree steps, half the bytes
        arrays.update({f"pool_{key}": array for key, array in pool.items()}, clip_starts=clip_starts)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as handle:
                np.savez_compressed(handle, format_version=FORMAT_VERSION, **arrays)

    @classmethod
    def load(cls, path: str | Path) -> "Repertoire":
        path = input_file(path, "repertoire")
        try:
            try:
                data = load_npz(path)  # sizes checked before anything is decompressed
            except MotionFormatError as error:
                raise InputError(f"{path} is not a readable repertoire: {str(error).removeprefix(f'{path}: ')}") from None
            version = int(data["format_version"])
            if version not in READABLE_VERSIONS:
                raise InputError(f"{path} has repertoire format {version}, expected one of {READABLE_VERSIONS}")
            values = {f.name: data[f.name] for f in fields(cls) if version == 1 or f.name not in (*POOLED, "poses")}
            if version == 2:
                values.update(unpooled_frames(data, len(values["names"]) if np.ndim(values["names"]) == 1 else 0, str(path)))
        except InputError:
            raise
        except Exception as error:
            raise InputError(f"{path} is not a readable repertoire ({type(error).__name__})") from None
        check_arrays(values, str(path))
        values["rotations"] = values["rotations"].astype(np.float32)
        return cls(**values)


def pooled_frames(repertoire: Repertoire) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The per-frame arrays with each frame of a source stored once, and the pool frame each clip
    starts at. Clips of one source are taken in order of their start: a clip starting d frames
    after the one before it (d < a clip's length) whose shared frames are equal, as stored, adds
    only its last d frames; any other clip adds all of its own."""
    stored = {key: getattr(repertoire, key).astype(dtype) for key, dtype in POOLED.items()}
    ids, starts = repertoire.origins
    pieces: dict[str, list[np.ndarray]] = {key: [] for key in POOLED}
    clip_starts = np.zeros(len(repertoire), np.int64)
    size, previous = 0, None
    for clip in np.lexsort((starts, ids)):
        step = int(starts[clip] - starts[previous]) if previous is not None and ids[clip] == ids[previous] else -1
        continues = 0 <= step < CLIP_FRAMES and all(
            np.array_equal(array[clip][: CLIP_FRAMES - step], array[previous][step:]) for array in stored.values())
        new = CLIP_FRAMES if not continues else step  # frames this clip adds at the pool's end
        clip_starts[clip] = size + new - CLIP_FRAMES
        for key, array in stored.items():
            pieces[key].append(array[clip][CLIP_FRAMES - new:])
        size, previous = size + new, clip
    return {key: np.concatenate(parts) for key, parts in pieces.items()}, clip_starts


def unpooled_frames(data, count: int, where: str) -> dict[str, np.ndarray]:
    """Every clip's per-frame arrays cut from a format 2 pool, after checking the pool and the
    clip offsets (a bad offset would otherwise index past the pool or wrap around); the poses
    from the pool's rotations, once per pooled frame."""
    if count == 0:
        raise InputError(f"{where}: empty repertoire (no clip names)")
    pool = {key: data[f"pool_{key}"] for key in POOLED}
    clip_starts = data["clip_starts"]
    frames = len(pool["root_positions"]) if pool["root_positions"].ndim else 0
    for key, shape in (("root_positions", (3,)), ("rotations", (24, 4))):
        if pool[key].shape != (frames, *shape) or pool[key].dtype.kind != "f":
            raise InputError(f"{where}: pool_{key} is {pool[key].dtype} {pool[key].shape}, expected {frames}x"
                             f"{'x'.join(map(str, shape))} numbers (one row per pooled frame)")
    if (clip_starts.shape != (count,) or clip_starts.dtype.kind not in "iu"
            or (clip_starts.min() < 0 or clip_starts.max() > frames - CLIP_FRAMES)):
        raise InputError(f"{where}: clip_starts must be {count} whole numbers from 0 to {frames - CLIP_FRAMES} "
                         f"(where each 8 s clip starts among {frames} pooled frames)")
    offsets = data["offsets"]
    if offsets.shape != (24, 3) or offsets.dtype.kind != "f" or not np.isfinite(offsets).all():
        raise InputError(f"{where}: offsets must be 24x3 finite numbers (the SMPL-24 skeleton)")
    if not all(np.isfinite(array).all() for array in pool.values()):
        raise InputError(f"{where}: the pooled frames hold NaN or infinite values")
    pool["poses"] = frame_poses(pool["root_positions"], pool["rotations"], offsets)
    index = clip_starts.astype(np.int64)[:, None] + np.arange(CLIP_FRAMES)
    return {key: array[index] for key, array in pool.items()}


def frame_poses(root_positions: np.ndarray, rotations: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(T, 24, 3) float16: each frame's joints local to itself (what transitions are priced on)."""
    motion = Motion(root_positions.astype(np.float64), rotations.astype(np.float64), fps=FPS,
                    skeleton=SMPL24.with_offsets(offsets))
    return frame_local_positions(motion.joint_positions()).astype(np.float16)


# Per array: the shape after the clip axis (None: any positive size) and the dtype kinds accepted.
CLIP_ARRAYS = {
    "names": ((), "U"), "genres": ((), "U"), "root_positions": ((CLIP_FRAMES, 3), "f"),
    "rotations": ((CLIP_FRAMES, 24, 4), "f"), "poses": ((CLIP_FRAMES, 24, 3), "f"), "style": ((None,), "f"),
    "beat_counts": ((), "fiu"), "tempo": ((CLIP_FRAMES,), "f"),
}  # fmt: skip


def check_arrays(values: dict[str, np.ndarray], where: str) -> None:
    """Refuse a repertoire whose arrays disagree in clip count, shape or kind, or hold NaN:
    the graph indexes them all by clip and would fail far from the file otherwise."""
    count = len(values["names"]) if np.ndim(values["names"]) == 1 else 0
    if count == 0:
        raise InputError(f"{where}: empty repertoire (no clip names)")
    for key, (shape, kinds) in CLIP_ARRAYS.items():
        array = values[key]
        expected = (count,) + shape
        fits = array.ndim == len(expected) and all(e is None and n > 0 or n == e
                                                   for n, e in zip(array.shape, expected))
        if not fits or array.dtype.kind not in kinds:
            wanted = "x".join("D" if e is None else str(e) for e in expected)
            raise InputError(f"{where}: {key} is {array.dtype} {array.shape}, expected {wanted} for {count} "
                             "clips of 8 s at 30 fps on SMPL-24")
        if kinds != "U" and not np.isfinite(array).all():
            raise InputError(f"{where}: {key} holds NaN or infinite values")
    offsets = values["offsets"]
    if offsets.shape != (24, 3) or offsets.dtype.kind != "f" or not np.isfinite(offsets).all():
        raise InputError(f"{where}: offsets must be 24x3 finite numbers (the SMPL-24 skeleton)")
    if values["source"].dtype.kind != "U":
        raise InputError(f"{where}: source is not text")


@dataclass(frozen=True)
class SpeedLimits:
    """Clips moving faster than this (m/s, between any two frames) are left out of a repertoire:
    glitches that warping (up to twice as fast) would only make worse."""

    joint: float | None = None  # any joint: a limb flipping between two frames
    root: float | None = None  # the root: the whole body dashing off faster than anyone travels

    def admit(self, positions: np.ndarray) -> bool:
        """Whether a clip's (frames, joints, 3) world positions at 30 fps stay within the limits."""
        speed = np.linalg.norm(np.diff(positions, axis=0), axis=-1) * FPS
        return ((self.joint is None or speed.max() <= self.joint)
                and (self.root is None or speed[:, 0].max() <= self.root))


def build_repertoire(motions: Sequence[tuple[str, Motion, str | None]], model: ChoreoGraphModel, stride: int,
                     source: str, progress: Callable[[int, int], None] | None = None,
                     limits: SpeedLimits = SpeedLimits()) -> Repertoire:
    """Cut every 8 s clip (``stride`` frames apart) from (name, motion at 30 fps, genre) and
    describe it with ``model``, leaving out clips faster than ``limits``. All motions are played
    on the first one's skeleton."""
    names, genres, roots, rotations, positions = [], [], [], [], []
    for name, motion, genre in motions:
        world = motion.joint_positions()
        for start in excerpt_starts(motion.num_frames, CLIP_FRAMES, stride):
            stop = start + CLIP_FRAMES
            if not limits.admit(world[start:stop]):
                continue
            names.append(f"{name}@{start}")
            genres.append(genre or "")
            roots.append(motion.root_positions[start:stop])
            rotations.append(motion.rotations[start:stop])
            positions.append(world[start:stop])
    if not names:
        raise InputError("no motion gives an 8 s clip (too short, or every clip faster than the speed limit)")
    positions = np.stack(positions).astype(np.float32)
    local = np.stack([local_positions(p) for p in positions]).astype(np.float32)
    middle = np.stack([local_positions(p[MIDDLE]) for p in positions]).astype(np.float32)
    style, tempo = [], []
    for first in range(0, len(names), 64):
        batch = slice(first, first + 64)
        style.append(model.motion_style(torch.from_numpy(middle[batch])).numpy())
        tempo.append(model.motion_tempo_density(torch.from_numpy(local[batch])).numpy())
        if progress:
            progress(min(first + 64, len(names)), len(names))
    return Repertoire(
        names=np.array(names), genres=np.array(genres), root_positions=np.stack(roots).astype(np.float32),
        rotations=np.stack(rotations).astype(np.float32), offsets=np.asarray(motions[0][1].skeleton.offsets, np.float32),
        poses=frame_local_positions(positions).astype(np.float16), style=np.concatenate(style),
        beat_counts=np.array([beat_count(p[MIDDLE]) for p in positions], np.float32), tempo=np.concatenate(tempo),
        source=np.array(source))
