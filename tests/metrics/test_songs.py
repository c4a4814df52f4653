"""choreo.metrics.songs: the whole-song protocol's library part."""

import numpy as np

from choreo.metrics.songs import COLUMNS, mean_rows, target_failures, window_fids
from choreo.metrics.fid import motion_features


def row(**changes) -> dict:
    base = {"pace": 0.5, "reach": 3.0, "planted": 0.4, "foot_root": 0.3, "jerk": 70.0, "beat_dip": 0.35}
    return {**base, **changes}


def test_a_run_misses_exactly_the_targets_its_songs_miss():
    songs = {"C": {"genre": "cha-cha", "real": row(), "seeds": [row(pace=0.7), row(pace=0.7)]},
             "R": {"genre": "rumba", "real": row(), "seeds": [row(foot_root=0.45)]},
             "W": {"genre": "waltz", "real": row(), "seeds": [row(jerk=100.0)]}}
    misses = target_failures(songs)
    assert misses == ["C pace: 0.700 (real 0.500)", "R foot_root: 0.450 (real 0.300)"]  # waltz's jerk mark: 1.5 x Latin


def test_mean_rows_leave_a_column_no_row_has_as_nan():
    mean = mean_rows([{"pace": 1.0}, {"pace": 3.0, "reach": 2.0}])
    assert mean["pace"] == 2.0 and mean["reach"] == 2.0 and np.isnan(mean["ankle_lift"]) and set(mean) == set(COLUMNS)


def test_window_fids_of_the_reference_itself_are_near_zero_and_grow_with_a_change():
    rng = np.random.default_rng(0)
    dances = [np.cumsum(rng.normal(0, 0.01, (450, 24, 3)), axis=0) for _ in range(6)]
    windows = [d[s:s + 150] for d in dances for s in range(0, 301, 75)]
    features = [motion_features(w) for w in windows]
    reference = (np.stack([k for k, _ in features]), np.stack([g for _, g in features]))
    same = window_fids(dances, reference)
    moved = window_fids([d * 3.0 for d in dances], reference)
    assert same["windows"] == len(windows)
    assert same["fid_k"][0] < 1e-6 and moved["fid_k"][0] > 1.0
    assert same["fid_k"][1] <= same["fid_k"][2]
