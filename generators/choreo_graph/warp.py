"""Dynamic time-warper (paper 3.2): cut and re-time a 4 s piece of an 8 s clip so that its
tempo-density follows the music's.

Subsequence DTW of the music's curve (query, every frame matched) against the clip's (reference,
free start and end) with steps (1,1), (1,2), (2,1): the reference advances 0.5 to 2 frames per
query frame, so the warped piece plays between half and twice its original speed. The recursion
and tie-breaking are librosa's (``librosa.sequence.dtw(..., subseq=True, step_sizes_sigma=...)``,
checked against it in the tests); this version runs thousands of pairs at once as array
operations, because the graph warps K candidates for every second of the song.
"""

from __future__ import annotations

import numpy as np
import scipy.ndimage

STEPS = np.array([[1, 1], [1, 2], [2, 1]])  # (query, reference) advances; slope in [0.5, 2]


def subsequence_dtw(queries: np.ndarray, references: np.ndarray) -> np.ndarray:
    """Reference index matched to every query frame, for a batch of pairs.

    queries (B, N) and references (B, M) are 1-d curves; cost |q_i - r_j|. Returns (B, N) float
    indices into the reference (frames a (2, 1) step skips are interpolated), non-decreasing.
    """
    queries = np.asarray(queries, np.float32)
    references = np.asarray(references, np.float32)
    batch, n = queries.shape
    m = references.shape[1]
    # rows first, so each query row is one contiguous block; two columns of +inf in front so the
    # shifted views below need no bounds checks or copies
    total = np.full((n, batch, m + 2), np.inf, np.float32)
    step = np.zeros((n, batch, m), np.int8)
    total[0, :, 2:] = np.abs(queries[:, :1] - references)
    best = np.empty((batch, m), np.float32)
    better = np.empty((batch, m), bool)
    for i in range(1, n):
        diagonal, fast = total[i - 1, :, 1:-1], total[i - 1, :, :-2]
        np.less(fast, diagonal, out=better)  # strict: on ties the earlier step wins, as in librosa
        np.minimum(diagonal, fast, out=best)
        row_step = step[i]
        np.copyto(row_step, better, casting="unsafe")
        if i >= 2:
            slow = total[i - 2, :, 1:-1]
            np.less(slow, best, out=better)
            np.minimum(best, slow, out=best)
            np.copyto(row_step, 2, where=better)
        np.subtract(queries[:, i : i + 1], references, out=total[i, :, 2:])
        np.abs(total[i, :, 2:], out=total[i, :, 2:])
        total[i, :, 2:] += best
    if not np.isfinite(total[-1, :, 2:].min()):
        raise ValueError(f"a query of {n} frames has no path through {m} reference frames "
                         "(each step advances the query by at most 2 frames per reference frame)")
    return _backtrack(total[-1, :, 2:].argmin(1), step, n)


def _backtrack(end: np.ndarray, step: np.ndarray, n: int) -> np.ndarray:
    batch = len(end)
    rows = np.arange(batch)
    matched = np.full((batch, n), np.nan)
    i = np.full(batch, n - 1)
    j = end.astype(np.int64)
    matched[rows, i] = j
    active = i > 0
    while active.any():
        s = step[i[active], rows[active], j[active]]
        i[active] -= STEPS[s, 0]
        j[active] -= STEPS[s, 1]
        matched[rows[active], i[active]] = j[active]
        active = i > 0
    missing = np.isnan(matched)
    if missing.any():  # query rows a (2, 1) step jumped over: halfway between their neighbours
        matched[missing] = 0.5 * (np.roll(matched, 1, 1)[missing] + np.roll(matched, -1, 1)[missing])
    return matched


def warp_frames(query_curves: np.ndarray, reference_curves: np.ndarray, stride: int = 1,
                smoothing: float = 0.0) -> np.ndarray:
    """(B, Tq) fractional reference frames that re-time each reference piece onto its query.

    ``stride`` > 1 matches every stride-th frame (cheaper by stride^2) and interpolates between.
    ``smoothing`` > 0: the warp is Gaussian-smoothed (sigma in frames). A DTW path changes speed
    between 0.5x and 2x from one step to the next; played as it is, every change is a jolt of
    the whole body, and feet that were still in the clip slide. A smoothed non-decreasing warp
    stays non-decreasing.
    """
    queries, references = query_curves[:, ::stride], reference_curves[:, ::stride]
    matched = subsequence_dtw(queries, references) * stride  # (B, Nc) at query frames 0, s, 2s...
    position = np.arange(query_curves.shape[1]) / stride
    lower = np.minimum(position.astype(int), matched.shape[1] - 1)
    upper = np.minimum(lower + 1, matched.shape[1] - 1)
    frac = position - lower
    slope = np.where(upper > lower, matched[:, upper] - matched[:, lower], stride)  # past the last: play on at 1x
    frames = matched[:, lower] + frac * slope
    if smoothing > 0:
        frames = scipy.ndimage.gaussian_filter1d(frames, smoothing, axis=1, mode="nearest")
    return np.clip(frames, 0, reference_curves.shape[1] - 1)
