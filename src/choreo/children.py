"""Child processes (ffmpeg, Blender) that never outlive choreo.

Ctrl-C reaches a child through the terminal, but SIGTERM, a failed write or a bug reach only
choreo: whatever ends the block, the child is killed and reaped before the exception goes on, so
no encoder keeps a temporary file open and no Blender keeps running after choreo has exited.
"""

from __future__ import annotations

import contextlib
import subprocess
from typing import Iterator


class _Start:
    """An interrupt that arrives while Popen is starting a child waits until the child is tracked:
    raised inside Popen, it would leave the child running, unknown to anyone (it then even wrote
    its output file after choreo had removed it)."""

    depth = 0
    deferred: BaseException | None = None


def starting_a_child() -> bool:
    return _Start.depth > 0


def defer_interrupt(error: BaseException) -> None:
    """Called by choreo's signal handler instead of raising ``error`` while a child is starting."""
    _Start.deferred = error


@contextlib.contextmanager
def _starting() -> Iterator[None]:
    _Start.depth += 1
    try:
        yield
    finally:
        _Start.depth -= 1
    if _Start.depth == 0 and _Start.deferred is not None:
        error, _Start.deferred = _Start.deferred, None
        raise error


@contextlib.contextmanager
def child_process(command: list[str], **popen) -> Iterator[subprocess.Popen]:
    """``subprocess.Popen(command, **popen)`` for the block; it is killed unless the block ends
    normally, and waited for in every case. Its pipes are closed on the way out."""
    process = None
    try:
        with _starting():
            process = subprocess.Popen(command, **popen)
        yield process
    except BaseException:
        if process is not None:
            process.kill()
        raise
    finally:
        if process is not None:
            for stream in (process.stdin, process.stdout, process.stderr):
                if stream is not None:
                    with contextlib.suppress(OSError):  # a broken pipe to a child that has died
                        stream.close()
            process.wait()
