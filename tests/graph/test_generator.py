"""ChoreoGraph: the batched DTW against librosa, the time-warper, the repertoire file, the graph
search and the whole backend end to end with tiny untrained models (fast, no dataset)."""

from pathlib import Path

import librosa
import numpy as np
import pytest
import torch

from choreo.cli import main
from choreo.generator import GenerationRequest
from choreo.motion import Motion
from choreo.motion.stitch import crossfade, facing_yaw, local_positions, placement_onto, turned_and_moved
from choreo.music import Music
from choreo_graph.config import GraphConfig, ModelConfig, StyleConfig, TempoConfig
from choreo_graph.generator import ChoreoGraphGenerator
from choreo_graph.graph import MusicWindows, replayed_nodes, search_graph
from choreo_graph.model import ChoreoGraphModel, load_checkpoint, save_checkpoint
from choreo_graph.repertoire import Repertoire, SpeedLimits, build_repertoire
from choreo_graph.tempo import random_time_warp
from choreo_graph.warp import STEPS, subsequence_dtw, warp_frames

REPO = Path(__file__).resolve().parents[2]
SONG = REPO / "examples" / "drum_and_bass_174bpm.wav"
TINY = ModelConfig(style=StyleConfig(style_dim=8, music_channels=(4, 4, 4, 4), motion_channels=(4, 4, 4, 4), gru_hidden=8,
                                     gru_layers=1, beat_hidden=8),
                   tempo=TempoConfig(width=8, content_dim=8, heads=2, music_layers=1))


def swaying_dance(seconds=20.0, fps=30, phase=0.0, speed=1.0) -> Motion:
    t = np.arange(int(seconds * fps)) / fps
    axis_angle = np.zeros((len(t), 24, 3))
    axis_angle[:, 16, 2] = 0.8 * np.sin(2 * np.pi * speed * t + phase)  # left shoulder
    axis_angle[:, 17, 2] = -0.8 * np.sin(2 * np.pi * speed * t + phase)
    axis_angle[:, 1, 0] = 0.3 * np.sin(np.pi * speed * t)  # hips
    axis_angle[:, 0, 1] = 0.2 * t  # slowly turning
    root = np.stack([0.3 * np.sin(0.5 * t), 0.95 + 0.02 * np.sin(4 * t), 0.2 * t], -1)
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


@pytest.fixture(scope="module")
def tiny_graph(tmp_path_factory):
    """A checkpoint of untrained tiny models and a repertoire of two synthetic dances."""
    torch.manual_seed(0)
    folder = tmp_path_factory.mktemp("graph")
    model = ChoreoGraphModel(TINY).eval()
    save_checkpoint(model, folder / "graph.pt")
    dances = [("sway", swaying_dance(), "waltz"), ("fast", swaying_dance(phase=1.0, speed=2.0), "rumba")]
    build_repertoire(dances, model, 60, "synthetic").save(folder / "repertoire.npz")
    return folder / "graph.pt", folder / "repertoire.npz"


# -- warping ---------------------------------------------------------------------------------
def test_subsequence_dtw_matches_librosa():
    rng = np.random.default_rng(1)
    queries, references = rng.random((40, 30)), rng.random((40, 70))
    ours = subsequence_dtw(queries, references)
    for q, r, path in zip(queries, references, ours):
        _, pairs = librosa.sequence.dtw(q[None], r[None], subseq=True, step_sizes_sigma=STEPS, backtrack=True)
        theirs = np.full(len(q), np.nan)
        theirs[pairs[:, 0]] = pairs[:, 1]
        known = ~np.isnan(theirs)
        np.testing.assert_array_equal(path[known], theirs[known])


def test_warp_keeps_slope_between_half_and_double():
    rng = np.random.default_rng(2)
    frames = warp_frames(rng.random((64, 120)), rng.random((64, 240)), stride=2)
    steps = np.diff(frames, axis=1)
    assert frames.shape == (64, 120)
    assert (steps >= 0).all() and (frames >= 0).all() and (frames <= 239).all()
    assert np.diff(frames[:, ::2], axis=1).max() <= 4 + 1e-9  # at most 2 reference frames per query frame
    assert steps.mean() > 0.5 - 1e-9


