"""Atomic output: a file either appears complete or not at all.

Every writer in choreo goes through :func:`atomic_output`, so a crash, a bad input discovered halfway
or Ctrl-C never leaves a truncated BVH/NPZ behind for a batch script to pick up.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path
from typing import IO, Iterator

from .errors import OutputError

STDOUT = "-"


def check_output_dir(path: str | os.PathLike) -> Path:
    """Fail early, with one line, if ``path`` cannot be created; returns it as a Path."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"cannot write {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise OutputError(f"cannot write {path}: folder {folder} is not writable")
    return path


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, binary: bool = True) -> Iterator[IO]:
    """Yield a file handle whose content replaces ``path`` only if the block succeeds.

    ``path == "-"`` writes to stdout instead (buffered, so a failure still writes nothing).
    """
    if str(path) == STDOUT:
        import io

        buffer = io.BytesIO() if binary else io.StringIO()
        yield buffer
        stream = sys.stdout.buffer if binary else sys.stdout
        stream.write(buffer.getvalue())
        stream.flush()
        return

    with atomic_path(path) as temporary:
        with open(temporary, "wb" if binary else "w", encoding=None if binary else "utf-8") as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())


def output_target(path: str | os.PathLike) -> Path:
    """The regular file an output to ``path`` replaces: ``path`` itself, or the file a symlink at
    ``path`` points to (written through, so the link stays). Anything else that exists there (a
    folder, a FIFO, a device such as /dev/null) is refused: replacing it would destroy it."""
    path = check_output_dir(path)
    try:
        return _regular_file_at(path)
    except OSError as error:  # a name too long for the file system, say
        raise OutputError(f"cannot write {path}: {error.strerror}") from None


def _regular_file_at(path: Path) -> Path:
    if os.path.islink(path):
        resolved = Path(os.path.realpath(path))
        if resolved.is_file():
            return check_output_dir(resolved)
        raise OutputError(f"cannot write {path}: it is a link to something that is not a regular file")
    if path.exists() and not path.is_file():
        kind = "a folder" if path.is_dir() else "not a regular file"
        raise OutputError(f"cannot write {path}: it exists and is {kind}")
    return path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same extension, for tools that infer the format from
    it, like ffmpeg); it replaces ``path`` only if the block succeeds. OS errors on the way (a name
    too long, a full disk) are output errors (exit 3)."""
    target = output_target(path)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{target.stem[:100]}.", suffix=f".tmp{target.suffix[:20]}",
                                        dir=target.parent or ".")
    except OSError as error:
        raise OutputError(f"cannot write {path}: {error.strerror}") from None
    os.close(fd)
    try:
        yield Path(tmp_name)
        os.chmod(tmp_name, 0o644)
        try:
            os.replace(tmp_name, target)
        except OSError as error:
            raise OutputError(f"cannot write {path}: {error.strerror}") from None
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp_name)
        raise
