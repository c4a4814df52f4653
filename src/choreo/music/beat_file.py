"""Beat times a user gives in a file (``choreo generate --beats FILE``).

Why: the tracker (choreo.music.beats) is licence-clean and right on most songs, but a producer
who has the beat grid in a DAW, or another tracker's output, knows better on the songs it gets
wrong. Two layouts are read, the ones DAWs and beat trackers export:

- one time in seconds a line;
- a CSV (comma, tab, semicolon or space separated) with a header, time first and an optional
  second column that marks downbeats: ``1`` is a downbeat, as in a 0/1 flag (``beat_time,downbeat``)
  or a beat's number in its bar (``time,beat``: 1 2 3 4 1 ...); ``true``/``false`` also read.

Anything else is refused in one line naming the file and the line: a file with no beats,
a cell that is not a number, negative or unsorted times, and beats closer than 0.2 s or further
apart than 3 s (faster than 300 or slower than 20 bpm: not beats a dance can follow).

Size is checked before reading (a 10-hour song at 300 bpm is about 2 MB of beats) and the file is
parsed as a stream, a line at a time into flat arrays: memory stays at a few bytes per beat
whatever the file holds.
"""

from __future__ import annotations

import itertools
import os
import re
from array import array
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator, TextIO

import numpy as np

from ..errors import InputError
from ..numbers import decimal, shown

MIN_INTERVAL, MAX_INTERVAL = 0.2, 3.0  # seconds between beats: 300 and 20 bpm
FLAGS = {"true": 1.0, "false": 0.0, "yes": 1.0, "no": 0.0}
MAX_FILE_BYTES = 8 << 20  # four times a 10-hour song's beats at 300 bpm, with a downbeat column
MAX_BEATS = 360_000  # 20 hours at 300 bpm
MAX_LINE_CHARS = 256  # a time and a downbeat cell, quoted and padded; a longer line is no beat


@dataclass(frozen=True, eq=False)
class BeatFile:
    """The beats of a file: times in seconds (increasing) and, when the file marks them, downbeats."""

    name: str  # the file's name, without its folder (it goes into a dance's metadata)
    times: np.ndarray  # (B,) seconds
    downbeats: np.ndarray | None = None  # (B,) bool, or None when the file has one column


def read_beat_file(path: str | os.PathLike) -> BeatFile:
    """The beats in ``path``, checked (see the module docstring); InputError in one line if not."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such beats file")
    if not path.is_file():
        raise InputError(f"{path} is not a file, expected a beats file")
    try:
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise InputError(f"{path}: {size:,} bytes, more than a beats file holds (choreo reads up to "
                             f"{MAX_FILE_BYTES:,}; a 10-hour song at 300 bpm takes about 2 MB)")
        with open(path, encoding="utf-8-sig") as handle:
            return parse_beats(_bounded_lines(handle, path.name), path.name)
    except (OSError, UnicodeDecodeError) as error:
        raise InputError(f"{path}: cannot read the beats file ({error.__class__.__name__})") from None


def _bounded_lines(handle: TextIO, name: str) -> Iterator[str]:
    """The file's lines, each at most MAX_LINE_CHARS and all together at most MAX_FILE_BYTES (the
    file may have grown since it was measured)."""
    read = 0
    for number in itertools.count(1):
        line = handle.readline(MAX_LINE_CHARS + 1)
        if not line:
            return
        read += len(line)
        if len(line) > MAX_LINE_CHARS:
            raise InputError(f"{name} line {number}: longer than {MAX_LINE_CHARS} characters (not a beat)")
        if read > MAX_FILE_BYTES:
            raise InputError(f"{name}: more than {MAX_FILE_BYTES:,} characters (more than a beats file holds)")
        yield line


def parse_beats(text: str | Iterable[str], name: str) -> BeatFile:
    """The beats in a file's ``text``, or its lines one at a time (``name`` is for messages)."""
    times, flags, lines = array("d"), array("d"), array("q")
    width = None
    for line, cells in _rows(text.splitlines() if isinstance(text, str) else text):
        if width is None and not lines and _is_header(cells):
            width = 0  # the header: only ever the first line
            continue
        if len(cells) > 2 or width not in (None, 0, len(cells)):
            raise InputError(f"{name}: expected one column of times, or two (time, downbeat) on every line")
        if len(lines) == MAX_BEATS:
            raise InputError(f"{name}: more than {MAX_BEATS:,} beats (20 hours at 300 bpm)")
        width = len(cells)
        times.append(_number(cells[0], name, line))
        if width == 2:
            flags.append(_number(cells[1], name, line, flag=True))
        lines.append(line)
    if not lines:
        raise InputError(f"{name} has no beats")
    if len(lines) < 2:  # one beat has no tempo: `info` said "tempo 0.0 bpm"
        raise InputError(f"{name} has one beat; give at least two (a tempo needs an interval)")
    times = np.frombuffer(times, dtype=np.float64).copy()
    check_beat_times(times, name, lines)
    return BeatFile(name, times, np.frombuffer(flags, dtype=np.float64) == 1 if width == 2 else None)


def check_beat_times(times: np.ndarray, name: str, lines: list[int] | None = None) -> None:
    """Refuse negative or unsorted times and spacing outside [MIN_INTERVAL, MAX_INTERVAL]."""
    line = lambda i: f"line {lines[i]}" if lines else f"beat {i + 1}"  # noqa: E731
    negative = np.flatnonzero(times < 0)
    if len(negative):
        raise InputError(f"{name} {line(negative[0])}: negative beat time {times[negative[0]]:g} s")
    gaps = np.diff(times)
    unsorted = np.flatnonzero(gaps <= 0)
    if len(unsorted):
        i = unsorted[0] + 1
        raise InputError(f"{name} {line(i)}: beat times must increase ({times[i]:g} s after {times[i - 1]:g} s)")
    odd = np.flatnonzero((gaps < MIN_INTERVAL) | (gaps > MAX_INTERVAL))
    if len(odd):
        i = odd[0] + 1
        raise InputError(f"{name} {line(i)}: beats {gaps[i - 1]:.3g} s apart; beats must be {MIN_INTERVAL:g} to "
                         f"{MAX_INTERVAL:g} s apart (20 to 300 bpm)")


def _rows(lines: Iterable[str]) -> Iterator[tuple[int, list[str]]]:
    """(line number, cells) of every non-blank line, as the lines come."""
    for number, line in enumerate(lines, start=1):
        cells = [cell.strip('"') for cell in re.split(r"\s*[,;\t]\s*|\s+", line.strip())]
        while cells and not cells[-1]:  # a trailing separator, as some exports write
            cells.pop()
        if cells:
            yield number, cells


def _is_header(cells: list[str]) -> bool:
    """A first line whose time cell is a word (``time``, ``beat_time``...), not a number. Words
    Python reads as numbers (``nan``, ``inf``) are cells, refused as such, not a header skipped."""
    if not re.fullmatch(r"[A-Za-z_][\w ()\[\].-]*", cells[0]):
        return False
    try:
        float(cells[0])
        return False
    except ValueError:
        return True


def _number(cell: str, name: str, line: int, flag: bool = False) -> float:
    """The cell's value, a plain decimal (:func:`choreo.numbers.decimal`: not ``0_5``, fullwidth
    digits or ``nan``); a downbeat cell (``flag``) may also be true/false or yes/no."""
    value = FLAGS[cell.lower()] if flag and cell.lower() in FLAGS else decimal(cell)
    if value is None:
        raise InputError(f"{name} line {line}: {shown(cell)} is not a number")
    return value