def test_warp_finds_a_planted_subsequence():
    reference = np.sin(np.linspace(0, 12, 240))
    query = reference[80:200:1].copy()[None]
    frames = warp_frames(query, reference[None], stride=1)[0]
    assert abs(frames[0] - 80) <= 1 and abs(frames[-1] - 199) <= 1



def test_smoothed_warp_changes_speed_gradually_and_keeps_its_course():
    rng = np.random.default_rng(5)
    queries, references = rng.random((32, 120)), rng.random((32, 240))
    raw = warp_frames(queries, references, stride=2)
    smooth = warp_frames(queries, references, stride=2, smoothing=4.0)
    assert (np.diff(smooth, axis=1) >= -1e-9).all() and (smooth >= 0).all() and (smooth <= 239).all()
    jolt = lambda frames: np.abs(np.diff(frames, 2, axis=1)).max(axis=1)  # noqa: E731 - speed change per frame
    assert (jolt(smooth) < 0.5 * jolt(raw)).all()
    assert np.abs(smooth - raw)[:, 12:-12].max() < 6.0  # the same course, minus the corners
    kernel = np.exp(-0.5 * (np.arange(-16, 17) / 4.0) ** 2)
    literal = np.convolve(raw[0], kernel / kernel.sum(), mode="same")[20:-20]
    np.testing.assert_allclose(smooth[0, 20:-20], literal, atol=1e-6)

def test_random_time_warp_keeps_ends_and_content():
    positions = local_positions(swaying_dance(8.0).joint_positions())
    warped = random_time_warp(positions, 6, np.random.default_rng(0))
    np.testing.assert_allclose(warped[[0, -1]], positions[[0, -1]], atol=1e-9)
    assert not np.allclose(warped, positions)
    lo, hi = positions.min(0), positions.max(0)
    assert ((warped >= lo - 1e-9) & (warped <= hi + 1e-9)).all()  # frames are blends of neighbours


# -- stitching -----------------------------------------------------------------------------------
def test_placement_puts_a_piece_where_and_how_asked():
    piece = swaying_dance(2.0)
    angle, offset = placement_onto(piece, np.array([3.0, 0.0, -2.0]), 1.2)
    placed = turned_and_moved(piece, angle, offset)
    first = placed.joint_positions()[0]
    assert facing_yaw(first) == pytest.approx(1.2, abs=1e-6)
    np.testing.assert_allclose(placed.root_positions[0, [0, 2]], [3.0, -2.0], atol=1e-9)
    assert placed.root_positions[0, 1] == pytest.approx(piece.root_positions[0, 1])
    # a rigid move: distances between joints are unchanged
    np.testing.assert_allclose(np.linalg.norm(first - first[0], axis=-1),
                               np.linalg.norm(piece.joint_positions()[0] - piece.joint_positions()[0, 0], axis=-1), atol=1e-9)


def test_crossfade_ramps_from_one_piece_to_the_other():
    a, b = swaying_dance(1.0), swaying_dance(1.0).translated([1.0, 0, 0])
    blended = crossfade(a.slice_frames(0, 6), b)
    x = blended.root_positions[:8, 0] - a.root_positions[:8, 0]
    assert np.all(np.diff(x[:7]) > 0) and 0 < x[0] < 0.2 and x[6] == pytest.approx(1.0)


# -- repertoire and search -------------------------------------------------------------------
def test_repertoire_round_trip(tiny_graph, tmp_path):
    repertoire = Repertoire.load(tiny_graph[1])
    assert len(repertoire) == 14 and set(repertoire.genres) == {"waltz", "rumba"}
    assert repertoire.tempo.shape == (14, 240) and repertoire.style.shape == (14, 8)
    repertoire.save(tmp_path / "again.npz")
    again = Repertoire.load(tmp_path / "again.npz")
    np.testing.assert_allclose(again.rotations, repertoire.rotations, atol=1e-3)
    sources, starts = again.origins  # from the "source@start" names: two dances, clips 2 s apart
    assert list(sources) == [1] * 7 + [0] * 7 and list(starts[:3]) == [0, 60, 120]
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    with pytest.raises(Exception, match="not a readable repertoire"):
        Repertoire.load(tmp_path / "bad.npz")


