"""Atomic output: a file either appears complete or not at all.

Every writer in choreo goes through :func:`atomic_output`, so a crash, a bad input discovered halfway
or Ctrl-C never leaves a truncated BVH/NPZ behind for a batch script to pick up.
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import secrets
import sys
from pathlib import Path
from typing import IO, Iterator

from .errors import InputError, OutputError

STDOUT = "-"
OUT_OF_SPACE = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG}  # a full disk, a quota, a file-size limit


def input_file(path: str | os.PathLike, what: str) -> Path:
    """``path`` when it is a file to read; else one line saying what is there instead (a folder
    given as a checkpoint or repertoire used to be reported as not existing)."""
    path = Path(path)
    if path.is_file():
        return path
    if path.is_dir():
        raise InputError(f"{what} {path} is a folder, expected a file")
    raise InputError(f"{what} {path} {'is not a regular file' if path.exists() else 'does not exist'}")


def check_output_dir(path: str | os.PathLike) -> Path:
    """Fail early, with one line, if ``path`` cannot be created; returns it as a Path."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"cannot write {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise OutputError(f"cannot write {path}: folder {folder} is not writable")
    return path


def check_outputs_apart(outputs: list[str | os.PathLike], inputs: list[str | os.PathLike]) -> None:
    """Refuse, before any work, an output that is also an input (the song, a motion or beat file:
    written over, the user's only copy would be lost) or two outputs that are one file. Files are
    compared by device and inode, so a link or another name for the same file counts; an output
    that does not exist yet is compared by the path it will have."""
    from .errors import ParameterError

    read = {_identity(path): path for path in inputs if path is not None and Path(path).exists()}
    written: dict[tuple, str | os.PathLike] = {}
    for path in outputs:
        if str(path) == STDOUT:
            continue
        identity = _identity(output_target(path))
        if identity in read:
            raise ParameterError(f"output {path} is also an input ({read[identity]}): it would be written over")
        if identity in written:
            raise ParameterError(f"outputs {written[identity]} and {path} are one file")
        written[identity] = path


def _identity(path: str | os.PathLike) -> tuple:
    """(device, inode) of a file that exists (links followed); else its absolute path, folders resolved."""
    try:
        status = os.stat(path)
        return status.st_dev, status.st_ino
    except OSError:
        path = Path(path)
        return (str(path.parent.resolve() / path.name),)


def check_output_folder(path: str | os.PathLike) -> Path:
    """Fail early, with one line, if ``path`` cannot be (made) a folder of outputs: something else is
    there, or the nearest folder that exists on the way to it is not writable. Creates nothing."""
    path = Path(path)
    for folder in (path, *path.absolute().parents):
        if folder.exists() or folder.is_symlink():
            if not folder.is_dir():
                raise OutputError(f"cannot write to {path}: {folder} exists and is not a folder")
            if not os.access(folder, os.W_OK):
                raise OutputError(f"cannot write to {path}: folder {folder} is not writable")
            break
    return path


def make_output_folder(path: str | os.PathLike) -> Path:
    """``path`` as a folder of outputs, created with its parents where missing (as ``mkdir -p``);
    one line (exit 3) where it cannot be."""
    path = check_output_folder(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OutputError(f"cannot write to {path}: {error.strerror}") from None
    return path


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, binary: bool = True, follow_links: bool = True) -> Iterator[IO]:
    """Yield a file handle whose content replaces ``path`` only if the block succeeds.

    ``path == "-"`` writes to stdout instead (buffered, so a failure still writes nothing).
    ``follow_links``: see :func:`output_target`.
    """
    if str(path) == STDOUT:
        import io

        buffer = io.BytesIO() if binary else io.StringIO()
        yield buffer
        stream = sys.stdout.buffer if binary else sys.stdout
        with out_of_space_is_an_output_error(path):
            stream.write(buffer.getvalue())
            stream.flush()
        return

    with atomic_path(path, follow_links) as temporary:
        with open(temporary, "wb" if binary else "w", encoding=None if binary else "utf-8") as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())


def output_target(path: str | os.PathLike, follow_links: bool = True) -> Path:
    """The regular file an output to ``path`` replaces: ``path`` itself, or the file a symlink at
    ``path`` leads to (written through, so the link stays) where the kernel's
    ``fs.protected_symlinks`` rule lets choreo follow it. Anything else that exists there (a
    folder, a FIFO, a device such as /dev/null) is refused: replacing it would destroy it.

    ``follow_links=False`` is for files no user names (choreo's cache): a link there was planted,
    so it is replaced itself and what it points to is never touched."""
    path = check_output_dir(path)
    try:
        if not follow_links and path.is_symlink():
            return path
        return _regular_file_at(path, _follow_links(path) if follow_links else path)
    except OSError as error:  # a name too long for the file system, say
        raise OutputError(f"cannot write {path}: {error.strerror}") from None


MAX_LINKS = 40  # the kernel's own limit on links followed in one path


def _follow_links(path: Path) -> Path:
    """Where the chain of symlinks at ``path`` ends, one link at a time, each checked by
    :func:`_check_link_may_be_followed`. Only the last name is read here: links among the folders
    above it are left to the kernel (``..`` in a link's target included), which resolves them
    when the file is written."""
    start = path
    for _ in range(MAX_LINKS):
        if not os.path.islink(path):
            return path
        _check_link_may_be_followed(path, start)
        target = Path(os.readlink(path))
        path = target if target.is_absolute() else path.parent / target
    raise OutputError(f"cannot write {start}: too many levels of symbolic links")


