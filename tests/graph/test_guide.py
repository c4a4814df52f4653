"""The graph guide's parts on a hand-made three-clip repertoire, against literal loops: which
frames count as given poses, where the first node starts, where each candidate would be played,
the path and key costs, and the walk's own distance from the path. Also the displacement map's
plumbing (reach, frame rate, skeleton, metadata)."""

from types import SimpleNamespace

import numpy as np
import pytest

from choreo.constraints import Constraints
from choreo.constraints.displacement import displace_motion, displace_to_constraints
from choreo.motion import Motion
from choreo.motion.stitch import facing_yaw, frame_local_positions
from choreo.skeleton import SMPL24
from choreo_graph.config import NODE_FRAMES, GraphConfig
from choreo_graph.guide import Guide
from choreo_graph.repertoire import Repertoire

pytestmark = pytest.mark.survivor  # written from the graph-guide mutation run's survivors (docs/dev/mutation.md)

CLIP_FRAMES = 240


OFFSETS = np.asarray(SMPL24.offsets, np.float64) * 1.1  # not the default skeleton: FK must use these


def hand_made_repertoire() -> Repertoire:
    """Three clips: one walking +z facing +z, one turned by 90 degrees walking sideways, one
    turning on the spot; every pose a little different."""
    rng = np.random.default_rng(0)
    t = np.arange(CLIP_FRAMES)
    roots = np.zeros((3, CLIP_FRAMES, 3))
    roots[..., 1] = 0.95
    roots[0, :, 2] = 0.02 * t
    roots[1, :, 0] = 0.5 + 0.01 * t
    roots[2, :, 0] = -0.3
    axis_angle = rng.normal(scale=0.1, size=(3, CLIP_FRAMES, 24, 3))
    axis_angle[1, :, 0] = [0.0, np.pi / 2, 0.0]
    axis_angle[2, :, 0] = np.stack([np.zeros(CLIP_FRAMES), 0.01 * t, np.zeros(CLIP_FRAMES)], -1)
    skeleton = SMPL24.with_offsets(OFFSETS)
    motions = [Motion.from_axis_angle(roots[i], axis_angle[i], fps=30.0, skeleton=skeleton) for i in range(3)]
    positions = np.stack([m.joint_positions() for m in motions])
    return Repertoire(names=np.array(["a@0", "b@0", "c@0"]), genres=np.array(["", "", ""]),
                      root_positions=roots.astype(np.float32),
                      rotations=np.stack([m.rotations for m in motions]).astype(np.float32), offsets=OFFSETS,
                      poses=frame_local_positions(positions).astype(np.float16), style=np.zeros((3, 4), np.float32),
                      beat_counts=np.zeros(3, np.float32), tempo=np.zeros((3, CLIP_FRAMES), np.float32),
                      source=np.array("hand-made"))


@pytest.fixture(scope="module")
def repertoire():
    return hand_made_repertoire()


def given_motion(frames=90, seed=1) -> Motion:
    rng = np.random.default_rng(seed)
    root = np.tile([0.2, 0.9, -0.4], (frames, 1)) + np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), 0)
    return Motion.from_axis_angle(root, rng.normal(scale=0.2, size=(frames, 24, 3)), fps=30.0)


def literal_between(frame):
    """The whole frames around a fractional clip frame (clamped to the clip) and the later one's weight."""
    frame = min(max(float(frame), 0.0), CLIP_FRAMES - 1.0)
    before = int(np.floor(frame))
    return before, min(before + 1, CLIP_FRAMES - 1), frame - before


def literal_played_root(repertoire, clip, frame, angle, offset):
    before, after, w = literal_between(frame)
    x, _, z = (1 - w) * repertoire.root_positions[clip, before].astype(np.float64) + w * repertoire.root_positions[clip, after]
    return np.array([np.cos(angle) * x + np.sin(angle) * z + offset[0], 0.0, -np.sin(angle) * x + np.cos(angle) * z + offset[2]])


def literal_facing(repertoire, clip, frame):
    before, after, w = literal_between(frame)
    a, b = float(repertoire.facing[clip, before]), float(repertoire.facing[clip, after])
    turn = (b - a + np.pi) % (2 * np.pi) - np.pi  # the short way round
    return a + w * turn


