"""On-disk cache of per-song music features, so a dataset is featurised once, not every epoch.

Entries are keyed by the audio file's absolute path, size and modification time, the excerpt
asked for, and the feature definition version; a changed file or feature set misses the cache.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from ..fileio import atomic_output

FEATURE_VERSION = 2  # 2: beats tracked on a 96 fps envelope; bump when choreo.music's feature definition changes


def cache_dir() -> Path:
    """$CHOREO_CACHE_DIR, else $XDG_CACHE_HOME/choreo, else ~/.cache/choreo."""
    if os.environ.get("CHOREO_CACHE_DIR"):
        return Path(os.environ["CHOREO_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "choreo"


def _cache_key(audio_path: Path, start: float | None, end: float | None) -> str:
    stat = audio_path.stat()
    text = f"{audio_path.resolve()}|{stat.st_size}|{stat.st_mtime_ns}|{start}|{end}|v{FEATURE_VERSION}"
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def cached_music(audio_path: str | os.PathLike, start: float | None = None, end: float | None = None,
                 use_cache: bool = True):
    """:class:`choreo.music.Music` for ``audio_path`` cut to [start, end] seconds, from cache if possible."""
    from ..music import Music

    audio_path = Path(audio_path)
    if not use_cache:
        return Music.from_file(audio_path, start=start, end=end)
    entry = cache_dir() / "features" / f"{_cache_key(audio_path, start, end)}.npz"
    if entry.exists():
        try:
            with np.load(entry) as data:
                return Music(path=audio_path, duration=float(data["duration"]), fps=float(data["fps"]),
                             features=data["features"], beat_times=data["beat_times"], tempo=float(data["tempo"]),
                             start=start or 0.0)
        except (OSError, KeyError, ValueError):
            pass  # a damaged entry is recomputed below
    music = Music.from_file(audio_path, start=start, end=end)
    entry.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(entry) as handle:
        np.savez(handle, features=music.features, beat_times=music.beat_times, tempo=music.tempo,
                 duration=music.duration, fps=music.fps)
    return music