def _check_link_may_be_followed(link: Path, output: Path) -> None:
    """The kernel's ``fs.protected_symlinks`` rule, applied whatever the sysctl says: in a sticky
    world-writable folder (/tmp) a link is followed only if its owner is us or the folder's owner.
    Otherwise another user could plant a link there and have choreo replace a file of theirs."""
    folder = os.stat(link.parent if str(link.parent) else ".")
    shared = folder.st_mode & stat.S_ISVTX and folder.st_mode & stat.S_IWOTH
    owner = os.lstat(link).st_uid
    if shared and owner not in (os.geteuid(), folder.st_uid):
        raise OutputError(f"cannot write {output}: it is a link owned by another user in the shared folder "
                          f"{link.parent} (not followed, as the kernel's protected_symlinks rule says)")


def _regular_file_at(path: Path, end: Path) -> Path:
    """``end`` (where the links at ``path`` lead) if writing there replaces at most a regular file."""
    if end.exists() and not end.is_file():
        if end != path:
            raise OutputError(f"cannot write {path}: it is a link to something that is not a regular file")
        kind = "a folder" if path.is_dir() else "not a regular file"
        raise OutputError(f"cannot write {path}: it exists and is {kind}")
    return check_output_dir(end)


def output_mode(target: Path) -> int:
    """The permissions an output gets, as ``cp`` and editors give them: those of the file it
    replaces (a private 0600 file stays private), else the default for a new file under the umask."""
    try:
        status = os.lstat(target)  # a link still at ``target`` is replaced, not its file: the default
    except FileNotFoundError:
        status = None
    if status is None or stat.S_ISLNK(status.st_mode):
        return 0o666 & ~current_umask()
    return stat.S_IMODE(status.st_mode) & 0o777


def current_umask() -> int:
    """The process's umask, read without changing it where Linux tells it (another thread may be
    creating files), else by the usual set-and-restore."""
    with contextlib.suppress(OSError):
        with open("/proc/self/status", encoding="ascii", errors="replace") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, follow_links: bool = True) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same extension, for tools that infer the format from
    it, like ffmpeg); it replaces ``path`` only if the block succeeds. OS errors on the way (a name
    too long, a full disk) are output errors (exit 3). ``follow_links``: see :func:`output_target`."""
    target = output_target(path, follow_links)
    tmp_name = temporary_beside(target)  # named before it exists: a signal any time after leaves nothing
    try:
        try:
            os.close(os.open(tmp_name, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        except FileExistsError:  # another writer's temporary by that name (1 in 2^48): ours never existed
            tmp_name = None
            raise OutputError(f"cannot write {path}: a temporary of that name exists") from None
        except OSError as error:
            raise OutputError(f"cannot write {path}: {error.strerror}") from None
        with out_of_space_is_an_output_error(path):
            yield Path(tmp_name)
        os.chmod(tmp_name, output_mode(target))
        try:
            os.replace(tmp_name, target)
        except OSError as error:
            raise OutputError(f"cannot write {path}: {error.strerror}") from None
    except BaseException:
        if tmp_name is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp_name)
        raise


def temporary_beside(target: Path) -> str:
    """A fresh name for a temporary beside ``target``: hidden, its stem and extension kept (tools
    infer the format from it), 48 random bits; created by the caller with O_EXCL, as mkstemp would."""
    return os.path.join(target.parent or ".", f".{target.stem[:100]}.{secrets.token_hex(6)}.tmp{target.suffix[:20]}")


@contextlib.contextmanager
def out_of_space_is_an_output_error(path: str | os.PathLike) -> Iterator[None]:
    """No room for an output (full disk, quota, ``ulimit -f``) is the user's output error, exit 3
    with one line, however deep in a writer (numpy, zipfile, json) the write failed."""
    try:
        yield
    except OSError as error:
        if error.errno not in OUT_OF_SPACE:
            raise
        raise OutputError(f"cannot write {path}: {error.strerror}") from None


def json_name(text: str) -> str:
    """``text`` (a path or a file's name) as strict JSON can hold it: the bytes of a name that is
    not UTF-8, which Python decodes to lone surrogates (``surrogateescape``) and ``json.dumps``
    would write as ``\\udcff``, which strict parsers refuse, are written as ``\\xNN`` (Python's
    ``backslashreplace`` of the original bytes). Names that are UTF-8 are returned unchanged."""
    if not any("\ud800" <= char <= "\udfff" for char in text):
        return text
    try:
        raw = os.fsencode(text)
    except UnicodeEncodeError:  # a surrogate that no byte stands for (from an escaped JSON text)
        raw = text.encode("utf-8", "surrogatepass")
    return raw.decode("utf-8", "backslashreplace")


def json_safe(value):
    """``value`` with every string in it (keys too, at any depth) passed through :func:`json_name`;
    anything else as it is (numbers, numpy values, None)."""
    return _escaped(value)


def _escaped(value):
    if isinstance(value, os.PathLike) and isinstance(os.fspath(value), str):  # as default=str would write it
        return json_name(os.fspath(value))
    if isinstance(value, str):
        return json_name(value)
    if isinstance(value, dict):
        return {_escaped(key): _escaped(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_escaped(item) for item in value]
    return value
