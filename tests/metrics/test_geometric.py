"""Tests of choreo.metrics.geometric.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""


import numpy as np
import pytest

from choreo.metrics import geometric as geo
from choreo.metrics import (
    geometric_features,
)
from choreo.metrics.geometric import GEOMETRIC_FRAME_TIME, HIP_WIDTH, HUMERUS, SHOULDER_WIDTH, J
from choreo.metrics.reference_loops import random_dances
from tests.metrics.helpers import no_warnings


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


@pytest.mark.survivor
def test_fast_is_strict_and_measures_displacement():
    threshold = 2.5 * geo.HUMERUS
    d = exact_step(threshold)
    assert not relation(geo._fast, two_frames({"rwrist": [d, 0, 0]}), "rwrist", threshold)
    assert relation(geo._fast, two_frames({"rwrist": [np.nextafter(d, 1), 0, 0]}), "rwrist", threshold)
    held = two_frames({"rwrist": [5.0, 0, 0]}, {"rwrist": [5.0, 0, 0]})  # far from the origin, still
    assert not relation(geo._fast, held, "rwrist", threshold)


@pytest.mark.survivor
def test_plane_distance_is_divided_by_the_normal_length_and_strict():
    threshold = 0.38 * geo.HUMERUS
    # normal (c - a) x (b - a) = (2, 0, 0) x (0, 0.25, 0) = (0, 0, 0.5): length 0.5, exact
    joints = {"root": [0, 0, 0], "lhip": [0, 0.25, 0], "ltoes": [2.0, 0, 0]}
    args = ("root", "lhip", "ltoes", "rankle", threshold)
    assert not relation(geo._plane, two_frames({**joints, "rankle": [0, 0, threshold]}), *args)
    assert relation(geo._plane, two_frames({**joints, "rankle": [0, 0, np.nextafter(threshold, 1)]}), *args)
    assert relation(geo._plane, two_frames({**joints, "rankle": [0, 0, 1.5 * threshold]}), *args)
    assert not relation(geo._plane, two_frames({**joints, "rankle": [0, 0, -1.5 * threshold]}), *args)


@pytest.mark.survivor
def test_normal_plane_is_strict():
    threshold = 2.1 * geo.HIP_WIDTH
    joints = {"lhip": [0, 0, 0], "rhip": [0, 0, 0.5], "lankle": [0, 0, 0]}
    args = ("lhip", "rhip", "lankle", "rankle", threshold)
    assert not relation(geo._normal_plane, two_frames({**joints, "rankle": [0, 0, threshold]}), *args)
    assert relation(geo._normal_plane, two_frames({**joints, "rankle": [0, 0, np.nextafter(threshold, 1)]}), *args)


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
def test_normal_move_is_strict():
    threshold = 1.8 * geo.HUMERUS
    d = exact_step(threshold)
    # direction (lhip - neck) x (rhip - neck) = (1, 0, 0) x (0, 0.5, 0) = (0, 0, 0.5)
    body = {"neck": [0, 0, 0], "lhip": [1.0, 0, 0], "rhip": [0, 0.5, 0]}
    args = ("neck", "rhip", "lhip", "rwrist", threshold)
    assert not relation(geo._normal_move, two_frames({**body, "rwrist": [0, 0, d]}, body), *args)
    assert relation(geo._normal_move, two_frames({**body, "rwrist": [0, 0, np.nextafter(d, 1)]}, body), *args)


@pytest.mark.survivor
def test_geometric_features_of_a_collapsed_body_are_silent_and_pinned():
    with no_warnings():
        features = geometric_features(np.zeros((4, 24, 3)))
    expected = np.zeros(32, dtype=np.float32)
    expected[[29, 30]] = 1.0  # wrists 0 m above the lowest joint: above -1.2 humerus lengths
    np.testing.assert_array_equal(features, expected)


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
def test_geometric_features_are_float32_fractions_of_frames():
    # the right wrist moves fast in 1 of 3 frame steps: a third, rounded to float32
    positions = np.zeros((4, 24, 3))
    positions[2:, geo.J["rwrist"], 0] = 1.0  # a 1 m jump between frames 1 and 2
    features = geometric_features(positions)
    assert features[12] == np.float32(1 / 3) and features[12].dtype == np.float32
    np.testing.assert_array_equal(features[[12, 13]], np.array([1 / 3, 0.0], dtype=np.float32))


@pytest.mark.survivor
def test_geometric_features_of_float32_positions_are_computed_in_float64():
    # a float32 step whose speed is just past 2.5 humerus lengths in float64, not in float32
    step = np.float32(0.005350794177502394)
    assert float(step) / geo.GEOMETRIC_FRAME_TIME > 2.5 * geo.HUMERUS
    positions = np.zeros((2, 24, 3), dtype=np.float32)
    positions[1, geo.J["rwrist"], 0] = step
    assert geometric_features(positions)[12] == 1.0
