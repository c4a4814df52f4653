"""choreo.looping: dances that loop, as an engine plays them over and over."""

import numpy as np
import pytest

import choreo
from choreo.errors import ParameterError
from choreo.looping import Loop
from choreo.metrics.loops import seam
from choreo.motion import Motion
from choreo.motion.delivery import delivered_loop
from choreo.motion.seam import bent_into, next_cycle
from choreo.music import Music

SONG = "examples/drum_and_bass_174bpm.wav"


def music(seconds: float = 10.2, beat: float = 0.5, first: float = 0.25) -> Music:
    """Beats every ``beat`` s from ``first``; feature column 0 names each frame."""
    frames = int(seconds * 30)
    features = np.zeros((frames, 35), np.float32)
    features[:, 0] = np.arange(frames)
    return Music(path=None, duration=frames / 30, fps=30.0, features=features,
                 beat_times=np.arange(first, seconds, beat), tempo=60 / beat)


def circling(frames: int = 300, turn: float = np.pi / 2) -> Motion:
    """A dancer turning ``turn`` per ``frames`` while walking a circle, arms swinging: a loop with
    a per-cycle turn and travel, its metadata saying so."""
    t = np.arange(frames)
    angle = turn * t / frames
    root = np.stack([np.sin(angle), np.full(frames, 0.9), np.cos(angle)], -1) * [2.0, 1.0, 2.0]
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 0, 1] = angle + np.pi / 2
    axis_angle[:, 16, 2] = 0.5 * np.sin(2 * np.pi * 4 * t / frames)  # four swings a cycle: periodic
    motion = Motion.from_axis_angle(root, axis_angle, fps=30.0)
    start, end = root[0] * [1, 0, 1], np.array([np.sin(turn), 0.0, np.cos(turn)]) * 2.0
    offset = end - np.array([np.cos(turn) * start[0] + np.sin(turn) * start[2], 0.0,
                             -np.sin(turn) * start[0] + np.cos(turn) * start[2]])
    motion.metadata = {"loop": {"bars": 5, "beats_per_bar": 4, "seconds": frames / 30,
                                "turn_degrees": float(np.degrees(turn)), "travel_m": [offset[0], offset[2]]}}
    return motion


def test_a_loop_is_the_songs_whole_bars_from_its_start():
    loop = Loop.of(music(), "cha-cha")
    assert (loop.bars, loop.beats_per_bar, loop.frames) == (5, 4, 300)  # 5 bars of 2 s; a sixth ends past 10.2 s
    assert (loop.lead_in, loop.returning, loop.after) == (120, 8, 30)  # 4 s before, 0.25 s given again of 1 s after
    waltz = Loop.of(music(), "Viennese waltz")
    assert (waltz.bars, waltz.beats_per_bar, waltz.frames) == (6, 3, 270)
    assert Loop.of(music(seconds=8.3), None).bars == 4  # the last bar's closing beat lies past the end, at the tempo
    deaf = music()
    deaf = Music(path=None, duration=deaf.duration, fps=30.0, features=deaf.features, beat_times=deaf.beat_times[:8],
                 tempo=120.0)  # a tracker that stops hearing after 4 s: the bars go on at its tempo
    assert Loop.of(deaf, None).frames == 300
    with pytest.raises(ParameterError, match=r"^--loop needs a whole bar \(4 beats\) in the song; it is shorter than one \(4 beats heard in 1.9 s\)$"):
        Loop.of(music(seconds=1.9), None)


