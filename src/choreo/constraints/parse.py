"""User-level constraint syntax: frame ranges, joint sets, poses taken from files, floor paths."""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np

from ..errors import InputError, ParameterError
from ..numbers import decimal, shown
from ..motion import Motion
from ..skeleton import JOINT_NAMES, LOWER_BODY_JOINTS, UPPER_BODY_JOINTS

JOINT_SETS = {"all": tuple(range(24)), "upper": UPPER_BODY_JOINTS, "lower": LOWER_BODY_JOINTS}
PATH_SUFFIXES = (".csv", ".txt")
MAX_PATH_VALUE = 1e4
MAX_KEY_SECONDS = 24 * 3600.0  # longer than any song, and seconds x fps stays a frame number
MAX_PATH_BYTES = 32 << 20  # about two million rows: a point a millisecond for half an hour


def parse_frame_range(text: str, num_frames: int) -> slice:
    """'60:120', '60:', ':90' (frames, end exclusive) -> a slice inside 0..num_frames."""
    parts = text.split(":")
    if len(parts) != 2:
        raise ParameterError(f"frame range {text!r} must look like START:END (e.g. 60:120)")
    try:
        start = int(parts[0]) if parts[0].strip() else 0
        stop = int(parts[1]) if parts[1].strip() else num_frames
    except ValueError:
        raise ParameterError(f"frame range {text!r} must hold whole frame numbers") from None
    if not 0 <= start < stop <= num_frames:
        raise ParameterError(f"frame range {text!r} is outside the dance's frames 0..{num_frames}")
    return slice(start, stop)


def parse_joints(text: str) -> tuple[int, ...]:
    """'upper', 'lower', 'all', or a comma list of SMPL joint names or indices."""
    key = text.strip().lower()
    if key in JOINT_SETS:
        return JOINT_SETS[key]
    joints = []
    for item in key.split(","):
        item = item.strip()
        if item.isascii() and item.isdigit() and int(item) < len(JOINT_NAMES):  # '²'.isdigit() is true too
            joints.append(int(item))
        elif item in JOINT_NAMES:
            joints.append(JOINT_NAMES.index(item))
        else:
            raise ParameterError(f"unknown joint {item!r} (use upper, lower, all, or names like {JOINT_NAMES[18]})")
    return tuple(sorted(set(joints)))


SCHEDULE_ENTRY = re.compile(r"^\s*([0-9.]*)\s*:\s*([0-9.]*)\s*=\s*(.+?)\s*$")


def parse_style_schedule(text: str, duration: float) -> list[tuple[float, float | None, str]] | None:
    """'0:30=waltz,30:=cha-cha' -> [(0, 30, 'waltz'), (30, None, 'cha-cha')] (seconds); None if
    ``text`` is a plain style (no 'START:END=' entries). Ranges must not overlap."""
    matches = [SCHEDULE_ENTRY.match(part) for part in text.split(",")]
    if not any(matches):
        return None
    if not all(matches):
        raise ParameterError(f"style schedule {text!r}: every entry must look like START:END=STYLE (seconds)")
    schedule = []
    for match in matches:
        try:
            start = float(match[1]) if match[1] else 0.0
            stop = float(match[2]) if match[2] else None
        except ValueError:
            raise ParameterError(f"style schedule {text!r}: times must be seconds") from None
        if stop is not None and stop <= start:
            raise ParameterError(f"style schedule {text!r}: {start:g}:{stop:g} is empty")
        if start >= duration:
            raise ParameterError(f"style schedule {text!r}: {start:g} s is past the song's end ({duration:.1f} s)")
        schedule.append((start, stop, match[3]))
    schedule.sort(key=lambda entry: entry[0])
    for (_, stop, _), (start, _, _) in zip(schedule, schedule[1:]):
        if stop is None or stop > start:
            raise ParameterError(f"style schedule {text!r}: time ranges overlap")
    return schedule


def parse_time_key(text: str) -> tuple[float, str]:
    """'4.0=pose.bvh' -> (4.0, 'pose.bvh')."""
    time, _, source = text.partition("=")
    seconds = decimal(time)
    if not source or seconds is None or seconds < 0:
        raise ParameterError(f"--key {shown(text)} must look like SECONDS=FILE (e.g. 4.0=pose.bvh)")
    if seconds > MAX_KEY_SECONDS:  # 1e308 s overflowed to an infinite frame (exit 70)
        raise ParameterError(f"--key {shown(text)}: {seconds:g} s is past any song's end")
    return seconds, source


