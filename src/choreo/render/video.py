"""Turning a motion into a preview: MP4 with the music muxed in (ffmpeg), GIF, or a PNG strip."""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import stat
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

import numpy as np
from PIL import Image

from ..children import child_process
from ..errors import InputError, OutputError, ParameterError
from ..fileio import OUT_OF_SPACE, atomic_path
from ..motion import Motion
from .camera import CameraConfig, FollowCamera
from .figure import render_frame

VIDEO_SUFFIXES = {".mp4", ".mov", ".mkv", ".webm"}
GIF_MAX_FPS = 15.0  # GIF frame delays are in hundredths of a second; more frames only bloat the file


# Frames are drawn whole in memory: 8K a side at most (100,000 x 100,000 asked for 30 GB before the
# first frame was drawn), and a PNG strip of at most 64 of them side by side.
MIN_SIDE, MAX_SIDE, MAX_STRIP = 16, 7680, 64


@dataclass(frozen=True, kw_only=True)
class RenderConfig:
    width: int = 640
    height: int = 480
    fps: float | None = None  # default: the motion's (GIF: at most GIF_MAX_FPS)
    strip_frames: int = 6  # PNG: this many moments side by side (1: the middle frame alone)
    camera: CameraConfig = CameraConfig()

    def __post_init__(self):
        if not (MIN_SIDE <= self.width <= MAX_SIDE and MIN_SIDE <= self.height <= MAX_SIDE):
            raise ParameterError(f"frame size {str(self.width)[:12]}x{str(self.height)[:12]}: each side must be "
                                 f"{MIN_SIDE} to {MAX_SIDE} pixels")
        if not 1 <= self.strip_frames <= MAX_STRIP:
            raise ParameterError(f"a strip must have 1 to {MAX_STRIP} moments, got {str(self.strip_frames)[:12]}")


def frames_of(motion: Motion, config: RenderConfig, indices: np.ndarray | None = None,
              progress: Callable[[int, int], None] | None = None) -> Iterator[np.ndarray]:
    positions = motion.joint_positions()
    camera = FollowCamera(motion.root_positions, motion.fps, config.width, config.height, config.camera)
    indices = np.arange(motion.num_frames) if indices is None else indices
    for count, frame in enumerate(indices):
        yield render_frame(positions[frame], camera, int(frame), caption=f"{frame / motion.fps:6.2f} s")
        if progress:
            progress(count + 1, len(indices))


def ffmpeg_executable() -> str:
    try:
        import imageio_ffmpeg
    except ImportError:
        raise OutputError("video previews need the imageio-ffmpeg package (pip install imageio-ffmpeg)") from None
    return imageio_ffmpeg.get_ffmpeg_exe()


def write_video(motion: Motion, file: Path, name: str, config: RenderConfig, music: str | None = None,
                progress=None) -> None:
    """Pipe the frames to ffmpeg, which writes ``file``, with ``music`` (an :func:`ffmpeg_input`)
    muxed in; ``name`` is the output's name in messages. ffmpeg's messages go to a file, not a pipe,
    so neither side can wait on the other; an interrupt kills it. A full disk is the OSError it
    would have been had choreo written the file itself."""
    fps = config.fps or motion.fps
    if fps != motion.fps:
        motion = motion.resample(fps)
    width, height = config.width // 2 * 2, config.height // 2 * 2  # H.264 wants even sizes
    config = RenderConfig(width=width, height=height, fps=fps, strip_frames=config.strip_frames, camera=config.camera)
    with tempfile.TemporaryFile() as log:
        command = [ffmpeg_executable(), "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
                   "-s", f"{width}x{height}", "-r", f"{fps:g}", "-i", "pipe:0"]
        if music is not None:
            command += ["-i", music, "-map", "0:v:0", "-map", "1:a:0", "-c:a", "aac", "-b:a", "160k", "-shortest"]
        command += ["-c:v", "libx264", "-preset", "veryfast", "-crf", "20", "-pix_fmt", "yuv420p", str(file)]
        with child_process(command, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=log) as encoder:
            with contextlib.suppress(BrokenPipeError):  # ffmpeg stopped early: its exit code and log say why
                for image in frames_of(motion, config, progress=progress):
                    encoder.stdin.write(image.tobytes())
                encoder.stdin.close()
        if encoder.returncode != 0:
            said = _last_line(log)
            if encoder.returncode == -signal.SIGXFSZ:  # past `ulimit -f`: the kernel's signal, not a message
                said = os.strerror(errno.EFBIG)
            for number in OUT_OF_SPACE:
                if os.strerror(number) in said:
                    raise OSError(number, os.strerror(number))
            raise OutputError(f"ffmpeg could not write {name}: {said or encoder.returncode}")


def _last_line(log) -> str:
    log.seek(0)
    lines = log.read().decode(errors="replace").strip().splitlines()
    return lines[-1] if lines else ""


def ffmpeg_input(path: str | os.PathLike) -> str:
    """``path`` as ffmpeg must be given it: ``file:`` and an absolute path, so that a name such as
    ``concat:a.wav|b.wav`` or ``http:/host/x`` is read as the file it names, never as a protocol;
    and only a regular file, the one choreo checked (a FIFO or a device is refused)."""
    try:
        info = os.stat(path)
    except OSError as error:
        raise InputError(f"cannot read the music {path}: {error.strerror}") from None
    if not stat.S_ISREG(info.st_mode):
        raise InputError(f"cannot read the music {path}: it is not a regular file")
    return "file:" + os.path.abspath(path)


def write_gif(motion: Motion, file: Path, config: RenderConfig, progress=None) -> None:
    fps = min(config.fps or motion.fps, GIF_MAX_FPS)
    motion = motion.resample(fps) if fps != motion.fps else motion
    images = [Image.fromarray(frame).quantize(colors=96, dither=Image.Dither.NONE)
              for frame in frames_of(motion, config, progress=progress)]
    images[0].save(file, format="GIF", save_all=True, append_images=images[1:], duration=round(1000 / fps),
                   loop=0, optimize=True)


def write_strip(motion: Motion, file: Path, config: RenderConfig, progress=None) -> None:
    count = max(1, min(config.strip_frames, motion.num_frames))
    indices = (np.array([motion.num_frames // 2]) if count == 1
               else np.linspace(0, motion.num_frames - 1, count).round().astype(int))
    strip = np.concatenate(list(frames_of(motion, config, indices, progress)), axis=1)
    Image.fromarray(strip).save(file, format="PNG", optimize=True)


def render_motion(motion: Motion, path: str | Path, config: RenderConfig = RenderConfig(), music: str | Path | None = None,
                  progress: Callable[[int, int], None] | None = None, into: Path | None = None) -> Path:
    """Write a preview of ``motion`` to ``path``, atomically; the kind follows the extension
    (.mp4/.mov/.mkv/.webm, .gif, .png). ``into``: write that temporary instead, which a caller
    writing several outputs all or none (choreo.formats.write_motions) moves into place; messages
    still name ``path``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if config.width < 16 or config.height < 16:
        raise ParameterError("preview size must be at least 16x16 pixels")
    if suffix not in (*VIDEO_SUFFIXES, ".gif", ".png"):
        raise OutputError(f"cannot render to {path.name}: use .mp4, .mov, .mkv, .webm, .gif or .png")
    with contextlib.nullcontext(into) if into is not None else atomic_path(path) as file:
        if suffix in VIDEO_SUFFIXES:
            write_video(motion, file, path.name, config, None if music is None else ffmpeg_input(music), progress)
        elif suffix == ".gif":
            write_gif(motion, file, config, progress)
        else:
            write_strip(motion, file, config, progress)
    return path
