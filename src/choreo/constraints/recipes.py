"""The controllable commands' constraints as library calls: seed motion, in-betweening, inpainting, a path.

Each takes the analysed song (a :class:`~choreo.music.Music`) and what the user gives, and returns
the :class:`Constraints` to dance under; pass it as ``choreo.dance(song, constraints=...)``, or
pass ``functools.partial(recipe, ...)`` to have it built from the song once analysed. Frames are
counted in the given motion's own frames, at its own rate, as its file numbers them.

    >>> from functools import partial
    >>> from choreo.formats import read_motion
    >>> dance = read_motion("dance.bvh")
    >>> choreo.dance("song.mp3", constraints=partial(inpainting, motion=dance, frames=slice(60, 120)))
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Iterable, Sequence

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from .mask import ALL_JOINTS, Constraints, as_smpl
from .parse import path_to_frames, read_root_path

if TYPE_CHECKING:
    from ..music import Music


def seed_motion(music: "Music", motion: Motion) -> Constraints:
    """A dance that opens with ``motion`` (every frame of it the song covers) and continues it."""
    opening = as_smpl(motion, music.fps)
    return Constraints.none(music.num_frames, music.fps).fix_motion(opening.slice_frames(0, music.num_frames))


def between_poses(music: "Music", start: Motion | None = None, end: Motion | None = None,
                  keys: Sequence[tuple[float, Motion]] = ()) -> Constraints:
    """A dance through given poses: ``start`` on the first frame, ``end`` on the last, and each of
    ``keys`` (seconds, pose) at its time; each pose is its motion's first frame."""
    if start is None and end is None and not keys:
        raise ParameterError("give at least one of a start pose, an end pose or a keyframe")
    fixed = Constraints.none(music.num_frames, music.fps)
    for seconds, pose in ([(0.0, start)] if start is not None else []) + list(keys):
        frame = round(seconds * music.fps)
        if frame >= music.num_frames:
            raise ParameterError(f"keyframe at {seconds:g} s is past the song's end ({music.duration:.1f} s)")
        fixed.fix_motion(pose, at=frame)
    if end is not None:
        fixed.fix_motion(end, at=music.num_frames - 1)
    return fixed


def inpainting(music: "Music", motion: Motion, frames: slice | None = None,
               joints: Iterable[int] = ALL_JOINTS) -> Constraints:
    """``motion`` kept except ``joints`` over ``frames`` (a slice of ``motion``'s own frames, end
    exclusive; None: all of them), which are danced afresh to the song."""
    given = as_smpl(motion, music.fps)
    fixed = Constraints.none(music.num_frames, music.fps).fix_motion(given.slice_frames(0, music.num_frames))
    joints = tuple(joints)
    fixed.free(in_song_frames(frames, motion, music) if frames is not None else slice(0, music.num_frames),
               joints, root=0 in joints)
    if fixed.is_empty:
        raise ParameterError("nothing of the dance would be kept: dance afresh instead (choreo generate)")
    return fixed


def along_path(music: "Music", path: str | os.PathLike) -> Constraints:
    """A dance whose root follows the floor path in ``path`` (a CSV, or a motion file's root),
    stretched over the whole song (choreo.constraints.read_root_path)."""
    xz, heights = path_to_frames(*read_root_path(path), music.num_frames)
    return Constraints.none(music.num_frames, music.fps).fix_root_path(xz, heights)


def in_song_frames(frames: slice, motion: Motion, music: "Music") -> slice:
    """``frames`` of ``motion`` (its own numbering, end exclusive) as the song's frames, which the
    model dances at ``music.fps``: the same span of time."""
    start, stop, step = frames.indices(motion.num_frames)
    if step != 1 or not 0 <= start < stop:
        raise ParameterError(f"frames {start}:{stop} are not a range of the dance's frames 0..{motion.num_frames}")
    first, last = (int(np.floor(start * music.fps / motion.fps + 1e-9)),
                   int(np.ceil(stop * music.fps / motion.fps - 1e-9)))
    if first >= music.num_frames:
        raise ParameterError(f"frames {start}:{stop} ({start / motion.fps:.2f} s on) lie past the song's end "
                             f"({music.duration:.1f} s)")
    return slice(first, min(max(last, first + 1), music.num_frames))
