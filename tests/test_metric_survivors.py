"""Metric values at the places the second mutation run of ``choreo/metrics`` showed unguarded.

Each test pins a value by an independent computation (a literal loop, a closed form, a hand-made
case) or a warning by its category and exact text; none checks where a warning points (mutmut's
trampoline adds a frame), so the names here avoid the area's ``with_a_warning`` skip.
"""

import contextlib
import warnings

import numpy as np
import pytest
import scipy.linalg

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
    motion_features,
    normalise_by_reference,
    prepare_positions,
    tempo_salience,
)
from choreo.metrics import genre
from choreo.metrics import geometric as geo
from choreo.metrics.beats import motion_beat_train
from choreo.metrics.evaluate import _mean_of, score_dance
from choreo.metrics.pfc import to_z_up
from choreo.metrics.reference_loops import random_dances
from choreo.motion import Motion
from tests.test_metric_edges import pulsing_positions


@contextlib.contextmanager
def no_warnings():
    """Any warning, a floating-point RuntimeWarning included, fails the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


# --------------------------------------------------------------------------------------- beats


def literal_salience(positions: np.ndarray, fps: float, bpm: float) -> float:
    """Normalised linear autocorrelation of the beat train by a plain loop, read by hand-written
    linear interpolation at one and two periods; 0 when two periods do not fit."""
    train = motion_beat_train(positions)
    train = train - train.mean()
    period = 60.0 * fps / bpm
    lags = int(2 * period) + 2
    ac = [sum(train[i] * train[i + k] for i in range(len(train) - k)) for k in range(lags)]
    ac = [value / ac[0] for value in ac]
    values = []
    for m in (1, 2):
        lag = m * period
        low = int(np.floor(lag))
        frac = lag - low
        values.append(ac[low] if frac == 0 else ac[low] * (1 - frac) + ac[low + 1] * frac)
    return max(values)


def test_beat_autocorrelation_of_an_odd_length_dance_is_the_literal_one():
    positions = pulsing_positions(201, 23.0)  # odd: a 3n-point FFT would not round-trip
    train = motion_beat_train(positions)
    train = train - train.mean()
    literal = np.array([sum(train[i] * train[i + k] for i in range(len(train) - k)) for k in range(70)])
    np.testing.assert_allclose(beat_autocorrelation(positions, 69), literal / literal[0], atol=1e-9)


def test_tempo_salience_below_one_bpm_and_just_past_four_periods():
    slow = pulsing_positions(600, 120.0)  # fps 1, 0.5 bpm: a period of 120 frames, five of them
    expected = literal_salience(slow, 1.0, 0.5)
    assert expected > 0.5
    assert tempo_salience(slow, 1.0, 0.5) == pytest.approx(expected, abs=1e-9)
    short = pulsing_positions(121, 30.0)  # one frame more than four periods at 60 bpm, 30 fps
    expected = literal_salience(short, 30.0, 60.0)
    assert expected > 0.3
    assert tempo_salience(short, 30.0, 60.0) == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("music, dance", [([], [10]), ([10], []), ([], [])])
def test_beat_align_refusal_text_and_value(music, dance):
    with pytest.warns(MetricWarning, match="^BeatAlign: no music beats or no motion beats; scoring 0$"):
        assert beat_align_score(np.array(music), np.array(dance)) == 0.0


@pytest.mark.parametrize("music, dance", [([], [10, 20]), ([10, 20], []), ([], [])])
def test_beat_distance_refusal_text_and_values(music, dance):
    with pytest.warns(MetricWarning, match="^beat distances: no music beats or no motion beats; returning NaN$") as record:
        distances = beat_distances(np.array(music), np.array(dance))
    assert [w.category for w in record] == [MetricWarning]
    assert isinstance(distances, tuple) and len(distances) == 2 and np.isnan(distances[0]) and np.isnan(distances[1])


def test_beat_distances_with_a_single_beat_on_either_side():
    with no_warnings():
        # one music beat: motion beats 14, 30 are 4 and 20 away; the music beat is 4 from 14
        assert beat_distances(np.array([10]), np.array([14, 30])) == pytest.approx(((16 + 400) / 2, 16))
        # one motion beat: it is 4 from music beat 10; music beats 10, 20 are 4 and 6 from it
        assert beat_distances(np.array([10, 20]), np.array([14])) == pytest.approx((16, (16 + 36) / 2))


# ----------------------------------------------------------------------------------------- PFC


def z_up_of(y_up: np.ndarray) -> np.ndarray:
    """Y up to Z up by +90 degrees about x: (x, y, z) -> (x, -z, y)."""
    return np.stack([y_up[..., 0], -y_up[..., 2], y_up[..., 1]], axis=-1)


def literal_pfc_z_up(z_up: np.ndarray) -> float:
    """EDGE's PFC term as a plain loop over frames on Z-up data (x, y horizontal), float64."""
    z_up = np.asarray(z_up, dtype=np.float64)
    dt = 1 / 30
    root = z_up[:, 0]
    accelerations = []
    for t in range(1, len(root) - 1):
        a = ((root[t + 1] - root[t]) / dt - (root[t] - root[t - 1]) / dt) / dt
        a[2] = max(a[2], 0.0)
        accelerations.append(float(np.sqrt(a @ a)))
    peak = max(accelerations)
    if peak == 0:
        return 0.0
    total = 0.0
    for t in range(1, len(root) - 1):
        slides = []
        for ankle, toe in ((7, 10), (8, 11)):
            slides.append(min(np.hypot(*(z_up[t + 1, j, :2] - z_up[t, j, :2])) for j in (ankle, toe)))
        total += slides[0] * slides[1] * accelerations[t - 1] / peak
    return total / (len(root) - 2)


