"""Training augmentation: mirror images, paces and rhythm channels, against hand-made answers."""


import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.motion import (
    Motion,
    mirrored,
    stretched,
    turned,
)
from choreo.motion.augment import mirror_joint_order
from choreo.music import BEAT_COLUMN, FEATURE_DIM, PEAK_COLUMN, beat_phase, rhythm_channels, stretch_features
from choreo.skeleton import SMPL24
from tests.motion.helpers import counting_motion, exactly


def symmetric_smpl():
    """SMPL-24 with each left offset the exact mirror of its right twin (the template is off by mm)."""
    order = mirror_joint_order(SMPL24.names)
    offsets = SMPL24.offsets.copy()
    for j, twin in enumerate(order):
        if SMPL24.names[j].startswith("l_"):
            offsets[j] = SMPL24.offsets[twin] * np.array([-1.0, 1.0, 1.0])
        elif twin == j:
            offsets[j, 0] = 0.0
    return SMPL24.with_offsets(offsets)


def random_motion(frames=12, seed=0, skeleton=SMPL24):
    rng = np.random.default_rng(seed)
    return Motion(rng.normal(size=(frames, 3)), rng.normal(size=(frames, 24, 4)), skeleton=skeleton)


def test_mirror_joint_order_swaps_sides_and_keeps_the_spine():
    order = mirror_joint_order(SMPL24.names)
    names = SMPL24.names
    assert names[order[names.index("l_wrist")]] == "r_wrist"
    assert names[order[names.index("r_knee")]] == "l_knee"
    assert order[names.index("head")] == names.index("head")
    assert sorted(order) == list(range(24))


def test_mirrored_positions_are_the_reflection_on_a_symmetric_body():
    motion = random_motion(skeleton=symmetric_smpl())
    reflected = motion.joint_positions() * np.array([-1.0, 1.0, 1.0])
    order = mirror_joint_order(SMPL24.names)
    np.testing.assert_allclose(mirrored(motion).joint_positions()[:, order], reflected, atol=1e-9)


def test_mirroring_twice_gives_the_dance_back():
    motion = random_motion()
    twice = mirrored(mirrored(motion))
    np.testing.assert_allclose(twice.joint_positions(), motion.joint_positions(), atol=1e-9)


def test_stretched_reads_source_frames_at_the_pace():
    motion = random_motion(frames=31)
    fast = stretched(motion, 1.5)
    assert fast.num_frames == 21  # frames 0, 1.5, ..., 30
    np.testing.assert_allclose(fast.root_positions[2], motion.root_positions[3])
    np.testing.assert_allclose(fast.root_positions[1], (motion.root_positions[1] + motion.root_positions[2]) / 2)
    assert stretched(motion, 0.5).num_frames == 61


def test_beat_phase_is_linear_between_beats_and_continues_the_grid_outside():
    phase = beat_phase(np.array([10, 20, 30]), 40)
    assert phase[10] == 0 and phase[15] == pytest.approx(0.5) and phase[29] == pytest.approx(0.9)
    assert phase[5] == pytest.approx(0.5)  # five frames before the first beat of a 10-frame grid
    assert phase[37] == pytest.approx(0.7)
    assert beat_phase(np.array([4]), 40) is None


def test_rhythm_channels_give_phase_and_log_tempo():
    features = np.zeros((60, FEATURE_DIM), np.float32)
    features[[0, 15, 30, 45], BEAT_COLUMN] = 1.0  # 15 frames at 30 fps: 120 bpm
    channels = rhythm_channels(features)
    np.testing.assert_allclose(channels[15, :2], [0.0, 1.0], atol=1e-6)
    np.testing.assert_allclose(channels[22, :2], [np.sin(2 * np.pi * 7 / 15), np.cos(2 * np.pi * 7 / 15)], atol=1e-6)
    np.testing.assert_allclose(channels[:, 2], 0.0, atol=1e-6)
    features[:, BEAT_COLUMN] = 0
    features[[0, 10, 20], BEAT_COLUMN] = 1.0  # 180 bpm
    assert rhythm_channels(features)[0, 2] == pytest.approx(np.log2(1.5))
    features[:, BEAT_COLUMN] = 0
    assert not rhythm_channels(features).any()


