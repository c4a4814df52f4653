"""What the music-features mutation run (scripts/mutation_score.py music-features) found untested
in `Music`: the excerpt checks and their messages, progress over an excerpt, the log-mel from the
same decode, and the fields a `Music` made from a file or an array carries."""

import numpy as np
import pytest
import soundfile as sf

from choreo.errors import AudioError, ParameterError
from choreo.music import FEATURE_DIM, SAMPLE_RATE, Music
from tests.test_music import click_track, write_song


@pytest.fixture(scope="module")
def song(tmp_path_factory):
    return write_song(tmp_path_factory.mktemp("songs") / "song.wav", 9.0)


def test_an_excerpt_may_start_at_zero_or_within_the_first_second_and_have_one_end_only(song):
    assert Music.from_file(song, start=0.0, end=3.0).duration == pytest.approx(3.0, abs=1 / 30)
    assert Music.from_file(song, start=0.5, end=3.0).start == 0.5
    tail = Music.from_file(song, start=6.0)
    assert tail.start == 6.0 and tail.duration == pytest.approx(3.0, abs=1 / 30)
    head = Music.from_file(song, end=4.0)
    assert head.start == 0.0 and head.duration == pytest.approx(4.0, abs=1 / 30)


def test_bad_excerpts_are_refused_with_their_numbers(song):
    with pytest.raises(ParameterError, match=r"^start must be >= 0 seconds, got -1\.0$"):
        Music.from_file(song, start=-1.0)
    with pytest.raises(ParameterError, match=r"^end \(2\.0\) must come after start \(3\.0\)$"):
        Music.from_file(song, start=3.0, end=2.0)
    with pytest.raises(ParameterError, match=r"^end \(3\.0\) must come after start \(3\.0\)$"):
        Music.from_file(song, start=3.0, end=3.0)


def test_an_excerpt_is_decoded_from_its_start_and_reports_its_own_length(song):
    seen = []
    excerpt = Music.from_file(song, start=2.0, end=7.0, progress=lambda done, total: seen.append((done, total)))
    assert {total for _, total in seen} == {5.0} and seen[-1][0] == pytest.approx(5.0, abs=0.1)
    assert excerpt.start == 2.0 and excerpt.duration == pytest.approx(5.0, abs=1 / 30)
    clicks = excerpt.beat_times + 2.0  # the song's clicks fall on whole and half seconds
    assert len(clicks) >= 8 and np.abs(clicks * 2 - np.round(clicks * 2)).max() < 0.05


def test_a_music_from_a_file_carries_its_path_rate_and_default_fields(song):
    music = Music.from_file(song)
    assert music.path == song and music.fps == 30.0 and music.start == 0.0
    assert music.log_mel is None and music.timbre
    assert music.duration == pytest.approx(len(music.features) / 30.0)


def test_the_log_mel_comes_with_the_features_when_asked(song):
    from choreo.music.mel import log_mel_from_file

    music = Music.from_file(song, log_mel=True)
    assert music.log_mel.shape == (music.num_frames, 96)
    np.testing.assert_array_equal(music.log_mel, log_mel_from_file(song, 0.0, music.num_frames))
    rhythm = Music.from_file(song, log_mel=True, timbre=False)
    assert not rhythm.timbre and rhythm.log_mel.shape == (rhythm.num_frames, 96)


def test_a_music_from_an_array_resamples_and_carries_its_fields():
    samples = click_track(120.0, 6.0, 44100)  # float64, another rate
    music = Music.from_array(samples, 44100)
    assert music.path is None and music.fps == 30.0 and music.features.dtype == np.float32
    assert music.features.shape == (180, FEATURE_DIM) and music.duration == pytest.approx(6.0)
    assert music.tempo == pytest.approx(120.0, abs=1.0) and music.log_mel is None
    native = Music.from_array(click_track(120.0, 6.0, SAMPLE_RATE), SAMPLE_RATE, log_mel=True, timbre=False)
    assert native.log_mel.shape == (180, 96) and not native.timbre


def test_a_music_from_an_array_refuses_stereo_and_silence_by_name():
    with pytest.raises(ParameterError, match=r"^from_array expects a mono signal of shape \(N,\)$"):
        Music.from_array(np.zeros((2, SAMPLE_RATE)), SAMPLE_RATE)
    with pytest.raises(AudioError, match="^audio array is silent$"):
        Music.from_array(np.zeros(3 * SAMPLE_RATE), SAMPLE_RATE)


def test_a_stereo_file_is_read(tmp_path):
    stereo = np.stack([click_track(120.0, 4.0, 22050)] * 2, axis=1)
    sf.write(tmp_path / "stereo.wav", stereo, 22050)
    assert Music.from_file(tmp_path / "stereo.wav").num_frames == 120
