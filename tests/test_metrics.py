"""Metrics: values derivable by hand, invariances, and the vectorised features against literal loops."""

import warnings

import numpy as np
import pytest

from choreo.metrics import (
    Dance,
    MetricWarning,
    beat_align_score,
    beat_autocorrelation,
    beat_distances,
    diversity,
    evaluate,
    foot_contact_score,
    frechet_distance,
    geometric_features,
    kinetic_features,
    motion_beats,
    normalise_by_reference,
    salience_at,
    same_pulse,
    tempo_salience,
)
from choreo.metrics.geometric import GEOMETRIC_FRAME_TIME, HIP_WIDTH, HUMERUS, SHOULDER_WIDTH, J
from choreo.metrics.pfc import Y_UP_TO_Z_UP
from choreo.metrics.reference_loops import literal_kinetic, random_dances
from choreo.motion import Motion




def test_vectorised_kinetic_features_equal_the_literal_definition():
    positions = random_dances(1, frames=40)[0]
    positions = positions - positions[:1, :1]
    np.testing.assert_allclose(kinetic_features(positions), literal_kinetic(positions), rtol=2e-5, atol=1e-4)


def literal_geometric_subset(positions):
    """A few relations written out frame by frame, one of each kind."""
    answers = []
    for t in range(1, len(positions)):
        p, q = positions[t], positions[t - 1]
        rows = []
        # f_nmove(neck, rhip, lhip, rwrist, 1.8 hl)
        vel = (p[J["rwrist"]] - p[J["neck"]]) - (q[J["rwrist"]] - q[J["neck"]])
        direction = np.cross(p[J["lhip"]] - p[J["neck"]], p[J["rhip"]] - p[J["neck"]])
        rows.append(vel @ direction / np.linalg.norm(direction) / GEOMETRIC_FRAME_TIME > 1.8 * HUMERUS)
        # f_nplane(lshoulder, rshoulder, lwrist, rwrist, 2.5 sw)
        normal = p[J["rshoulder"]] - p[J["lshoulder"]]
        rows.append(normal @ (p[J["rwrist"]] - p[J["lwrist"]]) / np.linalg.norm(normal) > 2.5 * SHOULDER_WIDTH)
        # f_angle(relbow, rshoulder, relbow, rwrist, [0, 110])
        a, b = p[J["rshoulder"]] - p[J["relbow"]], p[J["rwrist"]] - p[J["relbow"]]
        angle = np.degrees(np.arccos(a @ b / (np.linalg.norm(a) * np.linalg.norm(b))))
        rows.append(0 < angle < 110)
        # f_plane(root, lhip, ltoes, rankle, 0.38 hl)
        cross = np.cross(p[J["ltoes"]] - p[J["root"]], p[J["lhip"]] - p[J["root"]])
        rows.append(cross @ (p[J["rankle"]] - p[J["root"]]) / np.linalg.norm(cross) > 0.38 * HUMERUS)
        # f_nplane(zero, y_unit, y_min, rankle, 1.2 hl)
        rows.append(p[J["rankle"], 1] - p[:, 1].min() > 1.2 * HUMERUS)
        # f_nplane(lhip, rhip, lankle, rankle, 2.1 hw)
        normal = p[J["rhip"]] - p[J["lhip"]]
        rows.append(normal @ (p[J["rankle"]] - p[J["lankle"]]) / np.linalg.norm(normal) > 2.1 * HIP_WIDTH)
        # f_move(rwrist, root, lwrist, root, 1.4 hl): the third joint moves, the fourth is unused
        vel = (p[J["lwrist"]] - p[J["rwrist"]]) - (q[J["lwrist"]] - q[J["rwrist"]])
        direction = p[J["root"]] - p[J["rwrist"]]
        rows.append(vel @ direction / np.linalg.norm(direction) / GEOMETRIC_FRAME_TIME > 1.4 * HUMERUS)
        # f_fast(root, 2.3 hl)
        rows.append(np.linalg.norm(p[0] - q[0]) / GEOMETRIC_FRAME_TIME > 2.3 * HUMERUS)
        answers.append(rows)
    return np.mean(answers, axis=0)


