"""The scoring protocol every quality table uses, reached through the generator interface:
windows as Music, the batch `generate_windows`, and `score_generator`."""

from dataclasses import replace

import numpy as np
import pytest
import soundfile as sf

from choreo.constraints import Constraints
from choreo.datasets import Clip
from choreo.errors import ParameterError
from choreo.generator import GenerationRequest, Generator
from choreo.metrics.protocol import (ScoringSet, clip_log_mels, generate_window_motions, score, score_generator,
                                     window_music, windows_as_dances)
from choreo.motion import Motion, motion_to_vector
from choreo.motion.vector import ROOT_SLICE
from choreo.music import BEAT_COLUMN, FEATURE_DIM
from choreo.music.mel import log_mel_from_file
from tests.conftest import wandering_dance

pytestmark = pytest.mark.filterwarnings("ignore::scipy.linalg.LinAlgWarning")  # six windows: singular covariances
ROOT_AND_ROTATIONS = slice(ROOT_SLICE.start, None)  # the frame vector past the foot contacts
FRAMES = 330  # 11 s: three 5 s scoring windows per clip (starts 0, 75, 150)


def clip(name: str, split: str, seed: int, beat_every: int = 15, audio_path=None) -> Clip:
    rng = np.random.default_rng(seed)
    features = rng.normal(size=(FRAMES, FEATURE_DIM)).astype(np.float32)
    features[:, BEAT_COLUMN] = 0.0
    features[::beat_every, BEAT_COLUMN] = 1.0
    return Clip(name, wandering_dance(seed, FRAMES), features, genre="cha-cha", split=split,
                audio_path=audio_path)


@pytest.fixture(scope="module")
def clips():
    return [clip("a", "train", 0), clip("b", "train", 1), clip("c", "test", 2), clip("d", "test", 3, beat_every=20)]


class Replaying(Generator):
    """Dances each window's own real motion back (found by its music): a perfect backend."""

    name = "replaying"

    def __init__(self, windows):
        self.by_music = {w.features.tobytes(): w.motion for w in windows}
        self.requests = []

    def generate(self, request, progress=None):
        self.requests.append(request)
        return self.by_music[request.music.features.tobytes()]


def test_a_window_becomes_music_with_its_own_features_beats_and_tempo(clips):
    window = ScoringSet.from_clips(clips).windows[3]  # clip d, every 20th frame a beat: 90 bpm
    music = window_music(window)
    assert music.features is window.features and music.num_frames == 150 and music.duration == 5.0
    np.testing.assert_allclose(music.beat_times, np.arange(0, 150, 20) / 30.0)
    assert music.tempo == pytest.approx(90.0)
    assert music.log_mel is None and music.timbre


def test_scoring_set_holds_the_test_windows_and_the_train_dances(clips):
    scoring = ScoringSet.from_clips(clips)
    assert [(w.clip, w.start_frame) for w in scoring.windows] == [(c, s) for c in "cd" for s in (0, 75, 150)]
    assert [d.name for d in scoring.reference] == [f"{c}@{s}" for c in "ab" for s in (0, 75, 150)]


def test_a_perfect_backend_scores_exactly_as_the_real_test_motion(clips):
    scoring = ScoringSet.from_clips(clips)
    backend = Replaying(scoring.windows)
    report, dances = score_generator(backend, scoring, seed=7, options={"anything": 1})
    real = score(windows_as_dances(scoring.clips), scoring.reference)
    assert (report.fid_k, report.fid_g, report.div_k, report.beat_align) == (real.fid_k, real.fid_g, real.div_k,
                                                                            real.beat_align)
    assert [d.name for d in dances] == [f"{c}@{s}" for c in "cd" for s in (0, 75, 150)]
    assert {(r.style, r.seed, r.options["anything"]) for r in backend.requests} == {("cha-cha", 7, 1)}
    score_generator(backend, scoring, with_style=False)
    assert backend.requests[-1].style is None


def test_finished_scoring_runs_the_beat_lock(clips, monkeypatch):
    import choreo.finishing

    finished = []
    monkeypatch.setattr(choreo.finishing, "finish",
                        lambda motion, beats, finishing: finished.append(finishing.foot_lock and finishing.beat_lock) or motion)
    scoring = ScoringSet.from_clips(clips)
    score_generator(Replaying(scoring.windows), scoring, finished=True, foot_lock=True)
    assert finished == [True] * len(scoring.windows)


class Listening(Replaying):
    name = "listening"
    listens_to_spectrum = True


