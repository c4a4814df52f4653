"""The graph backend under constraints (bundled models and repertoire): a root path the walk
follows and the dance meets exactly, keys and kept frames met exactly, the guide's idea of where
each node is played equal to the assembly's, and the CLI commands with ``--generator graph``."""

from pathlib import Path

import numpy as np
import pytest

from choreo.cli import main
from choreo.constraints import Constraints
from choreo.formats import read_motion
from choreo.generator import GenerationRequest
from choreo.music import Music
from choreo_graph import DEFAULT_CHECKPOINT
from choreo_graph.config import NODE_FRAMES
from choreo_graph.generator import ChoreoGraphGenerator
from choreo_graph.guide import Guide, priced

REPO = Path(__file__).resolve().parents[2]
SONG = REPO / "examples" / "drum_and_bass_174bpm.wav"


@pytest.fixture(scope="module")
def graph():
    return ChoreoGraphGenerator.from_files(DEFAULT_CHECKPOINT)


@pytest.fixture(scope="module")
def music():
    return Music.from_file(SONG, log_mel=True, timbre=False)


@pytest.fixture(scope="module")
def free_dance(graph, music):
    return graph.generate(GenerationRequest(music))


def circle(num_frames: int, radius: float = 1.5) -> np.ndarray:
    angle = np.linspace(0, 2 * np.pi, num_frames)
    return radius * np.stack([np.cos(angle) - 1, np.sin(angle)], -1)  # starts at the origin


def dance_under(graph, music, constraints, **options):
    return graph.generate(GenerationRequest(music, constraints=constraints, options=options))


def test_a_root_path_is_met_exactly_and_the_path_cost_makes_the_walk_follow_it(graph, music):
    path = circle(music.num_frames)
    constraints = Constraints.none(music.num_frames, music.fps).fix_root_path(path)
    steered = dance_under(graph, music, constraints)
    unsteered = dance_under(graph, music, constraints, path_cost=0.0)
    for dance in (steered, unsteered):
        np.testing.assert_allclose(dance.root_positions[:, [0, 2]], path, atol=1e-9)
        assert dance.num_frames == music.num_frames
    # how far the walk itself strayed before being bent onto the path: the cost must steer it
    assert steered.metadata["walk_root_error_m"] < 0.5 * unsteered.metadata["walk_root_error_m"]
    assert unsteered.metadata["walk_root_error_m"] > 0.3  # the circle is not where clips wander by themselves


def test_keys_come_out_exact_and_the_rest_of_the_dance_is_the_graphs(graph, music, free_dance):
    key_source = free_dance.slice_frames(40, 41)  # a pose the repertoire can play, placed elsewhere
    constraints = Constraints.none(music.num_frames, music.fps)
    constraints.fix_motion(key_source, at=0).fix_motion(key_source, at=200)
    constraints.root[[0, 200]] += [0.8, 0.0, -0.5]
    dance = dance_under(graph, music, constraints)
    expected = constraints.target_motion().joint_positions()[[0, 200]]
    np.testing.assert_allclose(dance.joint_positions()[[0, 200]], expected, atol=1e-6)
    far = np.r_[30:170, 230:dance.num_frames]  # more than 0.5 s from a key: nothing bent, still moving
    assert np.linalg.norm(np.diff(dance.root_positions[far], axis=0), axis=-1).sum() > 0.2


def test_inpainting_keeps_every_frame_outside_the_range_and_regenerates_inside(graph, music):
    # Another take (seed 3) to repair: the same seed's walk, priced against its own frames, would
    # find its own nodes again.
    other = graph.generate(GenerationRequest(music, seed=3))
    constraints = Constraints.none(music.num_frames, music.fps).fix_motion(other).free(slice(90, 210))
    dance = dance_under(graph, music, constraints)
    kept = np.r_[0:90, 210:music.num_frames]
    np.testing.assert_allclose(dance.root_positions[kept], other.root_positions[kept], atol=1e-9)
    np.testing.assert_allclose(np.abs((dance.rotations[kept] * other.rotations[kept]).sum(-1)), 1.0, atol=1e-6)
    inside = dance.joint_positions()[120:180] - other.joint_positions()[120:180]
    assert np.linalg.norm(inside, axis=-1).mean() > 0.05  # another walk, not the old frames