def test_vectorised_geometric_features_equal_literal_relations():
    positions = random_dances(1, frames=60, seed=3)[0] * 3.0  # big swings so relations flip often
    features = geometric_features(positions)
    assert features.shape == (32,)
    np.testing.assert_allclose(features[[0, 8, 6, 14, 16, 18, 10, 31]], literal_geometric_subset(positions), atol=1e-6)


def test_template_body_measures():
    assert HUMERUS == pytest.approx(0.2568, abs=1e-4)
    assert SHOULDER_WIDTH == pytest.approx(0.3908, abs=1e-4)
    assert HIP_WIDTH == pytest.approx(0.1192, abs=1e-4)


def test_motionless_body_has_zero_kinetic_energy():
    still = np.repeat(Motion.rest(1).joint_positions(), 30, axis=0)
    still = still - still[:1, :1]
    features = kinetic_features(still)
    np.testing.assert_allclose(features[0::3], 0, atol=1e-12)
    np.testing.assert_allclose(features[1::3], 0, atol=1e-12)


def test_fid_of_a_set_with_itself_is_zero_and_translation_does_not_change_it():
    generated = random_dances(40, seed=1)
    truth = random_dances(40, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        same = evaluate([Dance(str(i), p) for i, p in enumerate(truth)], [Dance(str(i), p) for i, p in enumerate(truth)])
        # Zero up to sqrtm's round-off on singular covariances (40 samples, 72 dimensions).
        assert abs(same.fid_k) < 1e-4 and abs(same.fid_g) < 1e-4
        base = evaluate([Dance("g", p) for p in generated], [Dance("t", p) for p in truth])
        moved = evaluate([Dance("g", p + [3.0, 0.5, -7.0]) for p in generated], [Dance("t", p) for p in truth])
    assert base.fid_k > 0.1 and np.isfinite(base.fid_k) and np.isfinite(base.fid_g)
    assert moved.fid_k == pytest.approx(base.fid_k, rel=1e-6)
    assert moved.fid_g == pytest.approx(base.fid_g, rel=1e-6)
    assert isinstance(base.fid_k, float)


def test_diversity_of_identical_clips_is_zero():
    assert diversity(np.ones((5, 72))) == 0.0
    points = np.array([[0.0, 0.0], [3.0, 4.0]])
    assert diversity(points) == 5.0


def test_fid_is_finite_with_few_samples_and_warns():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(5, 72)), rng.normal(size=(6, 72))
    a, b = normalise_by_reference(a, b)
    with pytest.warns(MetricWarning, match="singular"):
        value = frechet_distance(a, b)
    assert np.isfinite(value) and isinstance(value, float)


def test_beat_align_is_one_when_speed_minima_sit_on_the_beats():
    beat_every = 15  # frames: a beat every 0.5 s at 30 fps
    frames = np.arange(300)
    # Speed is lowest exactly on the beats: position = integral of a speed with minima there.
    speed = 1.0 - np.cos(2 * np.pi * frames / beat_every) + 0.05
    x = np.concatenate([[0.0], np.cumsum(speed[:-1])]) * 0.01  # p[t+1] - p[t] = speed[t]
    positions = np.zeros((300, 24, 3))
    positions[..., 0] = x[:, None]
    dance_beats = motion_beats(positions)
    music_beats = np.arange(beat_every, 300, beat_every)  # frames 15, 30, ..., 285
    assert beat_align_score(music_beats, dance_beats) == pytest.approx(1.0, abs=1e-3)
    shifted = beat_align_score(music_beats + 7, dance_beats)  # half a beat off: exp(-7^2 / 18) ~ 0.07
    assert shifted < 0.1
    to_music, to_motion = beat_distances(music_beats, dance_beats)
    assert to_motion == pytest.approx(0.0, abs=1e-9) and to_music == pytest.approx(0.0, abs=1e-9)
    assert beat_distances(music_beats + 3, dance_beats) == pytest.approx((9.0, 9.0))


