"""On-disk cache of per-song music features, so a dataset is featurised once, not every epoch.

Entries are keyed by the audio file's absolute path, size, modification time and a hash of its
first and last MiB (so a file replaced by ``cp -p``, same size and time, misses too), the excerpt
asked for, and the feature definition version. An entry is checked on read (the arrays, their
shapes and dtypes, finite values): a damaged or planted one is recomputed, never trusted.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import ChoreoError, OutputError
from ..fileio import atomic_output
from ..formats.safe_arrays import ZIP_ERRORS, load_npz

MAX_ENTRY_BYTES = 1 << 28  # per array: hours of features; more is not an entry we wrote
FEATURE_VERSION = 2  # 2: beats tracked on a 96 fps envelope; bump when choreo.music's feature definition changes


def cache_dir() -> Path:
    """$CHOREO_CACHE_DIR, else $XDG_CACHE_HOME/choreo, else ~/.cache/choreo."""
    if os.environ.get("CHOREO_CACHE_DIR"):
        return Path(os.environ["CHOREO_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "choreo"


HASHED_BYTES = 1 << 20  # from each end of the file: cheap on any song, and a re-encode changes both


def _content_digest(audio_path: Path, size: int) -> str:
    """SHA-256 of the file's first and last MiB (all of it when smaller)."""
    digest = hashlib.sha256()
    with open(audio_path, "rb") as handle:
        digest.update(handle.read(HASHED_BYTES))
        if size > HASHED_BYTES:
            handle.seek(max(HASHED_BYTES, size - HASHED_BYTES))
            digest.update(handle.read(HASHED_BYTES))
    return digest.hexdigest()


def _cache_key(audio_path: Path, start: float | None, end: float | None) -> str:
    stat = audio_path.stat()
    content = _content_digest(audio_path, stat.st_size)
    text = f"{audio_path.resolve()}|{stat.st_size}|{stat.st_mtime_ns}|{content}|{start}|{end}|v{FEATURE_VERSION}"
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def finite_array(data: dict, key: str, shape: tuple, kinds: str = "f") -> bool:
    """Whether ``data[key]`` is there, a finite array of a dtype kind in ``kinds`` and of ``shape``
    (None: any length on that axis): what a cache validator asks of every array it trusts."""
    array = data.get(key)
    return (isinstance(array, np.ndarray) and array.dtype.kind in kinds and array.ndim == len(shape)
            and all(want is None or want == got for want, got in zip(shape, array.shape))
            and bool(np.isfinite(array).all()))


def _valid_features(data: dict) -> bool:
    """Whether a feature entry holds what :func:`cached_music` stores: (T, FEATURE_DIM) finite
    features, finite increasing beat times, a finite tempo, and a finite positive duration and
    rate. (An entry of another width passed an older check, and training then crashed.)"""
    from ..music import FEATURE_DIM

    return (finite_array(data, "features", (None, FEATURE_DIM)) and data["features"].size > 0
            and finite_array(data, "beat_times", (None,)) and bool(np.all(np.diff(data["beat_times"]) >= 0))
            and all(finite_array(data, key, (), "fi") and data[key] > 0 for key in ("duration", "fps"))
            and finite_array(data, "tempo", (), "fi"))


def read_entry(entry: Path, valid: Callable[[dict], bool]) -> dict | None:
    """The arrays of the cache entry ``entry`` when it is a regular file whose arrays pass
    ``valid``; None when it is missing, a link, unreadable, truncated or fails ``valid``. The one
    reader of both caches (features and M2D fits): anything wrong is a miss, recomputed and
    rewritten by the caller, never an error that leaves a dataset unloadable."""
    if not is_entry(entry):
        return None
    try:
        data = load_npz(entry, limit=MAX_ENTRY_BYTES)
        return data if valid(data) else None
    except (ChoreoError, *ZIP_ERRORS, KeyError, TypeError, IndexError):
        return None


def cached_music(audio_path: str | os.PathLike, start: float | None = None, end: float | None = None,
                 use_cache: bool = True):
    """:class:`choreo.music.Music` for ``audio_path`` cut to [start, end] seconds, from cache if possible."""
    from ..music import Music

    audio_path = Path(audio_path)
    if not use_cache:
        return Music.from_file(audio_path, start=start, end=end)
    entry = cache_dir() / "features" / f"{_cache_key(audio_path, start, end)}.npz"
    data = read_entry(entry, _valid_features)
    if data is not None:
        return Music(path=audio_path, duration=float(data["duration"]), fps=float(data["fps"]),
                     features=data["features"], beat_times=data["beat_times"], tempo=float(data["tempo"]),
                     start=start or 0.0)
    music = Music.from_file(audio_path, start=start, end=end)
    write_entry(entry, features=music.features, beat_times=music.beat_times, tempo=music.tempo,
                duration=music.duration, fps=music.fps)
    return music


def is_entry(entry: Path) -> bool:
    """Whether ``entry`` is there to be read: a regular file of its own. A link was planted (choreo
    writes none) and may lead to a FIFO, whose reading never ends, or to another user's file."""
    try:
        return stat.S_ISREG(entry.lstat().st_mode)
    except OSError:
        return False


def write_entry(entry: Path, **arrays) -> None:
    """Store ``arrays`` as the NPZ cache entry ``entry``, atomically. No user names a cache entry,
    so a link found at its name was planted there: the link itself is replaced, and the file it
    points to is never written (an output named by the user is written through its link).

    Best effort: the cache only saves time, so one that cannot be written (its root a file, a
    read-only folder, a full disk) is skipped and the command goes on without it."""
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        with atomic_output(entry, follow_links=False) as handle:
            np.savez(handle, **arrays)
    except (OSError, OutputError):
        return
