"""A song's form: its sections, on bar lines, and which of them return (A B A B, verse and chorus).

Why: choreographers give a returning section the same phrase of movement, and that is what makes
a dance read as choreographed. The analysis is bar-synchronous self-similarity of harmony
(chroma) and timbre (MFCC), both already among the music features, so it costs no second decode.
"""

from __future__ import annotations

import re
import string
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError


@dataclass(frozen=True)
class Section:
    """One section: where it starts (seconds) and its letter (equal letters: the music returns)."""

    start: float
    label: str


@dataclass(frozen=True)
class Form:
    """A song's sections in order; the first starts at 0, each runs to the next one's start."""

    sections: tuple[Section, ...]
    duration: float
    source: str = "analysed"  # or "given" (--form)

    def spans(self) -> list[tuple[float, float, str]]:
        """(start, end, label) of each section, in seconds."""
        ends = [s.start for s in self.sections[1:]] + [self.duration]
        return [(s.start, end, s.label) for s, end in zip(self.sections, ends)]

    def returns(self) -> list[tuple[int, int]]:
        """(section, the first earlier section with its letter) for every section that returns."""
        first: dict[str, int] = {}
        pairs = []
        for index, section in enumerate(self.sections):
            if section.label in first:
                pairs.append((index, first[section.label]))
            else:
                first[section.label] = index
        return pairs

    def describe(self) -> str:
        """"A 0:00, B 0:16, A 0:32": what `choreo info` shows."""
        return ", ".join(f"{s.label} {clock(s.start)}" for s in self.sections)

    def as_json(self) -> list[dict]:
        return [{"start": round(start, 3), "end": round(end, 3), "label": label} for start, end, label in self.spans()]


def beats_per_bar(style: str | None) -> int:
    """The bar a style dances in: three beats for a waltz, four for the rest."""
    return 3 if style and "waltz" in style.lower() else 4


def clock(seconds: float) -> str:
    """m:ss (rounded to the second)."""
    whole = int(round(seconds))
    return f"{whole // 60}:{whole % 60:02d}"


def letters(count: int) -> list[str]:
    """A, B, ..., Z, AA, AB, ...: as many section letters as asked for."""
    names = list(string.ascii_uppercase)
    while len(names) < count:
        names += [a + b for a in string.ascii_uppercase for b in string.ascii_uppercase]
    return names[:count]


# -- analysis ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FormConfig:
    """The analysis's few choices, chosen on the validation songs of benchmarks/form_songs.json
    (benchmarks/form_analysis.py)."""

    neighbours: int = 6  # each bar's links to the bars that sound most like it
    path_bars: int = 3  # repeats are stripes: the links smoothed along the diagonals over this many bars
    max_letters: int = 8  # at most this many different sections
    min_bars: int = 4  # no section is shorter (2 or 3 divided the waltzes into their 2-bar phrases)


def bar_lines(beat_times: np.ndarray, beats_per_bar: int, chroma_change: np.ndarray | None = None) -> np.ndarray:
    """Seconds of every bar line: every ``beats_per_bar``-th beat, from the phase at which the
    harmony changes most (chords change on the downbeat; ``chroma_change`` per beat), else the first."""
    beat_times = np.asarray(beat_times, dtype=np.float64)
    phase = 0
    if chroma_change is not None and len(beat_times) >= 2 * beats_per_bar:
        scores = [chroma_change[p::beats_per_bar].mean() for p in range(beats_per_bar)]
        phase = int(np.argmax(scores))
    return beat_times[phase::beats_per_bar]


