"""A folder of BVH files, each with its song beside it under the same name.

```
root/salsa/take1.bvh  root/salsa/take1.mp3     genre "salsa" from the parent folder, or from
root/take2.bvh        root/take2.wav           root/genres.json {"take2": "tango", ...}
root/split.json       {"take1": "train", "take2": "test"}   (optional)
```
The BVH skeleton must be SMPL-24 (see choreo.formats.bvh). Motion is resampled to 30 fps; the
music is assumed to start with the motion's first frame.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from ..errors import DatasetError
from ..formats.bvh import read_bvh
from ..music import SUPPORTED_EXTENSIONS
from .base import Clip, ProgressCallback
from ..formats import json_arrays
from .cache import cached_music
from .clips import align_music_and_motion


def _read_mapping(path: Path) -> dict[str, str]:
    if not path.is_file():
        return {}
    try:
        mapping = json_arrays.loads(path.read_text())
    except ValueError:  # malformed, not UTF-8, or nested too deeply
        raise DatasetError(f"{path} is not valid JSON") from None
    if not isinstance(mapping, dict):
        raise DatasetError(f"{path} must map clip names to strings")
    return {str(k): str(v) for k, v in mapping.items()}


def find_audio_beside(motion_path: Path) -> Path | None:
    for extension in SUPPORTED_EXTENSIONS:
        candidate = motion_path.with_suffix(extension)
        if candidate.is_file():
            return candidate
    return None


def load_bvh_folder(root: str | Path, fps: float = 30.0, progress: ProgressCallback | None = None) -> list[Clip]:
    """One Clip per ``*.bvh`` under ``root`` that has audio beside it (others skipped, with a warning)."""
    root = Path(root)
    if not root.is_dir():
        raise DatasetError(f"dataset folder {root} does not exist")
    genres, splits = _read_mapping(root / "genres.json"), _read_mapping(root / "split.json")
    paths = sorted(root.rglob("*.bvh"))
    if not paths:
        raise DatasetError(f"{root}: no .bvh files")
    clips, missing = [], []
    for done, path in enumerate(paths):
        if progress:
            progress(done, len(paths), path.stem)
        audio = find_audio_beside(path)
        if audio is None:
            missing.append(path.name)
            continue
        name = str(path.relative_to(root).with_suffix(""))
        genre = genres.get(path.stem) or (path.parent.name if path.parent != root else None)
        motion = read_bvh(path).resample(fps)
        motion, features = align_music_and_motion(motion, cached_music(audio).features, name)
        clips.append(Clip(name, motion, features, genre=genre, split=splits.get(path.stem), audio_path=str(audio)))
    if progress:
        progress(len(paths), len(paths), "")
    if missing:
        warnings.warn(f"{len(missing)} BVH file(s) without audio beside them were skipped: {', '.join(missing[:5])}")
    if not clips:
        raise DatasetError(f"{root}: no BVH file has an audio file of the same name beside it")
    return clips