@pytest.mark.parametrize("bpm", [60.0, 90.0, 104.4, 128.0, 144.0])
def test_tempo_salience_is_high_at_the_rate_of_speed_minima_only(bpm):
    frames = np.arange(1800)  # 60 s at 30 fps, speed minima every 60/bpm s: not on whole frames
    speed = 1.05 - np.cos(2 * np.pi * frames * bpm / 60 / 30)
    positions = np.zeros((1800, 24, 3))
    positions[..., 0] = np.cumsum(speed)[:, None] * 0.01
    assert tempo_salience(positions, 30.0, bpm) > 0.5
    assert tempo_salience(positions, 30.0, bpm / 2) > 0.5  # every other beat is a beat too
    assert tempo_salience(positions, 30.0, bpm * 1.3) < 0.2  # another tempo
    assert tempo_salience(positions[:40], 30.0, bpm) == 0.0  # too short for a period
    once = beat_autocorrelation(positions, 200)  # computed once, read at any tempo: the same numbers
    for tempo in (bpm, bpm / 2, bpm * 1.3):
        assert salience_at(once, 30.0, tempo) == pytest.approx(tempo_salience(positions, 30.0, tempo))


def test_same_pulse_counts_half_and_double_time():
    assert same_pulse(120.0, 120.0) and same_pulse(87.0, 174.0) and same_pulse(203.0, 102.0)
    assert same_pulse(124.0, 120.0) and not same_pulse(126.0, 120.0)  # within 4 %, not 5 %
    assert not same_pulse(80.0, 120.0) and not same_pulse(100.0, 0.0)


def test_beat_align_without_beats_warns_and_scores_zero():
    with pytest.warns(MetricWarning):
        assert beat_align_score(np.array([]), np.array([3, 5])) == 0.0


def test_sliding_feet_with_accelerating_root_score_worse_than_planted_feet():
    frames = 90
    t = np.arange(frames) / 30
    base = np.repeat(Motion.rest(1).joint_positions(), frames, axis=0)
    root_path = np.stack([0.5 * np.sin(2 * np.pi * t), 0.05 * np.sin(4 * np.pi * t), np.zeros(frames)], -1)
    planted = base.copy()
    planted[:, [0, 3, 6, 9, 12, 15]] += root_path[:, None]  # the upper body sways, feet stay put
    sliding = base + root_path[:, None]  # everything, feet included, slides with the root
    assert foot_contact_score(planted) == pytest.approx(0.0, abs=1e-12)
    assert foot_contact_score(sliding) > 1e-4


def test_z_up_and_y_up_give_the_same_numbers():
    dances = random_dances(6, seed=5)
    z_up = [p @ Y_UP_TO_Z_UP.T for p in dances]
    for y, z in zip(dances, z_up):
        assert foot_contact_score(y, up_axis="y") == pytest.approx(foot_contact_score(z, up_axis="z"), rel=1e-9)
        np.testing.assert_array_equal(motion_beats(y), motion_beats(z))


def test_genre_classifier_tells_fast_from_slow_dances():
    from choreo.metrics.genre import GenreClassifier

    rng = np.random.default_rng(0)
    t = np.arange(150) / 30
    body = rng.normal(size=(1, 24, 3)) * 0.3

    def dance(speed):
        positions = np.tile(body, (150, 1, 1))
        positions[:, 20:22, 1] += 0.4 * np.sin(2 * np.pi * speed * t + rng.uniform(0, 6))[:, None]
        return positions + rng.normal(scale=0.01, size=positions.shape)

    train = [dance(0.5) for _ in range(30)] + [dance(3.0) for _ in range(10)]
    labels = ["slow"] * 30 + ["fast"] * 10
    classifier = GenreClassifier.fit(train, labels)
    assert classifier.agreement([dance(0.5) for _ in range(5)] + [dance(3.0) for _ in range(5)],
                                ["slow"] * 5 + ["fast"] * 5) >= 0.9
    assert classifier.agreement([dance(3.0)], ["slow"]) == 0.0