def test_stretched_features_keep_beats_on_the_stretched_beats():
    features = np.zeros((100, FEATURE_DIM), np.float32)
    features[:, 0] = np.arange(100)  # onset strength: a ramp reads back the source frame
    features[[0, 30, 60, 90], BEAT_COLUMN] = 1.0
    features[[45], PEAK_COLUMN] = 1.0
    fast = stretch_features(features, 1.2)
    assert len(fast) == stretched(random_motion(frames=100), 1.2).num_frames
    np.testing.assert_allclose(fast[:10, 0], np.arange(10) * 1.2, rtol=1e-6)
    assert np.flatnonzero(fast[:, BEAT_COLUMN]).tolist() == [0, 25, 50, 75]
    assert np.flatnonzero(fast[:, PEAK_COLUMN]).tolist() == [38]  # 45 / 1.2 = 37.5 -> 38


def test_mirroring_marks_the_dance_and_keeps_what_else_it_knew():
    dance = Motion.rest(4).replace(metadata={"genre": "waltz"})
    once = mirrored(dance)
    assert once.metadata == {"genre": "waltz", "mirrored": True}
    assert mirrored(once).metadata == {"genre": "waltz", "mirrored": False}


def test_a_joint_without_a_twin_is_named_in_the_error():
    from choreo.errors import ParameterError

    with pytest.raises(ParameterError, match="joint 'l_hand' has no mirror twin 'r_hand'"):
        mirror_joint_order(("pelvis", "l_hand"))


def test_turned_dance_is_the_same_dance_rotated_about_the_vertical_through_its_centre():
    from choreo.motion import turned

    motion = random_motion(frames=12, seed=3)
    angle = np.deg2rad(90.0)
    c, s = np.cos(angle), np.sin(angle)
    about_y = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # right-handed, y up
    centre = motion.root_positions.mean(0) * np.array([1.0, 0.0, 1.0])
    expected = (motion.joint_positions() - centre) @ about_y.T + centre
    out = turned(motion, 90.0)
    np.testing.assert_allclose(out.joint_positions(), expected, atol=1e-9)
    np.testing.assert_allclose(out.root_positions.mean(0), motion.root_positions.mean(0), atol=1e-12)
    np.testing.assert_allclose(out.rotations[:, 1:], motion.rotations[:, 1:])  # only the root joint turns
    np.testing.assert_allclose(turned(out, -90.0).joint_positions(), motion.joint_positions(), atol=1e-9)
    assert out.metadata["turned_degrees"] == 90.0
    # a turn keeps the dance's handedness (a mirror would flip it): left stays left of right
    spread = lambda m: np.cross(m.joint_positions()[:, 16] - m.joint_positions()[:, 0],  # noqa: E731
                                m.joint_positions()[:, 17] - m.joint_positions()[:, 0])[:, 1]
    np.testing.assert_allclose(spread(out), spread(motion), atol=1e-9)


def test_augmentation_yields_every_pace_mirror_and_facing():
    from choreo.errors import ParameterError
    from choreo_sgmd.data import Augmentation

    motion, features = random_motion(frames=40), np.zeros((40, FEATURE_DIM))
    copies = list(Augmentation(stretch=(1.0, 1.18), mirror=True, turns=(0.0, 90.0, 180.0)).variants(motion, features))
    assert len(copies) == 2 * 2 * 3
    assert [c[0].metadata.get("turned_degrees", 0.0) for c in copies[:3]] == [0.0, 90.0, 180.0]
    assert copies[0][0] is motion and copies[3][0].metadata["mirrored"]
    assert len(list(Augmentation().variants(motion, features))) == 1
    with pytest.raises(ParameterError, match="turns must be angles"):
        Augmentation(turns=(400.0,))


@pytest.mark.survivor
def test_stretch_limits_are_inclusive():
    motion = counting_motion(9)
    slowest = stretched(motion, 0.25)
    np.testing.assert_allclose(slowest.root_positions[:, 0], np.arange(33) * 0.25, rtol=0, atol=1e-12)
    fastest = stretched(motion, 4.0)
    np.testing.assert_allclose(fastest.root_positions[:, 0], [0.0, 4.0, 8.0], rtol=0, atol=1e-12)
    for factor in [0.2, 4.5]:
        message = exactly(f"stretch factor must be within [0.25, 4], got {factor}")
        with pytest.raises(ParameterError, match=message):
            stretched(motion, factor)


@pytest.mark.survivor
def test_turns_add_up_in_the_metadata_and_keep_the_rest():
    motion = counting_motion(4, metadata={"genre": "waltz"})
    twice = turned(turned(motion, 30.0), 45.0)
    assert twice.metadata == {"genre": "waltz", "turned_degrees": 75.0}