def test_dynamic_graph_prefers_finishing_an_action(tiny_graph):
    repertoire = Repertoire.load(tiny_graph[1])
    seconds, k = 6, 3
    windows = MusicWindows(np.zeros((seconds, 8)), np.zeros(seconds), np.zeros((seconds, 120)))
    candidates = np.tile(np.arange(k), (seconds, 1))
    warps = np.broadcast_to(np.arange(60.0, 180.0), (seconds, k, 120))
    config = GraphConfig(style_cost=0.0, completeness_cost=100.0, transition_cost=0.0)
    path = search_graph(windows, candidates, warps, repertoire, config)
    assert len(path) == seconds
    # leaving a segment costs 1 x lambda_c; continuing it costs sigmoid(...) < 1: segments run to their end
    assert [node.index for node in path][:4] == [0, 1, 2, 3]
    assert len({node.segment for node in path[:4]}) == 1 and path[4].segment != path[3].segment
    plain = search_graph(windows, candidates, warps, repertoire, GraphConfig(dynamic=False))
    assert all(node.index == 0 for node in plain)


def test_dynamic_graph_does_not_replay_what_it_just_danced(tiny_graph):
    repertoire = Repertoire.load(tiny_graph[1])
    seconds = 16
    windows = MusicWindows(np.repeat(repertoire.style[:1], seconds, 0), np.zeros(seconds), np.zeros((seconds, 120)))
    candidates = np.tile(np.arange(len(repertoire)), (seconds, 1))
    warps = np.broadcast_to(np.arange(60.0, 180.0), (seconds, len(repertoire), 120))

    # clip 0 is the music's style every second: without the repeat cost its first node, nearest the
    # previous pose, is chosen again and again
    looping = search_graph(windows, candidates, warps, repertoire,
                           GraphConfig(completeness_cost=0.0, repeat_cost=0.0, take_variation=0.0))
    assert replayed_nodes(looping, repertoire, 30) >= seconds // 2
    varied = search_graph(windows, candidates, warps, repertoire, GraphConfig(completeness_cost=0.0, take_variation=0.0))
    assert replayed_nodes(varied, repertoire, 30) == 0 and len({n.clip for n in varied}) > 3


def test_speed_limits_leave_out_glitches():
    positions = swaying_dance(8.0).joint_positions()
    assert SpeedLimits(joint=8.0, root=3.0).admit(positions)
    dash = positions.copy()
    dash[100:] += [0.2, 0.0, 0.0]  # the whole body 20 cm in one frame: 6 m/s
    assert SpeedLimits(joint=8.0).admit(dash) and not SpeedLimits(root=3.0).admit(dash)
    flip = positions.copy()
    flip[100:, 20] += [0.0, 0.3, 0.0]  # a wrist 30 cm in one frame: 9 m/s
    assert SpeedLimits(root=3.0).admit(flip) and not SpeedLimits(joint=8.0).admit(flip)


# -- the backend ---------------------------------------------------------------------------------
def test_generates_as_many_frames_as_the_song_without_jumps(tiny_graph):
    generator = ChoreoGraphGenerator.from_files(*tiny_graph, config=GraphConfig(top_k=4))
    music = Music.from_file(SONG)
    motion = generator.generate(GenerationRequest(music, seed=3))
    assert motion.num_frames == music.num_frames
    def fastest(m):  # metres per frame
        return np.linalg.norm(np.diff(m.joint_positions(), axis=0), axis=-1).max()

    # seams are placed and cross-faded, never teleported: nothing moves faster than the fastest
    # source dance played at the warper's top speed (2x)
    assert fastest(motion) <= 2.05 * fastest(swaying_dance(phase=1.0, speed=2.0))
    assert np.linalg.norm(np.diff(motion.root_positions, axis=0), axis=-1).max() < 0.05
    again = generator.generate(GenerationRequest(music, seed=3))
    np.testing.assert_array_equal(again.rotations, motion.rotations)
    assert motion.metadata["generator"] == "graph" and motion.metadata["seed"] == 3


