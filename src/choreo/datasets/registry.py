"""Recognise a dataset folder's layout and load it with the right reader."""

from __future__ import annotations

from pathlib import Path

from ..errors import DatasetError, ParameterError
from .base import Clip, ProgressCallback, select_split

DATASET_KINDS = ("m2d", "aistpp", "bvh")


def detect_dataset_kind(root: str | Path) -> str:
    """'m2d' (DANCE_* folders with skeletons.json), 'aistpp' (motions/*.pkl) or 'bvh' (*.bvh files)."""
    root = Path(root)
    if not root.is_dir():
        raise DatasetError(f"dataset folder {root} does not exist")
    if any((d / "skeletons.json").is_file() for d in root.glob("DANCE_*")):
        return "m2d"
    if (root / "motions").is_dir() and any((root / "motions").glob("*.pkl")):
        return "aistpp"
    if any(root.rglob("*.bvh")):
        return "bvh"
    raise DatasetError(
        f"{root} is not a dataset folder: expected M2D clip folders (DANCE_*/skeletons.json), "
        "AIST++ (motions/*.pkl, wavs/*.wav) or BVH files with audio beside them"
    )


def load_dataset(root: str | Path, kind: str | None = None, split: str | None = None,
                 progress: ProgressCallback | None = None) -> list[Clip]:
    """Clips of a dataset at 30 fps on SMPL-24 with aligned music features, whatever its layout."""
    kind = kind or detect_dataset_kind(root)
    if kind == "m2d":
        from .m2d import load_m2d

        return load_m2d(root, split=split, progress=progress)
    if kind == "aistpp":
        from .aistpp import load_aistpp

        return load_aistpp(root, split=split, progress=progress)
    if kind == "bvh":
        from .bvh_folder import load_bvh_folder

        return select_split(load_bvh_folder(root, progress=progress), split)
    raise ParameterError(f"unknown dataset kind {kind!r} (known: {', '.join(DATASET_KINDS)})")