def beat_features(features: np.ndarray, fps: float, beat_times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(chroma, timbre) per beat: each beat's mean chroma_cens (12) and z-scored MFCC 1-12, from
    the music's 30 fps feature columns."""
    from .features import CHROMA_COLUMNS, MFCC_COLUMNS

    edges = np.clip(np.round(np.asarray(beat_times) * fps).astype(int), 0, len(features))
    edges = np.append(edges, len(features))
    chroma, timbre = features[:, CHROMA_COLUMNS], features[:, MFCC_COLUMNS][:, 1:13]
    timbre = (timbre - timbre.mean(0)) / (timbre.std(0) + 1e-6)
    spans = [(a, max(b, a + 1)) for a, b in zip(edges[:-1], edges[1:])]
    return (np.array([chroma[a:b].mean(0) for a, b in spans]), np.array([timbre[a:b].mean(0) for a, b in spans]))


def unit_rows(vectors: np.ndarray) -> np.ndarray:
    """Rows centred on their mean and scaled to unit length: cosine similarity is then a dot product."""
    centred = vectors - vectors.mean(0)
    return centred / (np.linalg.norm(centred, axis=1, keepdims=True) + 1e-9)


def bar_vectors(music, beats_per_bar: int) -> tuple[np.ndarray, np.ndarray]:
    """(bar line seconds (B,), (B, D) what each bar sounds like): its harmony and timbre beat by
    beat (its chord progression, not only its average), each part scaled alike."""
    beat_times = np.asarray(music.beat_times, dtype=np.float64)
    chroma, timbre = beat_features(music.features, music.fps, beat_times)
    bars = bar_lines(beat_times, beats_per_bar, np.r_[0.0, np.linalg.norm(np.diff(chroma, axis=0), axis=1)])
    first = int(np.searchsorted(beat_times, bars[0] - 1e-6)) if len(bars) else 0
    count = (len(beat_times) - first) // beats_per_bar
    if count < 1:  # not one whole bar
        return bars[:0], np.zeros((0, 24 * beats_per_bar))
    take = first + np.arange(count * beats_per_bar)
    return bars[:count], np.c_[unit_rows(chroma[take].reshape(count, -1)), unit_rows(timbre[take].reshape(count, -1))]


def music_self_similarity(music, beats_per_bar: int) -> tuple[np.ndarray, np.ndarray]:
    """(bar line seconds, (B, B) cosine similarity of the bars): the music's side of the form score
    and of `choreo render --plot form`."""
    bars, vectors = bar_vectors(music, beats_per_bar)
    unit = unit_rows(vectors)
    return bars, unit @ unit.T


def neighbour_links(vectors: np.ndarray, neighbours: int, apart: int = 2) -> np.ndarray:
    """(B, B) affinity exp(-d / median k-th neighbour distance) between rows that are among each
    other's ``neighbours`` nearest by cosine distance, at least ``apart`` rows apart (a mutual
    k-nearest-neighbour recurrence; librosa.segment.recurrence_matrix's, without its 2.5 s import)."""
    unit = vectors / (np.linalg.norm(vectors, axis=1, keepdims=True) + 1e-9)
    distance = np.clip(1.0 - unit @ unit.T, 0.0, None)
    index = np.arange(len(vectors))
    distance[np.abs(index[:, None] - index[None, :]) < apart] = np.inf
    kth = np.sort(distance, axis=1)[:, min(neighbours, len(vectors) - 1) - 1]
    near = distance <= kth[:, None]
    mutual = near & near.T & np.isfinite(distance)
    scale = np.median(kth[np.isfinite(kth)]) if np.isfinite(kth).any() else 1.0
    return np.where(mutual, np.exp(-distance / max(scale, 1e-9)), 0.0)


def along_diagonals(links: np.ndarray, length: int) -> np.ndarray:
    """``links`` averaged over ``length`` steps along the diagonals, centred: a repeat of several
    bars is a stripe, one bar's resemblance a dot, and the average keeps the stripes."""
    if length <= 1:
        return links
    count, out = len(links), np.zeros_like(links)
    for step in range(-(length // 2), length - length // 2):
        shifted = np.zeros_like(links)
        lo, hi = max(0, -step), min(count, count - step)
        shifted[lo:hi, lo:hi] = links[lo + step:hi + step, lo + step:hi + step]
        out += shifted
    return out / length


def bar_graph(vectors: np.ndarray, config: FormConfig) -> np.ndarray:
    """(B, B) links between bars: to the bars that sound most like them (with the bars on either
    side, so a phrase, smoothed along the diagonals: a repeat is a stripe), and to their neighbours
    in time, in proportion to how alike in timbre; the two kinds balanced so that neither drowns the
    other (the Laplacian segmentation of McFee and Ellis, 2014, on bars)."""
    phrases = np.c_[np.r_[vectors[:1], vectors[:-1]], vectors, np.r_[vectors[1:], vectors[-1:]]]
    repeats = along_diagonals(neighbour_links(phrases, min(config.neighbours, len(vectors) - 2)), config.path_bars)
    steps = np.sum(np.diff(vectors, axis=0) ** 2, axis=1)
    near = np.exp(-steps / (np.median(steps) + 1e-9))
    path = np.diag(near, 1) + np.diag(near, -1)
    path_degree, repeat_degree = path.sum(1), repeats.sum(1)
    share = path_degree @ (path_degree + repeat_degree) / np.sum((path_degree + repeat_degree) ** 2)
    return share * repeats + (1 - share) * path


def bar_labels(graph: np.ndarray, config: FormConfig) -> np.ndarray:
    """(B,) a cluster per bar: the graph's smoothest modes (its normalised Laplacian's first
    eigenvectors), as many as the largest gap between eigenvalues says, clustered by k-means
    (seeded: the same song, the same form)."""
    import scipy.linalg
    import scipy.ndimage
    import scipy.sparse.csgraph
    from scipy.cluster.vq import kmeans2

    laplacian = scipy.sparse.csgraph.laplacian(graph, normed=True)
    values, vectors = scipy.linalg.eigh(laplacian)
    vectors = scipy.ndimage.median_filter(vectors, size=(3, 1))
    top = min(config.max_letters, len(values) - 1)
    count = int(np.argmax(np.diff(values[: top + 1])[1:top]) + 2) if top >= 3 else 2
    modes = vectors[:, :count] / (np.linalg.norm(vectors[:, :count], axis=1, keepdims=True) + 1e-9)
    _, labels = kmeans2(modes, count, seed=0, minit="++")
    return labels


def runs_of(labels) -> list[list[int]]:
    """[first bar, stop bar, label] of each run of equal labels."""
    runs: list[list[int]] = []
    for bar, label in enumerate(labels):
        if runs and runs[-1][2] == label:
            runs[-1][1] = bar + 1
        else:
            runs.append([bar, bar + 1, int(label)])
    return runs


def sections_of(labels: np.ndarray, min_bars: int) -> list[list[int]]:
    """Runs of bars, none shorter than ``min_bars`` (a short one takes its left neighbour's label,
    the first its right one's)."""
    labels = list(labels)
    runs = runs_of(labels)
    while len(runs) > 1 and min(stop - start for start, stop, _ in runs) < min_bars:
        index = next(k for k, (start, stop, _) in enumerate(runs) if stop - start < min_bars)
        start, stop, _ = runs[index]
        labels[start:stop] = [runs[index - 1 if index else 1][2]] * (stop - start)
        runs = runs_of(labels)
    return runs


def analyse_form(music, beats_per_bar: int = 4, config: FormConfig = FormConfig()) -> Form:
    """The sections of ``music`` (a choreo.music.Music analysed with its timbre) on its bar lines,
    lettered in order of first appearance."""
    if not music.timbre:
        raise ParameterError("the form analysis needs the music's chroma and MFCC (analyse with timbre=True)")
    bars, vectors = bar_vectors(music, beats_per_bar)
    if len(bars) < 3 * config.min_bars:  # not even A B A
        return Form((Section(0.0, "A"),), music.duration)
    runs = sections_of(bar_labels(bar_graph(vectors, config), config), config.min_bars)
    order: dict[int, int] = {}
    for _, _, label in runs:
        order.setdefault(label, len(order))
    names = letters(len(order))
    return Form(tuple(Section(0.0 if start == 0 else float(bars[start]), names[order[label]])
                      for start, _, label in runs), music.duration)


# -- a form the user gives ----------------------------------------------------------------------------
FORM_ENTRY = re.compile(r"^\s*(?:(\d+):)?(\d+(?:\.\d+)?)\s*=\s*([A-Za-z]{1,2})\s*$")


def parse_form(text: str, duration: float) -> Form:
    """'0:00=A,0:16=B,0:32=A' (m:ss or seconds) -> the Form; the first section starts at 0."""
    sections = []
    for part in text.split(","):
        match = FORM_ENTRY.match(part)
        if not match:
            raise ParameterError(f"--form {text!r}: every entry must look like TIME=LETTER (e.g. 0:16=B)")
        start = 60 * int(match[1] or 0) + float(match[2])
        if start >= duration:
            raise ParameterError(f"--form {text!r}: {clock(start)} is past the song's end ({duration:.1f} s)")
        sections.append(Section(start, match[3].upper()))
    starts = [s.start for s in sections]
    if starts[0] != 0:
        raise ParameterError(f"--form {text!r}: the first section must start at 0:00")
    if any(b <= a for a, b in zip(starts, starts[1:])):
        raise ParameterError(f"--form {text!r}: the sections' times must increase")
    return Form(tuple(sections), duration, source="given")