def test_the_guide_places_each_node_where_the_assembly_plays_it(graph, music, monkeypatch):
    """The path cost prices each candidate by where the guide thinks its root will be; that must
    be where the assembled dance puts it, on the fractional frames the assembly plays (rounding
    them drifted the placement by up to 17 cm over a song's jumps)."""
    predicted = {}
    cost, chose = Guide.cost, Guide.chose

    def remembering_cost(self, t, clips, frames, follows, current):
        self.seen = (t, clips, frames)
        return cost(self, t, clips, frames, follows, current)

    def remembering_choice(self, best):
        chose(self, best)
        t, clips, frames = self.seen
        ends = self.placed_roots(clips[best : best + 1], frames[best : best + 1, -1:],
                                 np.array([self.placement.angle]), self.placement.offset[None])
        predicted[t] = ends[0, 0, [0, 2]]

    monkeypatch.setattr(Guide, "cost", remembering_cost)
    monkeypatch.setattr(Guide, "chose", remembering_choice)
    constraints = Constraints.none(music.num_frames, music.fps)
    constraints.root_known[0, [0, 2]] = True  # only a start: the walk is free, the guide still tracks it
    constraints.root[0] = [1.0, 0.0, 2.0]
    dance = dance_under(graph, music, constraints)
    ends = [t for t in predicted if (t + 1) * NODE_FRAMES <= music.num_frames]
    assembled = dance.root_positions[[(t + 1) * NODE_FRAMES - 1 for t in ends]][:, [0, 2]]
    error = np.linalg.norm(assembled - np.array([predicted[t] for t in ends]), axis=-1)
    assert len(ends) >= 10 and error.max() < 0.003
    np.testing.assert_allclose(dance.root_positions[0, [0, 2]], [1.0, 2.0], atol=1e-9)


def test_priced_frames_are_at_most_five_evenly_spread_ends_included():
    np.testing.assert_array_equal(priced(np.arange(3)), [0, 1, 2])
    np.testing.assert_array_equal(priced(np.arange(10, 40)), [10, 17, 24, 32, 39])


def test_the_cli_dances_a_path_and_an_inpainting_with_the_graph(tmp_path):
    path_file = tmp_path / "line.csv"
    path_file.write_text("x,z\n0,0\n2,0\n")
    out = tmp_path / "walk.bvh"
    assert main(["trajectory", str(SONG), "--path", str(path_file), "--generator", "graph", "-o", str(out),
                 "--no-beat-lock"]) == 0
    walk = read_motion(out)
    np.testing.assert_allclose(walk.root_positions[[0, -1]][:, [0, 2]], [[0, 0], [2, 0]], atol=1e-5)  # BVH: 6 decimals
    fixed = tmp_path / "fixed.bvh"
    assert main(["inpaint", str(SONG), "--motion", str(out), "--frames", "60:120", "--generator", "graph",
                 "-o", str(fixed), "--no-beat-lock"]) == 0
    again = read_motion(fixed)
    np.testing.assert_allclose(again.root_positions[:60], walk.root_positions[:60], atol=1e-5)
    assert not np.allclose(again.root_positions[60:120], walk.root_positions[60:120], atol=1e-3)


def test_a_free_walk_is_kept_on_its_floor(graph, music):
    """Joined clips travel like a random walk: without a root path the walk prices a node that
    ends beyond ``floor_radius`` of the start, and the dance stays nearer it (no constraint is
    reported, no frame is bent)."""
    def reach(dance):
        return np.linalg.norm(dance.root_positions[:, [0, 2]] - dance.root_positions[0, [0, 2]], axis=-1).max()

    wandering = dance_under(graph, music, None, floor_cost=0.0)
    kept = dance_under(graph, music, None, floor_radius=0.1, floor_cost=100.0)
    assert reach(wandering) > 0.5 and reach(kept) < 0.6 * reach(wandering)  # 11.5 s: 0.66 m and 0.31 m
    assert kept.metadata["constrained_fraction"] is None and kept.metadata["walk_root_error_m"] is None
    no_floor = dance_under(graph, music, None, floor_radius=0.0)  # --floor-radius 0: the walk as it was
    np.testing.assert_array_equal(no_floor.root_positions, wandering.root_positions)