def test_given_poses_are_frames_with_every_joint_and_the_root_height_given(repertoire):
    motion = given_motion()
    c = Constraints.none(90, 30.0)
    c.fix_motion(motion, frames=np.arange(10, 20))  # whole poses with the root: posed
    c.fix_motion(motion, frames=np.arange(30, 40), root=False)  # every joint but no root: not posed
    c.root_known[30:35, [0, 2]] = True  # ... nor with the floor position alone
    c.fix_motion(motion, frames=np.arange(50, 60), joints=range(1, 24))  # the root joint's rotation missing
    guide = Guide(c, repertoire, GraphConfig())
    assert np.flatnonzero(guide.posed).tolist() == list(range(10, 20))
    skeleton = SMPL24.with_offsets(OFFSETS)
    expected = frame_local_positions(motion.replace(skeleton=skeleton).joint_positions()[10:20])
    np.testing.assert_allclose(guide.poses[10:20], expected, atol=1e-5)
    assert not guide.poses[:10].any() and not guide.poses[20:].any()
    np.testing.assert_array_equal(guide.root[:, 1], 0.0)  # floor positions
    np.testing.assert_allclose(guide.root[10:20][:, [0, 2]], motion.root_positions[10:20][:, [0, 2]])


def test_the_first_node_starts_at_the_first_given_root_facing_its_pose_or_at_the_origin(repertoire):
    free = Guide(Constraints.none(60, 30.0), repertoire, GraphConfig())
    origin, yaw = free.start
    assert origin.shape == (3,) and not origin.any() and yaw == 0.0
    motion = given_motion()
    c = Constraints.none(90, 30.0).fix_motion(motion, frames=np.arange(7, 9))
    origin, yaw = Guide(c, repertoire, GraphConfig()).start
    np.testing.assert_allclose(origin, motion.root_positions[7] * [1, 0, 1])
    skeleton = SMPL24.with_offsets(OFFSETS)
    assert yaw == pytest.approx(float(facing_yaw(motion.replace(skeleton=skeleton).joint_positions()[7])), abs=1e-9)


def literal_placements(guide, repertoire, clips, first, follows, current):
    """Each candidate's (angle, offset): continuing the current segment keeps its placement; any
    other starts where the current one would have gone next, facing its way."""
    if current is None or guide.placement is None:
        target, yaw = guide.start
    else:
        rate = max(float(current.frames[-1] - current.frames[-2]), 0.5)
        ahead = float(current.frames[-1]) + rate
        target = literal_played_root(repertoire, current.clip, ahead, guide.placement.angle, guide.placement.offset)
        yaw = guide.placement.angle + literal_facing(repertoire, current.clip, ahead)
    angles, offsets = [], []
    for clip, frame, continues in zip(clips, first, follows):
        if continues and current is not None and guide.placement is not None:
            angles.append(guide.placement.angle)
            offsets.append(guide.placement.offset)
            continue
        angle = yaw - literal_facing(repertoire, clip, frame)
        start = literal_played_root(repertoire, clip, frame, angle, np.zeros(3))
        angles.append(angle)
        offsets.append((target - start) * [1, 0, 1])
    return np.array(angles), np.array(offsets)


