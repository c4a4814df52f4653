"""The whole-song protocol's library part: a dataset clip's song cut as a user would cut it, each
dance's per-song figures, the window FIDs with bootstrap intervals, the classifier tests and the
targets (docs/results.md, "Whole songs"). ``scripts/evaluate_whole_songs.py`` dances the songs
and prints; experiments and ``scripts/results_tables.py`` reuse these.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..music import Music
from .beats import beat_align_score, motion_beats
from .fid import frechet_distance, motion_features, normalise_by_reference
from .two_sample import classifier_test, windows_of
from .whole_song import whole_song

FPS = 30.0  # every figure is taken at 30 fps
COLUMNS = ("pace", "reach", "planted", "foot_root", "slide", "jerk", "root_jerk", "body_jerk", "beat_align", "beat_dip",
           "feet_speed", "ankle_lift", "pelvis_speed", "foot_jerk", "form")
BOOTSTRAP = 300  # resamplings of the windows behind each FID's interval


def split_clips(clips, split: str):
    """A split's clips: "validation" (m2d_split.json's validation clips, part of train), "test", "train"."""
    from ..datasets import TEST, select_split
    from ..datasets.m2d import validation_clips

    if split == "validation":
        held = set(validation_clips())
        return [c for c in clips if c.name in held]
    return select_split(clips, TEST if split == "test" else split)


def song_of(clip) -> Music:
    """The clip's music from where its dance starts, for the dance's length (as a user would cut it)."""
    start = max(clip.audio_offset, 0.0)
    return Music.from_file(clip.audio_path, start=start, end=start + clip.motion.num_frames / FPS,
                           log_mel=True, timbre=True)


def figures(positions: np.ndarray, music: Music, style: str | None = None) -> dict:
    """One dance's row (COLUMNS): choreo.metrics.whole_song's figures, BeatAlign against ``music`` and
    the form score (bars of the style's metre)."""
    from ..music.form import beats_per_bar, music_self_similarity
    from .form import dance_form_score

    row = whole_song(positions, FPS).to_dict()
    row["beat_align"] = beat_align_score(music.beat_frames, motion_beats(positions))
    bars, alike = music_self_similarity(music, beats_per_bar(style))
    score = dance_form_score(positions, bars * FPS, alike)
    row["form"] = float("nan") if score is None else score
    return row


def mean_rows(rows: list[dict]) -> dict:
    """Each column's mean over rows (runs saved before a column existed: NaN)."""
    return {c: float(np.nanmean([r.get(c, np.nan) for r in rows])) if any(c in r for r in rows) else float("nan")
            for c in COLUMNS}


def fid_with_interval(features: np.ndarray, reference: np.ndarray, rng: np.random.Generator) -> tuple[float, float, float]:
    """FID of the set against the reference and its 95 % bootstrap interval (windows resampled)."""
    generated, ref = normalise_by_reference(features, reference)
    value = frechet_distance(generated, ref)
    draws = [frechet_distance(generated[rng.integers(0, len(generated), len(generated))], ref) for _ in range(BOOTSTRAP)]
    low, high = np.percentile(draws, [2.5, 97.5])
    return value, float(low), float(high)


def window_fids(dances: list[np.ndarray], reference: tuple[np.ndarray, np.ndarray], seed: int = 0) -> dict:
    """FID_k and FID_g of the 5 s windows (2.5 s apart) of every dance, pooled, against the
    reference's (kinetic, geometric) features, each with its interval."""
    features = [motion_features(w) for d in dances for w in windows_of(d, FPS)]
    kinetic, geometric = np.stack([k for k, _ in features]), np.stack([g for _, g in features])
    rng = np.random.default_rng(seed)
    return {"windows": len(features), "fid_k": fid_with_interval(kinetic, reference[0], rng),
            "fid_g": fid_with_interval(geometric, reference[1], rng)}


def classifier_tests(dances: Sequence[np.ndarray], real_dances: Sequence[np.ndarray], genres: Sequence[str],
                     real_genres: Sequence[str], groups: Sequence[str]) -> dict:
    """The classifier two-sample test (choreo.metrics.two_sample) against the real dancers to the
    same songs, pooled over the Latin songs and over every song; windows grouped by song and seed."""
    tests = {}
    for name, keep in (("latin", lambda g: g != "waltz"), ("all", lambda g: True)):
        mine = [i for i, g in enumerate(genres) if keep(g)]
        theirs = [i for i, g in enumerate(real_genres) if keep(g)]
        result = classifier_test([dances[i] for i in mine], [real_dances[i] for i in theirs], FPS,
                                 [groups[i] for i in mine])
        tests[name] = vars(result)
    return tests


def target_failures(songs: dict) -> list[str]:
    """The whole-song targets per song (mean over seeds) that a run misses, one line each; ``songs``
    as a saved run holds them (per song: genre, the real row, one row per seed)."""
    latin = [v["real"]["jerk"] for v in songs.values() if v["genre"] != "waltz"]
    latin_jerk = float(np.mean(latin)) if latin else float("nan")
    misses = []
    for name, entry in songs.items():
        real, mean = entry["real"], mean_rows(entry["seeds"])
        jerk_mark = 1.5 * (latin_jerk if entry["genre"] == "waltz" else real["jerk"])
        checks = {"pace": abs(mean["pace"] / real["pace"] - 1) <= 0.2,
                  "reach": mean["reach"] <= 1.5 * real["reach"] + 0.5,
                  "planted": mean["planted"] >= 0.9 * real["planted"],
                  "foot_root": mean["foot_root"] <= real["foot_root"] + 0.1,
                  "jerk": mean["jerk"] <= jerk_mark,
                  "beat_dip": mean["beat_dip"] >= 0.8 * real["beat_dip"]}
        misses += [f"{name} {key}: {mean[key]:.3f} (real {real[key]:.3f})" for key, ok in checks.items() if not ok]
    return misses
