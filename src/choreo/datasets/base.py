"""What every dataset reader yields: whole clips, then fixed-length windows over them.

Readers (M2D, AIST++, BVH folders) only know their file layout; they return :class:`Clip` objects
with the motion at 30 fps on SMPL-24 and the music features cut to the same frames. Windowing,
caching and splitting are shared here so every dataset behaves the same for training and eval.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterator, Sequence

import numpy as np

from ..errors import ParameterError
from ..motion import Motion

TRAIN, TEST = "train", "test"


@dataclass
class Clip:
    """One performance: motion and the music it was danced to, frame for frame at the same fps."""

    name: str
    motion: Motion
    features: np.ndarray | None  # (T, 35) float32 music features, or None when there is no audio
    genre: str | None = None
    split: str | None = None  # "train", "test" or None when the dataset has no split
    audio_path: str | None = None
    audio_offset: float = 0.0  # seconds into the audio file at which motion frame 0 happens
    info: dict = field(default_factory=dict)  # reader-specific facts (fit error, source fps...)

    def __post_init__(self):
        if self.features is not None and len(self.features) != self.motion.num_frames:
            raise ParameterError(
                f"clip {self.name}: {len(self.features)} music frames for {self.motion.num_frames} motion frames"
            )


@dataclass(frozen=True, kw_only=True)
class WindowConfig:
    seconds: float = 5.0  # window length (EDGE and SGMD train and score 5 s windows)
    stride_seconds: float = 0.5  # hop between window starts; 2.5 s for evaluation
    fps: float = 30.0
    drop_last: bool = True  # a shorter final window is dropped, not padded

    @property
    def length(self) -> int:
        return int(round(self.seconds * self.fps))

    @property
    def stride(self) -> int:
        return max(1, int(round(self.stride_seconds * self.fps)))


@dataclass
class Window:
    """A fixed-length excerpt of a clip, ready to batch."""

    clip: str
    start_frame: int
    motion: Motion
    features: np.ndarray | None
    genre: str | None


def window_starts(num_frames: int, config: WindowConfig) -> list[int]:
    """Start frames of every full window (and a last short one when drop_last is False)."""
    if num_frames < config.length:
        return [] if config.drop_last else [0]
    starts = list(range(0, num_frames - config.length + 1, config.stride))
    if not config.drop_last and starts[-1] + config.length < num_frames:
        starts.append(starts[-1] + config.stride)
    return starts


class WindowedDataset(Sequence[Window]):
    """Random access to every window of a list of clips (a torch Dataset needs only this)."""

    def __init__(self, clips: Sequence[Clip], config: WindowConfig = WindowConfig()):
        for clip in clips:
            if not np.isclose(clip.motion.fps, config.fps):
                raise ParameterError(f"clip {clip.name} is at {clip.motion.fps} fps, windows expect {config.fps}")
        self.clips = list(clips)
        self.config = config
        self.index = [(c, s) for c, clip in enumerate(self.clips) for s in window_starts(clip.motion.num_frames, config)]

    def __len__(self) -> int:
        return len(self.index)

    def __getitem__(self, i: int) -> Window:
        clip_index, start = self.index[i]
        clip = self.clips[clip_index]
        stop = start + self.config.length
        features = None if clip.features is None else clip.features[start:stop]
        return Window(clip.name, start, clip.motion.slice_frames(start, stop), features, clip.genre)

    def __iter__(self) -> Iterator[Window]:
        return (self[i] for i in range(len(self)))


def select_split(clips: Sequence[Clip], split: str | None) -> list[Clip]:
    """Clips of one split ("train"/"test"), or all of them for None / "all"."""
    if split in (None, "all"):
        return list(clips)
    if split not in (TRAIN, TEST):
        raise ParameterError(f"unknown split {split!r}: use train, test or all")
    return [c for c in clips if c.split == split]


ProgressCallback = Callable[[int, int, str], None]  # (done, total, current item name)
