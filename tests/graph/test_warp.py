"""Tests of choreo_graph.warp.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import numpy as np
import pytest

from choreo_graph.warp import subsequence_dtw, warp_frames

STEP_LIST = ((1, 1), (1, 2), (2, 1))  # (query, reference) advances, in librosa's tie order


# -- the warper: a literal dynamic programme and a search over every path --------------------------
def literal_dtw(query, reference):
    """Subsequence DTW cell by cell in float32 (librosa's recursion: free start and end in the
    reference, first step in STEP_LIST order wins a tie, first minimum of the last row ends)."""
    q, r = np.asarray(query, np.float32), np.asarray(reference, np.float32)
    n, m = len(q), len(r)
    total = np.full((n, m), np.inf, np.float32)
    step = np.zeros((n, m), int)
    for j in range(m):
        total[0, j] = abs(q[0] - r[j])
    for i in range(1, n):
        for j in range(m):
            best, which = np.float32(np.inf), 0
            for k, (di, dj) in enumerate(STEP_LIST):
                if i - di >= 0 and j - dj >= 0 and total[i - di, j - dj] < best:
                    best, which = total[i - di, j - dj], k
            total[i, j] = np.float32(abs(q[i] - r[j])) + best
            step[i, j] = which
    j = int(np.argmin(total[-1]))
    i = n - 1
    matched = [None] * n
    matched[i] = j
    while i > 0:
        di, dj = STEP_LIST[step[i, j]]
        i, j = i - di, j - dj
        matched[i] = j
    for row in range(n):  # a (2, 1) step skips a query row: halfway between its neighbours
        if matched[row] is None:
            matched[row] = 0.5 * (matched[row - 1] + matched[row + 1])
    return np.array(matched, float), float(total[-1].min())


def all_path_costs(query, reference):
    """The cost of every path from the first query row (any reference frame) to the last."""
    n, m = len(query), len(reference)
    cost = lambda i, j: abs(float(query[i]) - float(reference[j]))  # noqa: E731
    found = []

    def walk(i, j, so_far, cells):
        if i == n - 1:
            found.append((so_far, cells))
            return
        for di, dj in STEP_LIST:
            if i + di < n and j + dj < m:
                walk(i + di, j + dj, so_far + cost(i + di, j + dj), cells + [(i + di, j + dj)])

    for j in range(m):
        walk(0, j, cost(0, j), [(0, j)])
    return found


@pytest.mark.survivor
def test_subsequence_dtw_is_the_literal_programme_on_ties_and_on_random_curves():
    rng = np.random.default_rng(0)
    ties_q, ties_r = rng.integers(0, 3, (12, 9)), rng.integers(0, 3, (12, 17))  # small integers: many ties
    smooth_q, smooth_r = rng.random((6, 11)), rng.random((6, 23))
    for queries, references in ((ties_q, ties_r), (smooth_q, smooth_r)):
        ours = subsequence_dtw(queries, references)
        assert ours.shape == queries.shape
        for q, r, path in zip(queries, references, ours):
            np.testing.assert_array_equal(path, literal_dtw(q, r)[0])


@pytest.mark.survivor
def test_subsequence_dtw_takes_a_cheapest_of_all_paths():
    rng = np.random.default_rng(3)
    queries, references = rng.random((8, 6)).round(2), rng.random((8, 8)).round(2)
    for q, r, path in zip(queries, references, subsequence_dtw(queries, references)):
        paths = all_path_costs(q, r)
        cheapest = min(c for c, _ in paths)
        cells = [(i, int(j)) for i, j in enumerate(path) if j == int(j)]  # rows a (2, 1) step visited
        assert any(c_ == cells for _, c_ in paths)  # a path the three steps allow, end to end
        assert sum(abs(q[i] - r[j]) for i, j in cells) == pytest.approx(cheapest, abs=1e-5)
        skipped = [i for i, j in enumerate(path) if j != int(j)]
        for i in skipped:
            assert path[i] == 0.5 * (path[i - 1] + path[i + 1])


@pytest.mark.survivor
def test_subsequence_dtw_hand_cases():
    # the query is the reference's 3..6 played straight: matched frame by frame
    reference = np.array([9.0, 9, 9, 0, 1, 2, 3, 9, 9])
    np.testing.assert_array_equal(subsequence_dtw(np.array([[0.0, 1, 2, 3]]), reference[None])[0], [3, 4, 5, 6])
    # the query plays it at half speed: (2, 1) steps, the rows between halfway
    slow = subsequence_dtw(np.array([[0.0, 0.5, 1, 1.5, 2, 2.5, 3]]), reference[None])[0]
    np.testing.assert_array_equal(slow, [3, 3.5, 4, 4.5, 5, 5.5, 6])
    # twice as fast: (1, 2) steps
    fast = subsequence_dtw(np.array([[0.0, 2, 4]]), np.array([[9.0, 0, 1, 2, 3, 4, 9]]))[0]
    np.testing.assert_array_equal(fast, [1, 3, 5])
    # a one-frame query: the nearest reference frame, nothing walked back from it
    np.testing.assert_array_equal(subsequence_dtw(np.array([[2.0]]), np.array([[0.0, 1, 2, 3]]))[0], [2])
    # a flat curve: every cell ties; the last row's first finite cell (1, via one (2, 1) step) ends
    np.testing.assert_array_equal(subsequence_dtw(np.zeros((1, 3)), np.zeros((1, 5)))[0], [0, 0.5, 1])


def literal_warp(query, reference, stride, smoothing=0.0):
    """warp_frames one pair at a time: DTW on every stride-th frame, the path read at each
    query frame by linear interpolation (past the last matched frame: on at 1x), a literal
    edge-held Gaussian, clamped to the reference."""
    matched = literal_dtw(query[::stride], reference[::stride])[0] * stride
    last = len(matched) - 1
    frames = []
    for f in range(len(query)):
        position = f / stride
        lower = min(int(position), last)
        upper = min(lower + 1, last)
        slope = matched[upper] - matched[lower] if upper > lower else stride
        frames.append(matched[lower] + (position - lower) * slope)
    frames = np.array(frames)
    if smoothing > 0:
        radius = int(4.0 * smoothing + 0.5)
        kernel = np.exp(-0.5 * (np.arange(-radius, radius + 1) / smoothing) ** 2)
        kernel /= kernel.sum()
        padded = np.concatenate([np.full(radius, frames[0]), frames, np.full(radius, frames[-1])])
        frames = np.array([padded[f : f + 2 * radius + 1] @ kernel for f in range(len(frames))])
    return np.minimum(np.maximum(frames, 0), len(reference) - 1)


@pytest.mark.survivor
@pytest.mark.parametrize("stride, smoothing", [(1, 0.0), (2, 0.0), (3, 0.0), (2, 1.5), (1, 0.7)])
def test_warp_frames_is_the_literal_warp(stride, smoothing):
    rng = np.random.default_rng(stride)
    queries, references = rng.random((4, 21)), rng.random((4, 31))  # odd lengths: the last frame extrapolates
    ours = warp_frames(queries, references, stride, smoothing)
    assert ours.shape == (4, 21)
    for q, r, frames in zip(queries, references, ours):
        np.testing.assert_allclose(frames, literal_warp(q, r, stride, smoothing), atol=1e-9)


@pytest.mark.survivor
def test_warp_frames_clamps_to_the_reference():
    # every 2nd frame: the query's 0, 1, 2 match the reference's 4, (halfway), 6 at half speed;
    # the last query frame, past the last matched one, plays on at 1x to 7: clamped to frame 6
    reference = np.array([[5.0, 5, 5, 5, 0, 1, 2]])
    frames = warp_frames(np.array([[0.0, 0.5, 1, 1.5, 2, 2.5]]), reference, stride=2)[0]
    np.testing.assert_array_equal(frames, [4, 4.5, 5, 5.5, 6, 6])
    assert warp_frames(np.array([[0.0, 1, 2]]), np.array([[0.0, 1, 2]]), stride=2)[0].tolist() == [0, 1, 2]
    # the strided path takes a (1, 2) step (0 -> 4); the query frame after it plays on at 1x, not at 2x
    frames = warp_frames(np.array([[0.0, 0.5, 1, 1.5]]), np.array([[0.0, 5, 9, 5, 1, 5, 9, 9, 9]]), stride=2)[0]
    np.testing.assert_array_equal(frames, [0, 2, 4, 5])


@pytest.mark.survivor
def test_warp_frames_matches_every_frame_unless_told():
    rng = np.random.default_rng(8)
    queries, references = rng.random((3, 9)), rng.random((3, 20))
    ours = warp_frames(queries, references)
    for q, r, frames in zip(queries, references, ours):
        np.testing.assert_array_equal(frames, literal_warp(q, r, 1))


@pytest.mark.survivor
def test_a_query_too_long_for_its_reference_is_a_clear_error():
    """No monotone path of slopes 1/2 to 2 fits 6 query frames into 2 reference frames."""
    with pytest.raises(ValueError, match="no path through 2 reference frames"):
        subsequence_dtw(np.zeros((1, 6)), np.zeros((1, 2)))
    assert subsequence_dtw(np.zeros((1, 3)), np.zeros((1, 2))).shape == (1, 3)  # 3 into 2 still fits