def test_a_saved_repertoire_stores_each_frame_once_and_reads_back_every_clip(tiny_graph, tmp_path):
    """Format 2: the 14 clips (two 20 s dances, 8 s clips 2 s apart) share their frames: the pool
    holds each dance's 600 frames once, not 14 x 240, and every clip reads back as stored."""
    repertoire = Repertoire.load(tiny_graph[1])
    repertoire.save(tmp_path / "pooled.npz")
    with np.load(tmp_path / "pooled.npz") as archive:
        assert int(archive["format_version"]) == 2 and "rotations" not in archive.files
        assert archive["pool_rotations"].shape == (1200, 24, 4) and archive["pool_rotations"].dtype == np.float16
        sources, starts = repertoire.origins
        first = {source: 600 * rank for rank, source in enumerate(np.unique(sources))}  # dances in name order
        assert list(archive["clip_starts"]) == [first[s] + start for s, start in zip(sources, starts)]
    again = Repertoire.load(tmp_path / "pooled.npz")
    np.testing.assert_array_equal(again.rotations, repertoire.rotations.astype(np.float16).astype(np.float32))
    np.testing.assert_array_equal(again.root_positions, repertoire.root_positions)
    # poses are not stored: recomputed from the float16 rotations, they differ by float16 steps of a metre
    np.testing.assert_allclose(again.poses.astype(np.float32), repertoire.poses.astype(np.float32), atol=4e-3)
    for key in ("names", "genres", "style", "beat_counts", "tempo"):
        np.testing.assert_array_equal(getattr(again, key), getattr(repertoire, key))


def test_clips_whose_shared_frames_differ_are_stored_whole(tiny_graph, tmp_path):
    """Two clips named as if cut from one motion but differing where they overlap (hand-made or
    edited repertoires) keep their own frames: nothing is read back from a neighbour."""
    repertoire = Repertoire.load(tiny_graph[1])
    second = int(np.flatnonzero(repertoire.origins[1] == 60)[0])
    repertoire.root_positions[second, 0] += 1.0  # its first frame, shared with the clip before it
    repertoire.save(tmp_path / "edited.npz")
    with np.load(tmp_path / "edited.npz") as archive:
        assert len(archive["pool_root_positions"]) == 1200 + 180  # that clip whole: 240 frames, not 60
    again = Repertoire.load(tmp_path / "edited.npz")
    np.testing.assert_array_equal(again.root_positions, repertoire.root_positions)


def test_style_restricts_the_repertoire(tiny_graph):
    generator = ChoreoGraphGenerator.from_files(*tiny_graph, config=GraphConfig(top_k=2))
    mask, genre = generator.allowed_clips("Waltz")
    assert genre == "waltz" and mask.sum() == 7
    with pytest.raises(Exception, match="repertoire genre"):
        generator.allowed_clips("tango")


def test_checkpoints_are_checked(tiny_graph, tiny_checkpoint, tmp_path):
    model, state = load_checkpoint(tiny_graph[0])
    assert state["generator"] == "graph"
    with pytest.raises(Exception, match="not a ChoreoGraph checkpoint"):
        load_checkpoint(tiny_checkpoint)


def test_training_runs_every_stage(tmp_path):
    from choreo_graph.config import TrainConfig
    from choreo_graph.data import Excerpts
    from choreo_graph.training import train_graph

    rng = np.random.default_rng(0)
    positions = local_positions(swaying_dance(8.0).joint_positions()).astype(np.float32)

    def excerpts(frames, count=6):
        return Excerpts(np.stack([positions[:frames]] * count), rng.random((count, frames, 96)).astype(np.float32),
                        np.full(count, 2.0, np.float32), [("x", 0)] * count, [None] * count)

    config = TrainConfig(batch_size=3, style_steps=2, motion_tempo_steps=2, music_tempo_steps=2)
    path = train_graph(excerpts(120), excerpts(240), None, tmp_path, TINY, config)
    model, state = load_checkpoint(path)
    assert len(state["training"]["music_tempo_curve"]) == 1 and state["training"]["clip_pairs"] == 6


