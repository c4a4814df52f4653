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
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

MIN_INTERVAL, MAX_INTERVAL = 0.2, 3.0  # seconds between beats: 300 and 20 bpm
FLAGS = {"true": 1.0, "false": 0.0, "yes": 1.0, "no": 0.0}


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
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as error:
        raise InputError(f"{path}: cannot read the beats file ({error.__class__.__name__})") from None
    return parse_beats(text, path.name)


def parse_beats(text: str, name: str) -> BeatFile:
    """The beats in a file's ``text`` (``name`` is for messages)."""
    rows = _rows(text)
    if rows and _is_header(rows[0][1]):
        rows = rows[1:]
    if not rows:
        raise InputError(f"{name} has no beats")
    widths = {len(cells) for _, cells in rows}
    if max(widths) > 2 or len(widths) > 1:
        raise InputError(f"{name}: expected one column of times, or two (time, downbeat) on every line")
    values = np.array([[_number(cell, name, line, flag=column == 1) for column, cell in enumerate(cells)]
                       for line, cells in rows])
    times = values[:, 0]
    check_beat_times(times, name, [line for line, _ in rows])
    return BeatFile(name, times, values[:, 1] == 1 if values.shape[1] == 2 else None)


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


def _rows(text: str) -> list[tuple[int, list[str]]]:
    """(line number, cells) of every non-blank line."""
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        cells = [cell.strip('"') for cell in re.split(r"\s*[,;\t]\s*|\s+", line.strip())]
        while cells and not cells[-1]:  # a trailing separator, as some exports write
            cells.pop()
        if cells:
            rows.append((number, cells))
    return rows


def _is_header(cells: list[str]) -> bool:
    """A first line whose time cell is a word (``time``, ``beat_time``...), not a number."""
    return bool(re.fullmatch(r"[A-Za-z_][\w ()\[\].-]*", cells[0]))


def _number(cell: str, name: str, line: int, flag: bool = False) -> float:
    """The cell's value; a downbeat cell (``flag``) may also be true/false or yes/no."""
    try:
        value = FLAGS[cell.lower()] if flag and cell.lower() in FLAGS else float(cell)
    except ValueError:
        raise InputError(f"{name} line {line}: {cell!r} is not a number") from None
    if not np.isfinite(value):
        raise InputError(f"{name} line {line}: {cell!r} is not a number")
    return value