def test_candidates_are_placed_where_the_walk_would_play_them(repertoire):
    motion = given_motion()
    c = Constraints.none(90, 30.0).fix_motion(motion, frames=np.arange(0, 3))
    guide = Guide(c, repertoire, GraphConfig())
    clips, first, follows = np.array([0, 1, 2, 0]), np.array([-1.0, 0.0, 12.4, 250.0]), np.array([False, True, False, False])
    for current in (None, SimpleNamespace(clip=1, frames=np.array([5.0, 6.3]))):  # no placement chosen yet
        angles, offsets = guide.placements(clips, first, follows, current)
        want_angles, want_offsets = literal_placements(guide, repertoire, clips, first, follows, None)
        np.testing.assert_allclose(angles, want_angles, atol=1e-9)
        np.testing.assert_allclose(offsets, want_offsets, atol=1e-6)
    guide.cost(0, clips, np.tile(first[:, None], (1, NODE_FRAMES)), follows, None)
    guide.chose(2)
    assert guide.placement.angle == pytest.approx(want_angles[2])
    for frames in ([100.0, 101.3], [237.0, 238.9], [10.0, 10.1]):  # ahead 102.6; past the clip's end; rate at least 0.5
        current = SimpleNamespace(clip=2, frames=np.concatenate([np.linspace(frames[0] - 28, frames[0] - 1, 28), frames]))
        angles, offsets = guide.placements(clips, first, follows, current)
        want_angles, want_offsets = literal_placements(guide, repertoire, clips, first, follows, current)
        np.testing.assert_allclose(angles, want_angles, atol=1e-9)
        np.testing.assert_allclose(offsets, want_offsets, atol=1e-6)
        assert angles[1] == guide.placement.angle and (offsets[1] == guide.placement.offset).all()
        assert (offsets[:, 1] == 0).all()
    angles, offsets = guide.placements(clips, first, follows, None)  # no current node: nothing continues
    want_angles, _ = literal_placements(guide, repertoire, clips, first, follows, None)
    np.testing.assert_allclose(angles, want_angles, atol=1e-9)


def test_placed_roots_interpolate_fractional_frames_within_the_clip(repertoire):
    guide = Guide(Constraints.none(30, 30.0), repertoire, GraphConfig())
    frames = np.array([[-1.0, 0.0, 0.6, 238.6, 239.0, 240.4]])
    placed = guide.placed_roots(np.array([0]), frames, np.array([0.3]), np.array([[1.0, 5.0, -2.0]]))
    want = [literal_played_root(repertoire, 0, f, 0.3, [1.0, 5.0, -2.0]) for f in frames[0]]
    np.testing.assert_allclose(placed[0], want, atol=1e-6)


def literal_cost(guide, repertoire, config, t, clips, frames, angles, offsets):
    span = range(t * NODE_FRAMES, min((t + 1) * NODE_FRAMES, guide.num_frames))
    rooted = [f for f in span if guide.root_known[f]]
    posed = [f for f in span if guide.posed[f]]
    pick = lambda fs: fs if len(fs) <= 5 else [fs[i] for i in np.rint(np.linspace(0, len(fs) - 1, 5)).astype(int)]  # noqa: E731
    rooted, posed = pick(rooted), pick(posed)
    costs = []
    for c, clip in enumerate(clips):
        cost = 0.0
        if rooted and config.path_cost:
            gaps = [literal_played_root(repertoire, clip, frames[c, f - t * NODE_FRAMES], angles[c], offsets[c])
                    - guide.root[f] for f in rooted]
            cost += config.path_cost * np.mean([np.sum(g**2) for g in gaps])
        if posed and config.key_cost:
            per_frame = []
            for f in posed:
                frame = min(max(int(np.rint(frames[c, f - t * NODE_FRAMES])), 0), CLIP_FRAMES - 1)
                pose = repertoire.poses[clip, frame].astype(np.float64)
                per_frame.append(np.mean([np.sum((pose[j] - guide.poses[f, j]) ** 2) for j in range(24)]))
            cost += config.key_cost * np.mean(per_frame)
        costs.append(cost)
    return np.array(costs)


@pytest.mark.parametrize("path_cost, key_cost", [(4.0, 4.0), (4.0, 0.0), (0.0, 2.5), (16.0, 1.0)])
def test_each_candidates_cost_is_the_literal_path_and_key_distance(repertoire, path_cost, key_cost):
    motion = given_motion(frames=90)
    c = Constraints.none(90, 30.0)
    c.fix_motion(motion, frames=np.arange(30, 36))  # six whole poses: five are priced
    c.fix_root_path(motion.root_positions[:, [0, 2]] + [0.0, 0.3])  # a floor path on every frame
    config = GraphConfig(path_cost=path_cost, key_cost=key_cost)
    guide = Guide(c, repertoire, config)
    clips = np.array([0, 1, 2, 0, 2, 1])
    frames = np.array([np.arange(NODE_FRAMES) + s for s in (0.0, 40.2, 100.0, 200.0, -40.0, 215.0)])  # the last two
    follows = np.zeros(6, bool)                                                                       # leave the clip
    guide.cost(0, clips, frames, follows, None)
    guide.chose(1)
    current = SimpleNamespace(clip=1, frames=frames[1])
    cost = guide.cost(1, clips, frames, np.array([False, True, False, False, False, False]), current)
    angles, offsets = guide.candidates
    want = literal_cost(guide, repertoire, config, 1, clips, frames, angles, offsets)
    np.testing.assert_allclose(cost, want, rtol=1e-5)
    assert len(set(np.round(cost[:4], 6))) == 4  # each candidate its own price (clip 2 turns on the spot)


