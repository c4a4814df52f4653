"""The scoring protocol every quality table here uses: 5 s windows at 30 fps, 2.5 s apart.

Papers score AIST++ this way; the reference row, the generators' results and the benchmarks all
cut M2D the same way so their numbers sit side by side.
"""

from __future__ import annotations

import warnings
from typing import Sequence

import numpy as np

from ..datasets import Clip, WindowConfig, WindowedDataset
from ..music import BEAT_COLUMN
from .beats import MetricWarning
from .evaluate import Dance, EvaluationReport, evaluate

SCORING_WINDOWS = WindowConfig(seconds=5.0, stride_seconds=2.5, fps=30.0)
TABLE_HEADER = ("| {label} | clips | BeatAlign | PFC | FID_k | FID_g | Div_k | Div_g | beat dist motion->music | "
                "music->motion |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")


def scoring_windows(clips: Sequence[Clip]) -> list:
    """Every scoring window of ``clips`` (motion, features, genre), in a fixed order."""
    return list(WindowedDataset(list(clips), SCORING_WINDOWS))


def music_beats(features: np.ndarray) -> np.ndarray:
    return np.flatnonzero(features[:, BEAT_COLUMN] > 0.5)


def window_dance(window, motion, finished: bool = False, foot_lock: bool = False) -> Dance:
    """A generated ``motion`` for a scoring window as a Dance, optionally after the finishing passes
    (the beat lock, and the foot lock when asked)."""
    beats = music_beats(window.features)
    if finished:
        from ..finishing import finish

        motion = finish(motion, beats, foot=foot_lock)
    return Dance(f"{window.clip}@{window.start_frame}", motion.joint_positions(), beats)


def windows_as_dances(clips: Sequence[Clip]) -> list[Dance]:
    """Real motion of each scoring window, with that window's music beats."""
    return [Dance(f"{w.clip}@{w.start_frame}", w.motion.joint_positions(), music_beats(w.features))
            for w in scoring_windows(clips)]


def score(dances: Sequence[Dance], ground_truth: Sequence[Dance]) -> EvaluationReport:
    """Evaluate without the per-clip warnings (clips with no music beat are expected here)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        return evaluate(list(dances), list(ground_truth), fps=SCORING_WINDOWS.fps)


def fmt(value) -> str:
    return "-" if value is None else f"{0.0 if abs(value) < 5e-4 else value:.3f}"  # no "-0.000"


def table_row(label: str, report: EvaluationReport) -> str:
    """One markdown row in TABLE_HEADER's column order."""
    values = (report.beat_align, report.pfc, report.fid_k, report.fid_g, report.div_k, report.div_g,
              report.motion_to_music, report.music_to_motion)
    return f"| {label} | {report.generated_count} | " + " | ".join(fmt(v) for v in values) + " |"
