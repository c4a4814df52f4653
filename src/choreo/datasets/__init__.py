"""Dataset readers (M2D, AIST++, BVH folders) yielding the same clips and 5 s windows."""

from .base import TEST, TRAIN, Clip, Window, WindowConfig, WindowedDataset, select_split, window_starts
from .registry import DATASET_KINDS, detect_dataset_kind, load_dataset

__all__ = [
    "DATASET_KINDS", "TEST", "TRAIN", "Clip", "Window", "WindowConfig", "WindowedDataset",
    "detect_dataset_kind", "load_dataset", "select_split", "window_starts",
]  # fmt: skip
