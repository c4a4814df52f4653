"""Child processes (ffmpeg, Blender) that never outlive choreo.

Ctrl-C reaches a child through the terminal, but SIGTERM, a failed write or a bug reach only
choreo: whatever ends the block, the child is killed and reaped before the exception goes on, so
no encoder keeps a temporary file open and no Blender keeps running after choreo has exited.
"""

from __future__ import annotations

import contextlib
import subprocess
from typing import Iterator


@contextlib.contextmanager
def child_process(command: list[str], **popen) -> Iterator[subprocess.Popen]:
    """``subprocess.Popen(command, **popen)`` for the block; it is killed unless the block ends
    normally, and waited for in every case. Its pipes are closed on the way out."""
    process = subprocess.Popen(command, **popen)
    try:
        yield process
    except BaseException:
        process.kill()
        raise
    finally:
        for stream in (process.stdin, process.stdout, process.stderr):
            if stream is not None:
                with contextlib.suppress(OSError):  # a broken pipe to a child that has died
                    stream.close()
        process.wait()