def sliding_body(frames: int, root_x) -> np.ndarray:
    """Y-up rest pose whose joints all follow ``root_x`` along x (feet slide with the root)."""
    positions = np.repeat(Motion.rest(1).joint_positions(), frames, axis=0)
    positions[..., 0] += np.asarray(root_x)[:, None]
    return positions


def test_pfc_on_exactly_three_frames_is_scored():
    positions = sliding_body(3, [0.0, 0.1, 0.3])  # one acceleration, so it is its own peak
    with no_warnings():
        # one frame: each foot's smaller slide is 0.2 m, times an acceleration at its peak (1)
        assert foot_contact_score(positions) == pytest.approx(0.2 * 0.2, rel=1e-12)


@pytest.mark.parametrize("frames", [0, 1, 2])
def test_pfc_refusal_text_and_value(frames):
    with pytest.warns(MetricWarning, match="^PFC needs at least 3 frames; returning NaN$") as record:
        value = foot_contact_score(sliding_body(3, [0.0, 0.1, 0.3])[:frames])
    assert [w.category for w in record] == [MetricWarning] and np.isnan(value)


def test_pfc_is_zero_when_the_root_never_accelerates_upward_or_sideways():
    t = np.arange(12.0)
    steady = sliding_body(12, 0.25 * t)  # constant velocity, exact in binary: no acceleration at all
    falling = sliding_body(12, 0.25 * t)
    falling[:, 0, 1] -= 0.0625 * t**2  # the root accelerates downward only, clamped to 0
    with no_warnings():
        assert foot_contact_score(steady) == 0.0
        assert foot_contact_score(falling) == 0.0


def test_pfc_with_a_gentle_root_acceleration_below_one():
    t = np.arange(30.0)
    positions = sliding_body(30, 1e-4 * np.sin(t / 3))  # peak acceleration about 0.1 m/s^2
    assert 0 < np.abs(np.diff(positions[:, 0, 0], 2)).max() * 900 < 1
    assert foot_contact_score(positions) == pytest.approx(literal_pfc_z_up(z_up_of(positions)), rel=1e-9)
    assert foot_contact_score(positions) > 0


def test_pfc_of_float32_positions_is_computed_in_float64():
    rng = np.random.default_rng(7)
    z_up = (np.repeat(Motion.rest(1).joint_positions(), 25, axis=0) + rng.normal(scale=0.05, size=(25, 24, 3))).astype(np.float32)
    assert foot_contact_score(z_up, up_axis="z") == pytest.approx(literal_pfc_z_up(z_up), rel=1e-12)


def test_to_z_up_turns_y_up_by_default():
    positions = np.arange(24.0).reshape(2, 4, 3)
    np.testing.assert_array_equal(to_z_up(positions), z_up_of(positions))
    np.testing.assert_array_equal(to_z_up(positions, "z"), positions)


def test_unknown_up_axis_is_refused_by_name():
    with pytest.raises(ValueError, match="^up axis must be 'y' or 'z', got 'x'$"):
        foot_contact_score(sliding_body(3, [0.0, 0.1, 0.3]), up_axis="x")


