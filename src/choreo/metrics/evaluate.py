"""Evaluate a set of dances against a ground-truth set: every metric of the field in one report."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .beats import beat_align_score, beat_distances, motion_beats
from .form import dance_form_score
from .fid import diversity, frechet_distance, motion_features, normalise_by_reference
from .legs import Legs, legs, mean_legs
from .pfc import foot_contact_score, PFC_SCALE
from .stepping import Stepping, pooled, stepping
from .two_sample import TwoSample, classifier_test


@dataclass
class Dance:
    """One motion to score: joint positions and, when known, the music beats it dances to."""

    name: str
    positions: np.ndarray  # (T, 24, 3) metres, Y up, at the evaluation frame rate
    music_beats: np.ndarray | None = None  # beat frame indices at the same frame rate
    music_bars: tuple[np.ndarray, np.ndarray] | None = None  # (bar line frames (B,), how alike they sound (B, B))


@dataclass
class DanceScore:
    name: str
    frames: int
    seconds: float
    beat_align: float | None
    pfc: float  # this clip's PFC term x 10,000
    motion_to_music: float | None  # ChoreoGraph's mean squared beat distances, frames^2
    music_to_motion: float | None
    stepping: Stepping  # planted feet, feet against the root, the supporting foot's slide (stepping.py)
    legs: Legs  # feet around the pelvis, ankle lift, pelvis speed, foot jerk (legs.py)
    form_score: float | None = None  # how the dance's bar self-similarity follows the music's (form.py)


@dataclass
class EvaluationReport:
    fps: float
    generated_count: int
    ground_truth_count: int
    mean_clip_seconds: float
    beat_align: float | None  # mean over clips with music
    pfc: float
    fid_k: float
    fid_g: float
    div_k: float
    div_g: float
    ground_truth_div_k: float
    ground_truth_div_g: float
    ground_truth_beat_align: float | None
    ground_truth_pfc: float
    motion_to_music: float | None
    music_to_motion: float | None
    planted_share: float  # stepping (stepping.py): share of frames with a planted foot
    foot_root_correlation: float  # the faster foot's speed against the root's
    support_slide: float  # metres the slower foot travels per metre the root travels
    ground_truth_planted_share: float
    ground_truth_foot_root_correlation: float
    ground_truth_support_slide: float
    legs: Legs  # the mean over clips of each legs figure (legs.py)
    ground_truth_legs: Legs
    classifier: TwoSample  # how well a logistic regression tells the generated windows from the ground truth's
    form_score: float | None  # mean over clips with music (form.py)
    ground_truth_form_score: float | None
    clips: list[DanceScore] = field(default_factory=list)
    ground_truth_clips: list[DanceScore] = field(default_factory=list)

    def to_dict(self) -> dict:
        return asdict(self)


def score_dance(dance: Dance, fps: float) -> DanceScore:
    beats = motion_beats(dance.positions)
    align = m2m = music2m = None
    if dance.music_beats is not None:
        align = beat_align_score(dance.music_beats, beats)
        m2m, music2m = beat_distances(dance.music_beats, beats)
    form = dance_form_score(dance.positions, *dance.music_bars) if dance.music_bars is not None else None
    return DanceScore(dance.name, len(dance.positions), len(dance.positions) / fps, align,
                      foot_contact_score(dance.positions) * PFC_SCALE, m2m, music2m, stepping(dance.positions, fps),
                      legs(dance.positions, fps), form)


def _mean_of(values) -> float | None:
    values = [v for v in values if v is not None and np.isfinite(v)]
    return float(np.mean(values)) if values else None


def evaluate(generated: Sequence[Dance], ground_truth: Sequence[Dance], fps: float = 30.0,
             progress: Callable[[int, int], None] | None = None) -> EvaluationReport:
    """Score ``generated`` against ``ground_truth`` (features normalised by the ground truth)."""
    total = len(generated) + len(ground_truth)
    features = []
    for done, dance in enumerate([*generated, *ground_truth]):
        features.append(motion_features(dance.positions))
        if progress:
            progress(done + 1, total)
    kinetic = np.stack([k for k, _ in features])
    geometric = np.stack([g for _, g in features])
    n = len(generated)
    gen_k, gt_k = normalise_by_reference(kinetic[:n], kinetic[n:])
    gen_g, gt_g = normalise_by_reference(geometric[:n], geometric[n:])
    scores = [score_dance(d, fps) for d in generated]
    truth_scores = [score_dance(d, fps) for d in ground_truth]
    steps, truth_steps = pooled([s.stepping for s in scores]), pooled([s.stepping for s in truth_scores])
    return EvaluationReport(
        fps=fps, generated_count=n, ground_truth_count=len(ground_truth),
        mean_clip_seconds=float(np.mean([s.seconds for s in scores])) if scores else 0.0,
        beat_align=_mean_of(s.beat_align for s in scores), pfc=float(np.nanmean([s.pfc for s in scores])),
        fid_k=frechet_distance(gen_k, gt_k), fid_g=frechet_distance(gen_g, gt_g),
        div_k=diversity(gen_k), div_g=diversity(gen_g),
        ground_truth_div_k=diversity(gt_k), ground_truth_div_g=diversity(gt_g),
        ground_truth_beat_align=_mean_of(s.beat_align for s in truth_scores),
        ground_truth_pfc=float(np.nanmean([s.pfc for s in truth_scores])),
        motion_to_music=_mean_of(s.motion_to_music for s in scores),
        music_to_motion=_mean_of(s.music_to_motion for s in scores),
        planted_share=steps[0], foot_root_correlation=steps[1], support_slide=steps[2],
        ground_truth_planted_share=truth_steps[0], ground_truth_foot_root_correlation=truth_steps[1],
        ground_truth_support_slide=truth_steps[2],
        legs=mean_legs([s.legs for s in scores]), ground_truth_legs=mean_legs([s.legs for s in truth_scores]),
        classifier=classifier_test([d.positions for d in generated], [d.positions for d in ground_truth], fps),
        form_score=_mean_of(s.form_score for s in scores),
        ground_truth_form_score=_mean_of(s.form_score for s in truth_scores),
        clips=scores, ground_truth_clips=truth_scores,
    )  # fmt: skip


def resample_positions(positions: np.ndarray, source_fps: float, target_fps: float) -> np.ndarray:
    """Linear resampling of joint positions in time, keeping the duration."""
    if np.isclose(source_fps, target_fps):
        return positions
    from ..motion import positions_at

    frames = max(1, int(round(len(positions) * target_fps / source_fps)))
    return positions_at(positions, np.arange(frames) * source_fps / target_fps)


MOTION_EXTENSIONS = (".bvh", ".npz", ".pkl", ".json", ".npy")


def collect_motion_files(path: Path) -> list[Path]:
    """A single motion file, or every motion file in a folder (not recursive), sorted."""
    from ..errors import InputError

    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such file or folder")
    if path.is_file():
        return [path]
    files = sorted(p for p in path.iterdir() if p.suffix.lower() in MOTION_EXTENSIONS and p.is_file())
    if not files:
        raise InputError(f"{path}: no motion files ({', '.join(MOTION_EXTENSIONS)})")
    return files