def test_a_backend_that_listens_gets_the_log_mel_under_each_window(tmp_path):
    song = tmp_path / "song.wav"
    rng = np.random.default_rng(0)
    sf.write(song, rng.normal(scale=0.1, size=22050 * 13).astype(np.float32), 22050)
    clips = [clip("a", "train", 0), replace(clip("c", "test", 2), audio_path=str(song), audio_offset=1.0)]
    scoring = ScoringSet.from_clips(clips)
    backend = Listening(scoring.windows)
    with pytest.raises(ParameterError, match="listens to the spectrum"):
        generate_window_motions(backend, scoring.windows)
    score_generator(backend, scoring)
    whole = log_mel_from_file(song, 1.0, FRAMES)
    np.testing.assert_array_equal(clip_log_mels(scoring.clips)["c"], whole)
    for request, start in zip(backend.requests, (0, 75, 150)):
        np.testing.assert_array_equal(request.music.log_mel, whole[start:start + 150])


def requests_for(windows, **fields):
    return [GenerationRequest(window_music(w), style="cha-cha", seed=fields.get("seed", 0),
                              options=fields.get("options", {"steps": 3}), constraints=fields.get("constraints"))
            for w in windows]


def test_sgmd_batch_dances_each_window_on_its_own(tiny_generator, clips):
    windows = ScoringSet.from_clips(clips).windows[:3]
    first = tiny_generator.generate_windows(requests_for(windows))
    assert [m.num_frames for m in first] == [150, 150, 150]
    again = tiny_generator.generate_windows(requests_for(windows))
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a.root_positions, b.root_positions)
    # Another song in window 1 changes window 1 only: no stitching, no shared attention across windows.
    other = [windows[0], replace(windows[1], features=windows[1].features[::-1].copy()), windows[2]]
    changed = tiny_generator.generate_windows(requests_for(other))
    np.testing.assert_array_equal(changed[0].rotations, first[0].rotations)
    np.testing.assert_array_equal(changed[2].rotations, first[2].rotations)
    assert not np.allclose(changed[1].rotations, first[1].rotations)
    reseeded = tiny_generator.generate_windows(requests_for(windows, seed=1))
    assert not np.allclose(reseeded[0].rotations, first[0].rotations)
    single = tiny_generator.generate(requests_for(windows[:1])[0])
    assert all(m.metadata["genre"] == single.metadata["genre"] for m in first)  # the finishing reads it, as for a song


def test_sgmd_batch_keeps_each_windows_constraints_exactly(tiny_generator, clips):
    windows = ScoringSet.from_clips(clips).windows[:2]
    constraints = [Constraints.none(150, 30.0).fix_motion(w.motion.slice_frames(0, 10)) for w in windows]
    motions = tiny_generator.generate_windows([replace(r, constraints=c) for r, c in
                                               zip(requests_for(windows), constraints)])
    for motion, window in zip(motions, windows):
        given, danced = motion_to_vector(window.motion)[:10, ROOT_AND_ROTATIONS], motion_to_vector(motion)[:10, ROOT_AND_ROTATIONS]
        np.testing.assert_allclose(danced, given, atol=1e-5)
        assert not np.allclose(motion.root_positions[10:], window.motion.root_positions[10:], atol=1e-3)


def test_sgmd_batch_refuses_mixed_requests(tiny_generator, clips):
    windows = ScoringSet.from_clips(clips).windows[:2]
    mixed_seeds = requests_for(windows[:1]) + requests_for(windows[1:], seed=1)
    with pytest.raises(ParameterError, match="share their options, seed and length"):
        tiny_generator.generate_windows(mixed_seeds)
    one_constrained = [replace(requests_for(windows[:1])[0], constraints=Constraints.none(150, 30.0).fix_motion(
        windows[0].motion.slice_frames(0, 1)))] + requests_for(windows[1:])
    with pytest.raises(ParameterError, match="all constrained or none"):
        tiny_generator.generate_windows(one_constrained)
    assert tiny_generator.generate_windows([]) == []


def test_the_default_batch_is_generate_one_by_one(tiny_generator, clips):
    windows = ScoringSet.from_clips(clips).windows[:2]
    requests = requests_for(windows)
    batched = Generator.generate_windows(tiny_generator, requests)
    for request, motion in zip(requests, batched):
        single = tiny_generator.generate(request)
        np.testing.assert_array_equal(single.rotations, motion.rotations)
    assert isinstance(batched[0], Motion)