def test_cli_graph_and_build(tiny_graph, tmp_path, capsys):
    checkpoint, repertoire = tiny_graph
    dance = tmp_path / "sway.bvh"
    from choreo.formats import write_motion

    write_motion(swaying_dance(10.0), dance)
    built = tmp_path / "mine.npz"
    assert main(["graph", "build", "--motion", str(dance), "--genre", "waltz", "--checkpoint", str(checkpoint),
                 "-o", str(built)]) == 0
    assert len(Repertoire.load(built)) == 2
    capsys.readouterr()
    too_slow = tmp_path / "none.npz"  # the swaying dance travels at up to 0.3 m/s: nothing passes 0.1
    assert main(["graph", "build", "--motion", str(dance), "--checkpoint", str(checkpoint), "--max-root-speed", "0.1",
                 "-o", str(too_slow)]) == 2  # bad input: nothing in it can be used
    assert "faster than the speed limit" in capsys.readouterr().err and not too_slow.exists()
    out = tmp_path / "dance.npz"
    code = main(["graph", str(SONG), "-o", str(out), "--checkpoint", str(checkpoint), "--repertoire", str(built), "-k", "2"])
    assert code == 0 and out.exists()
    capsys.readouterr()
    bad = tmp_path / "none.bvh"
    code = main(["graph", str(SONG), "-o", str(bad), "--checkpoint", str(checkpoint), "--repertoire", str(tmp_path / "missing.npz")])
    err = capsys.readouterr().err
    assert code == 2 and not bad.exists() and "does not exist" in err and "Traceback" not in err
    code = main(["graph", str(SONG), "-o", str(bad), "--checkpoint", str(checkpoint), "--repertoire", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and not bad.exists() and "is a folder, expected a file" in err  # was "does not exist"


def test_seeds_give_other_takes_and_the_dance_lists_its_clips(tiny_graph):
    from choreo.finishing import beat_lock

    generator = ChoreoGraphGenerator.from_files(*tiny_graph)
    music = Music.from_file(SONG, end=8.0)
    take = lambda seed: generator.generate(GenerationRequest(music, seed=seed, options={"top_k": 4}))  # noqa: E731
    paper, again, other = take(0), take(0), take(7)
    np.testing.assert_array_equal(paper.rotations, again.rotations)
    assert not np.allclose(paper.rotations, other.rotations)
    np.testing.assert_array_equal(take(7).rotations, other.rotations)
    clips = paper.metadata["clips"]
    assert clips[0]["output_frames"][0] == 0 and clips[-1]["output_frames"][1] >= music.num_frames - 1
    for before, after in zip(clips, clips[1:]):
        assert after["output_frames"][0] == before["output_frames"][1] + 1  # one after another, no gap
    assert all(c["source"] in ("sway", "fast") and c["clip"].startswith(c["source"] + "@") for c in clips)
    first = clips[0]
    source = generator.repertoire.clip_motion(generator.repertoire.names.tolist().index(first["clip"]))
    start = int(first["clip"].rpartition("@")[2])
    # the dance opens on the listed source frame (joint rotations; the root is placed and turned)
    opening = source.sample_frames(np.array([first["source_frames"][0] - start]))
    np.testing.assert_allclose(np.abs(np.sum(paper.rotations[0, 1:] * opening.rotations[0, 1:], -1)), 1.0, atol=1e-3)
    locked = beat_lock(paper, np.arange(0, music.num_frames, 12)).motion
    retimed = locked.metadata["clips"]
    assert retimed[0]["output_frames"][0] == 0 and retimed[-1]["output_frames"][1] == music.num_frames - 1


@pytest.mark.parametrize("flags, words", [
    (("--warp-smoothing", "nan"), "--warp-smoothing takes a finite number"),
    (("--warp-smoothing", "inf"), "--warp-smoothing takes a finite number"),
    (("--warp-smoothing", "1e308"), "warp_smoothing must be 0 to 240"),
    (("--take-variation", "nan"), "--take-variation takes a finite number"),
    (("--take-variation", "inf"), "--take-variation takes a finite number"),
    (("--take-variation", "1e9"), "take_variation must be 0 to 10"),
    (("--floor-radius", "nan"), "--floor-radius takes a finite number"),
    (("--floor-radius", "-1"), "floor_radius must be 0 to inf"),
])
def test_graph_numbers_are_refused_by_name_before_any_work(tmp_path, capsys, flags, words):
    """Issue 48, items 10 and 12: inf and 1e308 were exit 70, NaN was accepted."""
    out = tmp_path / "dance.bvh"
    code = main(["graph", str(SONG), "-o", str(out), *flags])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err and not out.exists(), err
