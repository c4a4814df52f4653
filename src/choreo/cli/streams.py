"""Standard streams a user closed or filled (`>&-`, `2>&-`, `> /dev/full`).

A closed descriptor's number goes to the next file the process opens: with stderr closed, a
song's audio file became descriptor 2, and progress written to "stderr" landed in it (decoding
then failed). So each closed one of 0, 1 and 2 is opened on /dev/null first. Output lost this
way is the user's to know: writing to a stdout that was closed or that fails (a full disk, a
closed pipe) is an :class:`~choreo.errors.OutputError` (exit 3, one line); a closed or full
stderr just takes the messages away.
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Iterator

from ..errors import OutputError


class GuardedOutput:
    """sys.stdout (text, or its binary ``buffer``) whose failures are output errors. ``stream`` None:
    the user closed stdout, and any write is one."""

    def __init__(self, stream):
        self.stream = stream

    def write(self, data) -> int:
        return self._guarded(lambda: self.stream.write(data))

    def flush(self) -> None:
        if self.stream is not None:
            self._guarded(self.stream.flush)

    @property
    def buffer(self) -> "GuardedOutput":
        return GuardedOutput(getattr(self.stream, "buffer", None)) if self.stream is not None else self

    def isatty(self) -> bool:
        return self.stream is not None and self.stream.isatty()

    def __getattr__(self, name):  # encoding, fileno, ...: the stream's own
        if self.stream is None:
            raise AttributeError(name)
        return getattr(self.stream, name)

    def _guarded(self, call):
        if self.stream is None:
            raise OutputError("cannot write to standard output: it is closed")
        try:
            return call()
        except OSError as error:
            _silence_stdout()  # what is still buffered goes nowhere at exit, instead of failing again
            raise OutputError(f"cannot write to standard output: {error.strerror or type(error).__name__}") from None


class ForgivingErrors:
    """sys.stderr that a full or failing stream cannot fail: messages then go nowhere, as with a
    closed stderr, and the command keeps its own exit code."""

    def __init__(self, stream):
        self.stream = stream

    def write(self, data) -> int:
        try:
            return self.stream.write(data)
        except OSError:
            _silence(2)
            return len(data)

    def flush(self) -> None:
        try:
            self.stream.flush()
        except OSError:
            _silence(2)

    def __getattr__(self, name):  # encoding, fileno, isatty, ...: the stream's own
        return getattr(self.stream, name)


@contextlib.contextmanager
def standard_streams() -> Iterator[None]:
    """For the block: closed descriptors 0-2 opened on /dev/null, so no file choreo opens takes
    their number; sys.stdout guarded (:class:`GuardedOutput`); a closed stderr a sink."""
    closed = [fd for fd in (0, 1, 2) if not _is_open(fd)]
    for fd in closed:
        null = os.open(os.devnull, os.O_RDWR)
        if null != fd:
            os.dup2(null, fd)
            os.close(null)
    before = sys.stdin, sys.stdout, sys.stderr
    if 0 in closed or sys.stdin is None:  # Python leaves a closed stdin None: read it as the empty /dev/null
        sys.stdin = open(0, closefd=False)
    sys.stdout = GuardedOutput(None if 1 in closed or sys.stdout is None else sys.stdout)
    if 2 in closed or sys.stderr is None:
        sys.stderr = open(2, "w", closefd=False, errors="backslashreplace")
    sys.stderr = ForgivingErrors(sys.stderr)
    try:
        yield
    finally:
        sys.stdin, sys.stdout, sys.stderr = before


def _silence_stdout() -> None:
    _silence(1)


def _silence(fd: int) -> None:
    """Point ``fd`` at /dev/null: what is still buffered for it goes nowhere instead of failing again."""
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, fd)
    os.close(null)


def _is_open(fd: int) -> bool:
    try:
        os.fstat(fd)
    except OSError:
        return False
    return True