def test_the_loop_is_danced_to_its_end_then_itself_then_its_opening():
    song = music()
    loop = Loop.of(song, None)
    danced = loop.music(song)
    order = danced.features[:, 0].astype(int)
    lead = loop.lead_in
    assert lead == 120 and danced.num_frames == lead + 300 + lead
    np.testing.assert_array_equal(order, np.r_[np.arange(180, 300), np.arange(300), np.arange(120)])
    assert loop.span == slice(120, 420)
    beats = danced.beat_times
    np.testing.assert_allclose(beats[beats < 4.0], np.arange(6.25, 10.0, 0.5) - 6.0)  # the loop's last 4 s
    np.testing.assert_allclose(beats[(beats >= 4.0) & (beats < 14.0)], np.arange(0.25, 10.0, 0.5) + 4.0)
    np.testing.assert_allclose(beats[beats >= 14.0], np.arange(0.25, 4.0, 0.5) + 14.0)
    danced = loop.music(song, loop.after)  # what the two takes dance: a second of the opening after the end
    assert danced.num_frames == 120 + 300 + 30 and danced.beat_times[-1] == pytest.approx(14.75)
    loud = Music(path=None, duration=song.duration, fps=30.0, features=song.features, beat_times=song.beat_times,
                 tempo=song.tempo, loudness=np.arange(song.num_frames, dtype=np.float32))
    np.testing.assert_array_equal(loop.music(loud).loudness, order)  # the loudness goes round with the frames


def test_a_bend_runs_the_end_into_the_given_frames_pose_and_velocity():
    frames = 60
    root = np.stack([np.linspace(0, 1, frames), np.full(frames, 0.9), np.zeros(frames)], -1)
    motion = Motion.from_axis_angle(root, np.zeros((frames, 24, 3)), fps=30.0)
    after = Motion.from_axis_angle(np.array([[1.2, 0.95, 0.1], [1.25, 0.96, 0.14]]), np.full((2, 24, 3), 0.2), fps=30.0)
    bent = bent_into(motion, after, frames, 15)
    np.testing.assert_array_equal(bent.root_positions[:frames - 15], motion.root_positions[:frames - 15])
    np.testing.assert_array_equal(bent.rotations[:frames - 15], motion.rotations[:frames - 15])
    joined = Motion.concatenate([bent, after]).joint_positions()
    steps = np.diff(joined, axis=0)
    velocity_change = np.linalg.norm(np.diff(steps, axis=0), axis=-1).max(axis=1)
    before = np.linalg.norm(np.diff(np.diff(Motion.concatenate([motion, after]).joint_positions(), axis=0), axis=0),
                            axis=-1).max(axis=1)
    assert velocity_change[frames - 2] < 0.15 * before[frames - 2]  # into the given frames: as smooth as the rest
    assert velocity_change[frames - 15:].max() < 0.3 * before.max()


def test_a_loop_at_another_rate_or_in_place_is_still_a_loop():
    motion = circling()  # steps all alike: a seam as smooth as the rest scores 1
    assert max(seam(motion)) < 1.01
    wrong = motion.replace(metadata={"loop": dict(motion.metadata["loop"], turn_degrees=0.0)})
    assert seam(wrong)[0] > 50  # a loop that does not run into its next cycle jumps
    for fps in (24.0, 60.0):
        faster = delivered_loop(motion, fps)
        assert faster.fps == fps and faster.num_frames == round(300 * fps / 30)
        assert max(seam(faster)) < 1.01
    still = delivered_loop(motion, None, without_travel=True)
    assert np.linalg.norm(np.diff(still.root_positions[:, [0, 2]], axis=0), axis=-1).sum() < 0.5  # it stays put
    assert max(seam(still)) < 1.05 and still.metadata["loop"]["turn_degrees"] == pytest.approx(90.0)
    assert np.linalg.norm(next_cycle(still).root_positions[0, [0, 2]] - still.root_positions[0, [0, 2]]) < 0.1


@pytest.mark.parametrize("generator", ["sgmd", "graph"])
def test_both_backends_dance_a_loop_that_ends_where_it_began(generator):
    dance = choreo.dance(SONG, generator, style="cha-cha", seed=1, loop=True, threads=1)
    loop = dance.metadata["loop"]
    assert loop["beats_per_bar"] == 4 and loop["bars"] >= 3 and dance.duration <= 11.6
    assert abs(dance.duration - loop["seconds"]) < 1e-3
    step, velocity = seam(dance)  # in root-local space: the next cycle turned and moved by the loop's own
    assert step <= 1.0 and velocity <= 1.0, (step, velocity)


def test_a_loop_keeps_no_given_frames():
    with pytest.raises(ParameterError, match="--loop leads the dance back into its own opening"):
        choreo.dance(SONG, "sgmd", loop=True, constraints=lambda music: None)