def pose_file(spec: str) -> tuple[str, int]:
    """'dance.npz@42' -> ('dance.npz', 42); 'pose.bvh' -> ('pose.bvh', 0)."""
    if "@" not in spec or Path(spec).is_file():  # a file may have @ in its own path
        return spec, 0
    path, _, index = spec.rpartition("@")
    try:
        return path, int(index)
    except ValueError:
        raise ParameterError(f"pose {spec!r}: the part after @ must be a frame number") from None


def read_pose(spec: str) -> Motion:
    """One frame of a motion file: 'pose.bvh' (its first frame) or 'dance.npz@42' / 'dance.bvh@-1'."""
    from ..formats import read_motion

    path, frame = pose_file(spec)
    motion = read_motion(path)
    if not -motion.num_frames <= frame < motion.num_frames:
        raise ParameterError(f"pose {spec!r}: {Path(path).name} has {motion.num_frames} frames")
    frame %= motion.num_frames
    return motion.slice_frames(frame, frame + 1)


def read_root_path(path: str | Path) -> tuple[np.ndarray | None, np.ndarray, np.ndarray | None]:
    """(times or None, (N, 2) x-z points, heights or None) from a CSV path or any motion file.

    CSV: a header naming columns among t (or time), x, y, z, or no header and 2 columns (x, z) or
    3 columns (t, x, z). Metres; y is the root's height above the floor. A motion file gives its
    root's own path with its frame times.
    """
    path = Path(path)
    if path.suffix.lower() not in PATH_SUFFIXES:
        from ..formats import read_motion

        motion = read_motion(path)
        root = motion.root_positions
        return np.arange(motion.num_frames) / motion.fps, root[:, [0, 2]], root[:, 1]
    if not path.is_file():
        raise InputError(f"path file {path} does not exist")
    if path.stat().st_size > MAX_PATH_BYTES:
        raise InputError(f"path file {path} is larger than {MAX_PATH_BYTES >> 20} MiB: thin it out (a point per frame is plenty)")
    rows = [row for row in csv.reader(io.StringIO(path.read_text(errors="replace"))) if any(c.strip() for c in row)]
    if not rows:
        raise InputError(f"path file {path} is empty")
    header = [c.strip().lower() for c in rows[0]]
    if all(_is_number(c) for c in header):
        columns = {2: ("x", "z"), 3: ("t", "x", "z")}.get(len(header))
        if columns is None:
            raise InputError(f"{path}: without a header a path has 2 columns (x, z) or 3 (t, x, z), not {len(header)}")
        body = rows
    else:
        columns = tuple("t" if c == "time" else c for c in header)
        if "x" not in columns or "z" not in columns or not set(columns) <= {"t", "x", "y", "z"}:
            raise InputError(f"{path}: header must name x and z (and optionally t, y), got {ascii(', '.join(header))[:80]}")
        body = rows[1:]
    try:
        values = np.array([[float(c) for c in row] for row in body], dtype=np.float64)
    except ValueError:
        raise InputError(f"{path}: every value must be a number") from None
    if values.ndim != 2 or values.shape[1] != len(columns):
        raise InputError(f"{path}: every row needs {len(columns)} values")
    if len(values) < 2:
        raise InputError(f"{path}: a path needs at least two points")
    if not np.isfinite(values).all():
        raise InputError(f"{path}: path values must be finite numbers")
    if np.abs(values).max() > MAX_PATH_VALUE:
        raise InputError(f"{path}: path values beyond {MAX_PATH_VALUE:g} (metres or seconds) are not a dance floor")
    column = {name: values[:, i] for i, name in enumerate(columns)}
    times = column.get("t")
    if times is not None and not (np.diff(times) > 0).all():
        raise InputError(f"{path}: times must increase")
    return times, np.stack([column["x"], column["z"]], axis=1), column.get("y")


def path_to_frames(times: np.ndarray | None, xz: np.ndarray, heights: np.ndarray | None,
                   num_frames: int) -> tuple[np.ndarray, np.ndarray | None]:
    """Stretch a path over a dance of ``num_frames``: its first point on frame 0, its last on the last."""
    if len(xz) < 2:
        raise InputError("a path needs at least two points")
    progress = np.linspace(0, 1, len(xz)) if times is None else (times - times[0]) / (times[-1] - times[0])
    frames = np.linspace(0, 1, num_frames)
    resampled = np.stack([np.interp(frames, progress, xz[:, axis]) for axis in range(2)], axis=1)
    return resampled, None if heights is None else np.interp(frames, progress, heights)


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False