def test_the_walks_own_root_error_is_the_mean_floor_distance_where_the_root_is_given(repertoire):
    path = np.stack([np.linspace(0, 1, 60), np.zeros(60)], -1)
    c = Constraints.none(60, 30.0).fix_root_path(path)
    c.root_known[40:] = False
    guide = Guide(c, repertoire, GraphConfig())
    root = np.zeros((60, 3))
    root[:, 0] = path[:, 0] + 0.3  # 0.3 m off in x, 0.4 in z, and a metre too high
    root[:, 2] = 0.4
    root[:, 1] = 1.0
    root[40:, 0] += 7.0  # not given there: not counted
    motion = Motion.from_axis_angle(root, np.zeros((60, 24, 3)), fps=30.0)
    assert guide.root_error(motion) == pytest.approx(0.5, abs=1e-12)
    assert Guide(Constraints.none(60, 30.0), repertoire, GraphConfig()).root_error(motion) is None


def test_displace_motion_passes_its_reach_frame_rate_skeleton_and_metadata_on():
    skeleton = SMPL24.with_offsets(OFFSETS)
    rng = np.random.default_rng(3)
    motion = Motion.from_axis_angle(np.tile([0.0, 0.9, 0.0], (40, 1)), rng.normal(scale=0.1, size=(40, 24, 3)),
                                    fps=60.0, skeleton=skeleton, metadata={"generator": "graph"})
    given = Motion.from_axis_angle(np.tile([0.5, 0.9, 0.0], (1, 1)), rng.normal(scale=0.1, size=(1, 24, 3)), fps=60.0)
    c = Constraints.none(40, 60.0).fix_motion(given, at=20)
    near = displace_motion(motion, c, reach=2)
    far = displace_motion(motion, c, reach=10)
    assert near.fps == 60.0 and far.fps == 60.0
    np.testing.assert_array_equal(near.skeleton.offsets, skeleton.offsets)
    assert near.metadata == {"generator": "graph"} and near.metadata is not motion.metadata
    np.testing.assert_allclose(near.rotations[15], motion.rotations[15], atol=1e-8)  # 5 frames away: outside reach 2 (6-d round trip)
    assert not np.allclose(far.rotations[15], motion.rotations[15], atol=1e-4)  # inside reach 10


def test_reach_one_still_bends_the_neighbours():
    frames = np.zeros((5, 1))
    values = np.zeros((5, 1))
    values[2] = 1.0
    mask = np.zeros((5, 1), bool)
    mask[2] = True
    np.testing.assert_allclose(displace_to_constraints(frames, values, mask, reach=1)[:, 0], [0, 0, 1, 0, 0])
    np.testing.assert_allclose(displace_to_constraints(frames, values, mask, reach=2)[:, 0], [0, 0.5, 1, 0.5, 0])
    np.testing.assert_allclose(displace_to_constraints(frames, values, np.roll(mask, 1, 0) | mask, reach=1)[:, 0],
                               [0, 0, 1, 0, 0])  # frame 3 given as 0 stays 0
    values[[1, 3]], mask[[1, 3]] = 1.0, True
    mask[2] = False  # frames 1 and 3 given, 2 apart: reach 1 bridges the gap (an overwrite would leave frame 2 at 0)
    np.testing.assert_allclose(displace_to_constraints(frames, values, mask, reach=1)[:, 0], [0, 1, 1, 1, 0])