# ----------------------------------------------------------------------------------------- FID


def test_prepare_positions_works_in_float64():
    rng = np.random.default_rng(2)
    positions = rng.uniform(-3, 3, size=(5, 24, 3)).astype(np.float32)
    wide = positions.astype(np.float64)
    expected = wide - wide[0, 0]  # every joint of every frame relative to the frame-0 root
    np.testing.assert_array_equal(prepare_positions(positions), expected)


def test_normalise_by_reference_per_dimension_by_hand():
    reference = np.array([[0.0, 10.0, 5.0], [2.0, 30.0, 5.0]])  # means 1, 20, 5; population stds 1, 10, 0
    generated = np.array([[1.0, 40.0, 5.5], [3.0, 0.0, 4.0]])
    gen, ref = normalise_by_reference(generated, reference)
    np.testing.assert_allclose(gen[:, :2], [[0.0, 2.0], [2.0, -2.0]], rtol=1e-9)
    np.testing.assert_allclose(ref[:, :2], [[-1.0, -1.0], [1.0, 1.0]], rtol=1e-9)
    # a constant reference dimension is divided by the epsilon alone, 1e-10
    np.testing.assert_allclose(gen[:, 2], [0.5e10, -1e10], rtol=1e-12)
    np.testing.assert_array_equal(ref[:, 2], [0.0, 0.0])


def test_fid_with_two_samples_in_one_dimension_is_the_closed_form():
    a, b = np.array([[0.0], [2.0]]), np.array([[1.0], [5.0]])
    with no_warnings():
        # (1 - 3)^2 + var 2 + var 8 - 2 sqrt(2 * 8)
        assert frechet_distance(a, b) == pytest.approx(4 + 2 + 8 - 2 * 4, rel=1e-12)


@pytest.mark.parametrize("sizes", [(1, 5), (5, 1), (1, 1), (0, 3)])
def test_fid_refusal_text_and_value(sizes):
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(sizes[0], 2)), rng.normal(size=(sizes[1], 2))
    with pytest.warns(MetricWarning, match="^FID needs at least 2 samples per set; returning NaN$") as record:
        value = frechet_distance(a, b)
    assert [w.category for w in record] == [MetricWarning] and np.isnan(value)


def test_fid_warns_at_exactly_as_many_samples_as_dimensions():
    a = np.array([[0.0, 0.0], [1.0, 2.0]])
    b = np.array([[1.0, 1.0], [2.0, 0.0]])
    message = "^FID with 2 samples for 2 feature dimensions: covariances are singular, the value is unreliable$"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        with pytest.warns(MetricWarning, match=message) as record:
            frechet_distance(a, b)
    assert MetricWarning in [w.category for w in record]


def offset_fid(a: np.ndarray, b: np.ndarray, offset: float) -> float:
    """FID with both covariances lifted by offset * I inside the square root only, written with
    symmetric eigen-decompositions: tr sqrt(A B) = sum sqrt(eig(A^1/2 B A^1/2))."""
    cov_a, cov_b = np.cov(a, rowvar=False), np.cov(b, rowvar=False)
    lifted_a, lifted_b = cov_a + offset * np.eye(len(cov_a)), cov_b + offset * np.eye(len(cov_b))
    w, v = np.linalg.eigh(lifted_a)
    half = v @ np.diag(np.sqrt(w)) @ v.T
    root_trace = np.sqrt(np.clip(np.linalg.eigvalsh(half @ lifted_b @ half), 0, None)).sum()
    return float(((a.mean(0) - b.mean(0)) ** 2).sum() + np.trace(cov_a) + np.trace(cov_b) - 2 * root_trace)


def test_fid_retries_a_failed_square_root_with_a_small_offset():
    a = np.array([[-3.0, -3.0, 2.0], [0.0, 1.0, 1.0]])
    b = np.array([[1.0, -3.0, 0.0], [-2.0, -1.0, 3.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if np.isfinite(scipy.linalg.sqrtm(np.cov(a, rowvar=False) @ np.cov(b, rowvar=False))).all():
            pytest.skip("this scipy's sqrtm does not fail on this product; the retry is not reached")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.warns(MetricWarning, match="^FID with 2 samples for 3 feature dimensions"):
            value = frechet_distance(a, b)
    # exactly 2 + 13 + 11 - 2 * 2 = 22 without the offset; 1e-5 on the diagonals lowers it by ~2.6e-4
    assert value == pytest.approx(offset_fid(a, b, 1e-5), abs=1e-8)
    assert value == pytest.approx(22.0 - 2.595756e-4, abs=1e-9)


@pytest.mark.parametrize("count", [0, 1])
def test_diversity_refusal_text_and_value(count):
    with pytest.warns(MetricWarning, match="^diversity needs at least 2 samples; returning NaN$") as record:
        value = diversity(np.ones((count, 4)))
    assert [w.category for w in record] == [MetricWarning] and np.isnan(value)


# ----------------------------------------------------------------------------------- geometric


def two_frames(now: dict, before: dict | None = None) -> np.ndarray:
    """(2, 24, 3): every joint at the origin except those named (joint name -> position)."""
    positions = np.zeros((2, 24, 3))
    for frame, joints in ((0, before or {}), (1, now)):
        for name, value in joints.items():
            positions[frame, geo.J[name]] = value
    return positions


def exact_step(threshold: float) -> float:
    """The float d for which d / GEOMETRIC_FRAME_TIME is exactly ``threshold``."""
    d = threshold * geo.GEOMETRIC_FRAME_TIME
    for _ in range(64):
        q = d / geo.GEOMETRIC_FRAME_TIME
        if q == threshold:
            return d
        d = np.nextafter(d, -np.inf if q > threshold else np.inf)
    raise AssertionError("no exact step found")


def relation(function, positions, *args) -> bool:
    with no_warnings():
        (answer,) = function(geo._Frames(positions), *args)
    return bool(answer)


def test_fast_is_strict_and_measures_displacement():
    threshold = 2.5 * geo.HUMERUS
    d = exact_step(threshold)
    assert not relation(geo._fast, two_frames({"rwrist": [d, 0, 0]}), "rwrist", threshold)
    assert relation(geo._fast, two_frames({"rwrist": [np.nextafter(d, 1), 0, 0]}), "rwrist", threshold)
    held = two_frames({"rwrist": [5.0, 0, 0]}, {"rwrist": [5.0, 0, 0]})  # far from the origin, still
    assert not relation(geo._fast, held, "rwrist", threshold)


def test_plane_distance_is_divided_by_the_normal_length_and_strict():
    threshold = 0.38 * geo.HUMERUS
    # normal (c - a) x (b - a) = (2, 0, 0) x (0, 0.25, 0) = (0, 0, 0.5): length 0.5, exact
    joints = {"root": [0, 0, 0], "lhip": [0, 0.25, 0], "ltoes": [2.0, 0, 0]}
    args = ("root", "lhip", "ltoes", "rankle", threshold)
    assert not relation(geo._plane, two_frames({**joints, "rankle": [0, 0, threshold]}), *args)
    assert relation(geo._plane, two_frames({**joints, "rankle": [0, 0, np.nextafter(threshold, 1)]}), *args)
    assert relation(geo._plane, two_frames({**joints, "rankle": [0, 0, 1.5 * threshold]}), *args)
    assert not relation(geo._plane, two_frames({**joints, "rankle": [0, 0, -1.5 * threshold]}), *args)


def test_normal_plane_is_strict():
    threshold = 2.1 * geo.HIP_WIDTH
    joints = {"lhip": [0, 0, 0], "rhip": [0, 0, 0.5], "lankle": [0, 0, 0]}
    args = ("lhip", "rhip", "lankle", "rankle", threshold)
    assert not relation(geo._normal_plane, two_frames({**joints, "rankle": [0, 0, threshold]}), *args)
    assert relation(geo._normal_plane, two_frames({**joints, "rankle": [0, 0, np.nextafter(threshold, 1)]}), *args)


def test_angle_range_is_open_at_both_ends():
    def angle(rshoulder, rwrist, degrees_range):
        return relation(geo._angle, two_frames({"relbow": [0, 0, 0], "rshoulder": rshoulder, "rwrist": rwrist}),
                        "relbow", "rshoulder", "relbow", "rwrist", degrees_range)

    assert not angle([1, 0, 0], [1, 0, 0], (0, 110))  # 0 degrees: not inside (0, 110)
    assert not angle([1, 0, 0], [-1, 0, 0], (25, 180))  # 180 degrees: not inside (25, 180)
    # 60 degrees between vectors of lengths 2 and 0.5 (cos = 0.5 / (2 * 0.5))
    sixty = [0.25, 0.25 * np.sqrt(3), 0]
    assert angle([2.0, 0, 0], sixty, (0, 70)) and angle([2.0, 0, 0], sixty, (50, 110))
    assert not angle([2.0, 0, 0], sixty, (65, 110))


def test_move_is_a_velocity_component_and_strict():
    threshold = 1.4 * geo.HUMERUS
    d = exact_step(threshold)
    # _move(rwrist, root, lwrist, root): lwrist moves relative to rwrist along root - rwrist (length 0.5)
    args = ("rwrist", "root", "lwrist", "root", threshold)
    def moved(step):
        return two_frames({"rwrist": [0, 0, 0], "root": [0.5, 0, 0], "lwrist": [step, 0, 0]}, {"root": [0.5, 0, 0]})

    assert not relation(geo._move, moved(d), *args)
    assert relation(geo._move, moved(np.nextafter(d, 1)), *args)
    assert relation(geo._move, moved(1.5 * d), *args)  # 1.5 x the threshold (0.75 x if multiplied by the length)


def test_normal_move_is_strict():
    threshold = 1.8 * geo.HUMERUS
    d = exact_step(threshold)
    # direction (lhip - neck) x (rhip - neck) = (1, 0, 0) x (0, 0.5, 0) = (0, 0, 0.5)
    body = {"neck": [0, 0, 0], "lhip": [1.0, 0, 0], "rhip": [0, 0.5, 0]}
    args = ("neck", "rhip", "lhip", "rwrist", threshold)
    assert not relation(geo._normal_move, two_frames({**body, "rwrist": [0, 0, d]}, body), *args)
    assert relation(geo._normal_move, two_frames({**body, "rwrist": [0, 0, np.nextafter(d, 1)]}, body), *args)


def test_geometric_features_of_a_collapsed_body_are_silent_and_pinned():
    with no_warnings():
        features = geometric_features(np.zeros((4, 24, 3)))
    expected = np.zeros(32, dtype=np.float32)
    expected[[29, 30]] = 1.0  # wrists 0 m above the lowest joint: above -1.2 humerus lengths
    np.testing.assert_array_equal(features, expected)


def test_degenerate_limbs_divide_silently():
    # Vectors so short that their length underflows to 0 while a dot product with a longer one
    # does not: a nonzero number over 0, which the relations must absorb without a warning.
    tiny = 1e-170
    hl = geo.HUMERUS
    assert relation(geo._plane, two_frames({"lhip": [0, 1e-90, 0], "ltoes": [1e-90, 0, 0], "rankle": [0, 0, 1.0]}),
                    "root", "lhip", "ltoes", "rankle", 0.38 * hl)
    assert relation(geo._normal_plane, two_frames({"rhip": [0, 0, tiny], "rankle": [0, 0, 1.0]}),
                    "lhip", "rhip", "lankle", "rankle", 2.1 * geo.HIP_WIDTH)
    assert not relation(geo._angle, two_frames({"root": [0, tiny, 0]}), "neck", "root", "zero", "y_unit", (70, 110))
    assert relation(geo._move, two_frames({"root": [tiny, 0, 0], "lwrist": [1.0, 0, 0]}),
                    "rwrist", "root", "lwrist", "root", 1.4 * hl)
    assert relation(geo._normal_move, two_frames({"lhip": [1e-90, 0, 0], "rhip": [0, 1e-90, 0], "rwrist": [0, 0, 1.0]}),
                    "neck", "rhip", "lhip", "rwrist", 1.8 * hl)


def test_virtual_up_vectors_point_along_y():
    hl = geo.HUMERUS

    def holds(relation_function, body, *args):
        with no_warnings():
            return geo.__dict__[relation_function](geo._Frames(two_frames(body)), *args).tolist() == [True]

    # the right ankle 1.25 humerus lengths above the lowest joints (y = 0), far out in -x and -z
    assert holds("_normal_plane", {"rankle": [-3.0, 1.25 * hl, -3.0]}, "zero", "y_unit", "y_min", "rankle", 1.2 * hl)
    assert not holds("_normal_plane", {"rankle": [-3.0, 1.15 * hl, -3.0]}, "zero", "y_unit", "y_min", "rankle", 1.2 * hl)
    # the right wrist is the lowest joint (0 above y_min), far out in -x and -z: "not above -1.2 hl" fails
    low_wrist = {"rwrist": [-3.0, -1.25 * hl, -3.0]}
    assert holds("_normal_plane", low_wrist, "zero", "minus_y_unit", "y_min", "rwrist", -1.2 * hl)
    high_wrist = {"rwrist": [3.0, 1.25 * hl, 3.0]}  # 1.25 above the lowest joints
    assert not holds("_normal_plane", high_wrist, "zero", "minus_y_unit", "y_min", "rwrist", -1.2 * hl)
    # the body lying down (spine from neck to root horizontal, along x or z): 90 degrees from y
    for spine in ([1.0, 0, 0], [0, 0, 1.0]):
        assert holds("_angle", {"neck": [0, 0, 0], "root": spine}, "neck", "root", "zero", "y_unit", (70, 110))
    assert not holds("_angle", {"neck": [0, 0.6, 0], "root": [0, 0, 0]}, "neck", "root", "zero", "y_unit", (70, 110))


def test_geometric_features_are_float32_fractions_of_frames():
    # the right wrist moves fast in 1 of 3 frame steps: a third, rounded to float32
    positions = np.zeros((4, 24, 3))
    positions[2:, geo.J["rwrist"], 0] = 1.0  # a 1 m jump between frames 1 and 2
    features = geometric_features(positions)
    assert features[12] == np.float32(1 / 3) and features[12].dtype == np.float32
    np.testing.assert_array_equal(features[[12, 13]], np.array([1 / 3, 0.0], dtype=np.float32))


def test_geometric_features_of_float32_positions_are_computed_in_float64():
    # a float32 step whose speed is just past 2.5 humerus lengths in float64, not in float32
    step = np.float32(0.005350794177502394)
    assert float(step) / geo.GEOMETRIC_FRAME_TIME > 2.5 * geo.HUMERUS
    positions = np.zeros((2, 24, 3), dtype=np.float32)
    positions[1, geo.J["rwrist"], 0] = step
    assert geometric_features(positions)[12] == 1.0


# ------------------------------------------------------------------------------------- kinetic


def test_kinetic_features_of_two_frames_are_silent():
    positions = np.zeros((2, 24, 3))
    positions[1, 5] = [0.5, 0.25, 0.0]  # one step of joint 5: velocity (30, 15, 0) m/s at dt 1/60
    with no_warnings():
        features = kinetic_features(positions)
    assert features[15] == 900.0 and features[16] == 225.0  # joint 5's horizontal and vertical energy
    np.testing.assert_array_equal(np.delete(features.reshape(24, 3)[:, :2], 5, axis=0), 0.0)
    assert np.isnan(features[2::3]).all()  # no acceleration to average: NaN, without a warning


def test_kinetic_features_are_rounded_to_float32():
    positions = np.zeros((6, 24, 3))
    positions[5, 0, 1] = 1 / 60  # joint 0 rises 1/60 m between frames 4 and 5: 1 m/s there
    # frames 1..5 average the differences k in [i-2, i+2] within 1..5: {1-3}, {1-4}, {1-5}, {2-5}, {3-5}
    expected_vertical = (0 + 0 + (1 / 5) ** 2 + (1 / 4) ** 2 + (1 / 3) ** 2) / 5
    features = kinetic_features(positions)
    assert features.dtype == np.float32
    assert features[1] == np.float32(expected_vertical)


# ------------------------------------------------------------------------------------ evaluate


def test_mean_of_skips_missing_and_non_finite_values():
    assert _mean_of([1.0, None, float("nan"), 4.0, float("inf")]) == 2.5
    assert _mean_of(v for v in [None, float("nan")]) is None
    assert _mean_of([]) is None


BEAT_FRAMES = [15, 45, 75, 105]  # speed minima of beating_positions


def beating_positions() -> np.ndarray:
    t = np.arange(120)
    speed = 1.0 + np.cos(2 * np.pi * t / 30)
    x = np.concatenate([[0.0], np.cumsum(speed[:-1])]) * 0.01
    return sliding_body(120, x)


def test_score_dance_fields_by_hand():
    positions = beating_positions()
    assert motion_beats(positions).tolist() == BEAT_FRAMES
    with no_warnings():
        score = score_dance(Dance("clip", positions, np.array([14, 45, 80])), fps=24.0)
    assert score.name == "clip" and score.frames == 120 and score.seconds == 5.0
    assert score.beat_align == pytest.approx((np.exp(-1 / 18) + 1 + np.exp(-25 / 18)) / 3)
    # motion -> music: 15-14, 45-45, 75-80, 105-80; music -> motion: 14-15, 45-45, 80-75
    assert score.motion_to_music == pytest.approx((1 + 0 + 25 + 625) / 4)
    assert score.music_to_motion == pytest.approx((1 + 0 + 25) / 3)
    assert score.pfc == pytest.approx(literal_pfc_z_up(z_up_of(positions)) * 10_000, rel=1e-9)


def literal_diversity(rows: np.ndarray) -> float:
    distances = [np.sqrt(((rows[i] - rows[j]) ** 2).sum()) for i in range(len(rows)) for j in range(i + 1, len(rows))]
    return sum(distances) / len(distances)


def test_evaluate_report_fields_against_literal_numbers():
    dances = random_dances(6, frames=40, seed=11)
    generated = [Dance("g0", dances[0], np.array([5, 20])), Dance("g1", dances[1]), Dance("g2", dances[2], np.array([8]))]
    truth = [Dance("t0", dances[3], np.array([10, 30])), Dance("t1", dances[4]), Dance("t2", dances[5][:30])]
    calls = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        report = evaluate(generated, truth, fps=20.0, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(i, 6) for i in range(1, 7)]
    assert report.fps == 20.0 and report.generated_count == 3 and report.ground_truth_count == 3
    assert report.mean_clip_seconds == pytest.approx(2.0)
    assert [c.name for c in report.clips] == ["g0", "g1", "g2"]
    assert [(c.name, c.frames) for c in report.ground_truth_clips] == [("t0", 40), ("t1", 40), ("t2", 30)]

    def pfc(d):
        return literal_pfc_z_up(z_up_of(d.positions)) * 10_000

    assert report.pfc == pytest.approx(np.mean([pfc(d) for d in generated]), rel=1e-9)
    assert report.ground_truth_pfc == pytest.approx(np.mean([pfc(d) for d in truth]), rel=1e-9)

    def align(d):
        beats = motion_beats(d.positions)
        return np.mean([np.exp(-min((m - b) ** 2 for b in beats) / 18) for m in d.music_beats])

    def squared(queries, references):
        return np.mean([min((q - r) ** 2 for r in references) for q in queries])

    with_music = [d for d in generated if d.music_beats is not None]
    assert report.beat_align == pytest.approx(np.mean([align(d) for d in with_music]))
    assert report.ground_truth_beat_align == pytest.approx(align(truth[0]))
    assert report.motion_to_music == pytest.approx(np.mean([squared(motion_beats(d.positions), d.music_beats) for d in with_music]))
    assert report.music_to_motion == pytest.approx(np.mean([squared(d.music_beats, motion_beats(d.positions)) for d in with_music]))

    features = [motion_features(d.positions) for d in generated + truth]
    for index, (div, truth_div) in enumerate([("div_k", "ground_truth_div_k"), ("div_g", "ground_truth_div_g")]):
        rows = np.array([f[index] for f in features], dtype=np.float64)
        mean = rows[3:].sum(0) / 3
        std = np.sqrt(((rows[3:] - mean) ** 2).sum(0) / 3) + 1e-10
        assert getattr(report, div) == pytest.approx(literal_diversity((rows[:3] - mean) / std), rel=1e-6)
        assert getattr(report, truth_div) == pytest.approx(literal_diversity((rows[3:] - mean) / std), rel=1e-6)


def test_evaluate_without_generated_dances_reports_zero_seconds():
    truth = [Dance(str(i), p) for i, p in enumerate(random_dances(2, frames=30, seed=4))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = evaluate([], truth)
    assert report.mean_clip_seconds == 0.0 and report.generated_count == 0 and report.clips == []
    assert report.fps == 30.0 and [c.seconds for c in report.ground_truth_clips] == [1.0, 1.0]  # 30 frames at 30 fps


# --------------------------------------------------------------------------------------- genre


def reference_fit(features: np.ndarray, labels: list, l2: float = 1e-2):
    """The class-weighted multinomial logistic regression, written in numpy and solved by BFGS."""
    import scipy.optimize

    names = sorted(set(labels))
    y = np.array([names.index(g) for g in labels])
    classes, dims = len(names), features.shape[1]
    mean = features.sum(0) / len(features)
    std = np.sqrt(((features - mean) ** 2).sum(0) / len(features)) + 1e-8
    x = (features - mean) / std
    per_class = len(y) / (classes * np.bincount(y))  # inverse frequency: n / (G * n_c)
    sample_weight = per_class[y] / per_class[y].sum()

    def loss(theta):
        weights, bias = theta[: dims * classes].reshape(dims, classes), theta[dims * classes:]
        z = x @ weights + bias
        z = z - z.max(1, keepdims=True)
        log_p = z - np.log(np.exp(z).sum(1, keepdims=True))
        value = -(sample_weight * log_p[np.arange(len(y)), y]).sum() + l2 * (weights**2).sum()
        residual = np.exp(log_p)
        residual[np.arange(len(y)), y] -= 1
        residual *= sample_weight[:, None]
        return value, np.concatenate([(x.T @ residual + 2 * l2 * weights).ravel(), residual.sum(0)])

    solution = scipy.optimize.minimize(loss, np.zeros(dims * classes + classes), jac=True, method="BFGS",
                                       options={"gtol": 1e-12, "maxiter": 10_000}).x
    return names, mean, std, solution[: dims * classes].reshape(dims, classes), solution[dims * classes:]


def test_genre_classifier_fit_is_the_weighted_logistic_regression(monkeypatch):
    rng = np.random.default_rng(1)
    features = rng.normal(size=(30, 40)) * np.linspace(0.5, 3.0, 40) + np.linspace(-5.0, 5.0, 40)
    labels = ["a"] * 18 + ["b"] * 8 + ["c"] * 4  # unbalanced: the class weights matter
    features[:18, :5] += 0.5
    features[18:26, 5:10] -= 0.5
    features[:, 7] = 2.5  # a constant feature: standardised by the epsilon alone
    monkeypatch.setattr(genre, "clip_features", lambda positions: np.asarray(positions, dtype=np.float64))
    classifier = genre.GenreClassifier.fit(features, labels)
    names, mean, std, weights, bias = reference_fit(features, labels)
    assert classifier.genres == names == ["a", "b", "c"]
    np.testing.assert_allclose(classifier.mean, mean, rtol=1e-12)
    np.testing.assert_allclose(classifier.std, std, rtol=1e-12, atol=0)
    assert classifier.std[7] == 1e-8
    assert classifier.weights.dtype == np.float64 and classifier.bias.dtype == np.float64
    np.testing.assert_allclose(classifier.weights, weights, atol=2e-4)
    np.testing.assert_allclose(classifier.bias, bias, atol=2e-4)
    assert np.abs(bias).max() > 0.1


def test_genre_classifier_predicts_from_standardised_features(monkeypatch):
    monkeypatch.setattr(genre, "clip_features", lambda positions: np.asarray(positions, dtype=np.float64))
    classifier = genre.GenreClassifier(["slow", "fast"], mean=np.array([1.0, 2.0]), std=np.array([2.0, 4.0]),
                                       weights=np.array([[1.0, -1.0], [0.0, 0.0]]), bias=np.array([0.0, 0.5]))
    # x = (f - mean) / std; logits (x0, -x0 + 0.5): "slow" when x0 > 0.25, i.e. f0 > 1.5
    assert classifier.predict(np.array([[1.6, 0.0], [1.4, 0.0], [0.0, 9.0]])) == ["slow", "fast", "fast"]
    # with x multiplied by std instead, f0 = 1.2 would give x0 = 0.4 and "slow"
    assert classifier.predict(np.array([[1.2, 0.0]])) == ["fast"]


# ------------------------------------------------------------------------------- reference loops


def test_random_dances_default_to_150_frames_and_seed_0():
    (dance,) = random_dances(1)
    assert dance.shape == (150, 24, 3)
    rng = np.random.default_rng(0)
    angles = rng.normal(0.0, 0.05, size=(150, 24, 3)).cumsum(axis=0)
    root = rng.normal(0.0, 0.02, size=(150, 3)).cumsum(axis=0) + np.array([0.0, 0.9, 0.0])
    np.testing.assert_allclose(dance, Motion.from_axis_angle(root, angles).joint_positions(), rtol=1e-12, atol=1e-12)


def test_random_dances_are_the_seeded_random_walk():
    dances = random_dances(2, frames=6, seed=5)
    rng = np.random.default_rng(5)
    for dance in dances:
        angles = rng.normal(0.0, 0.05, size=(6, 24, 3)).cumsum(axis=0)
        root = rng.normal(0.0, 0.02, size=(6, 3)).cumsum(axis=0) + np.array([0.0, 0.9, 0.0])
        np.testing.assert_allclose(dance, Motion.from_axis_angle(root, angles).joint_positions(), rtol=1e-12, atol=1e-12)
