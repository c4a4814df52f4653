"""Music loading, 30 fps features, beats, streaming equivalence and one-line audio errors."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from choreo.errors import AudioError, ParameterError
from choreo.music import (
    BEAT_COLUMN,
    FEATURE_DIM,
    FPS,
    SAMPLE_RATE,
    Music,
    audio_duration,
    frame_features,
    load_audio,
    stream_features,
)
from choreo.music.features import BlockConfig
from tests.music.helpers import click_track, write_song

REPO = Path(__file__).resolve().parents[2]
EXAMPLE_SONG = REPO / "examples" / "drum_and_bass_174bpm.wav"
M2D_SONG = REPO.parent / "shared" / "data" / "m2d" / "DANCE_C_2" / "audio.mp3"


@pytest.mark.parametrize("seconds,frames", [(1.0, 30), (5.0, 150), (180.0, 5400)])
def test_feature_frame_counts(tmp_path, seconds, frames):
    music = Music.from_file(write_song(tmp_path / "song.wav", seconds))
    assert music.features.shape == (frames, FEATURE_DIM)
    assert music.features.dtype == np.float32
    assert np.isfinite(music.features).all()
    assert music.duration == pytest.approx(seconds, abs=1 / FPS)


@pytest.mark.parametrize("extension,options", [(".flac", {}), (".ogg", {"subtype": "VORBIS"}),
                                               (".mp3", {"format": "MP3"}), (".opus", {"format": "OGG", "subtype": "OPUS"})])
def test_compressed_formats_decode(tmp_path, extension, options):
    sr = 48000 if extension == ".opus" else 44100
    path = write_song(tmp_path / f"song{extension}", 5.0, sr=sr, **options)
    music = Music.from_file(path)
    assert abs(music.num_frames - 150) <= 2  # codecs may pad a few milliseconds
    assert 110 < music.tempo < 130


def test_click_track_tempo_and_beats():
    music = Music.from_array(click_track(120, 20.0), 22050)
    assert music.tempo == pytest.approx(120, rel=0.03)
    intervals = np.diff(music.beat_times)
    assert np.median(intervals) == pytest.approx(0.5, abs=1 / FPS)
    np.testing.assert_array_equal(music.beat_frames, np.round(music.beat_times * FPS).astype(int))
    assert music.features[:, BEAT_COLUMN].sum() == len(music.beat_times)
    # Beats sit on the clicks: each within two frames of a multiple of 0.5 s.
    phase = np.abs(music.beat_times - np.round(music.beat_times / 0.5) * 0.5)
    assert phase.max() <= 2 / FPS


def test_example_song_has_its_known_tempo():
    music = Music.from_file(EXAMPLE_SONG)
    # Beat trackers may lock onto half or double time; either is the right tempo family.
    ratios = [music.tempo / bpm for bpm in (87.0, 174.0)]
    assert min(abs(r - 1) for r in ratios) < 0.03, music.tempo
    assert np.median(np.diff(music.beat_times)) * music.tempo / 60 == pytest.approx(1.0, abs=0.05)


def test_streamed_features_equal_whole_signal_features():
    """Blocks with 2 s or more of context reproduce the whole-song computation exactly."""
    samples = load_audio(EXAMPLE_SONG, SAMPLE_RATE)
    samples = np.concatenate([samples, samples])  # ~23 s
    whole = frame_features(samples)[: len(samples) // 512]
    blocks = [samples[i: i + 7001] for i in range(0, len(samples), 7001)]  # odd sizes on purpose
    streamed, _, _ = stream_features(blocks, "test", config=BlockConfig(block_frames=90, context_frames=60))
    np.testing.assert_allclose(streamed[:, :33], whole, atol=1e-4)


def test_excerpt_by_start_and_end(tmp_path):
    path = write_song(tmp_path / "song.wav", 12.0)
    music = Music.from_file(path, start=2.0, end=7.0)
    assert music.num_frames == 150
    assert audio_duration(path) == pytest.approx(12.0, abs=1e-3)


def test_progress_is_reported(tmp_path):
    seen = []
    Music.from_file(write_song(tmp_path / "song.wav", 25.0), progress=lambda done, total: seen.append((done, total)))
    assert seen and seen[-1][0] == pytest.approx(25.0, abs=0.1) and seen[-1][1] == pytest.approx(25.0, abs=0.1)


@pytest.mark.skipif(not M2D_SONG.exists(), reason="../shared/data/m2d not available")
def test_real_mp3_song():
    music = Music.from_file(M2D_SONG, start=10.0, end=40.0)
    assert music.num_frames == 900
    assert 60 < music.tempo < 200 and len(music.beat_times) > 20


def _one_line(error: Exception) -> str:
    text = str(error)
    assert "\n" not in text
    return text


def test_non_audio_file(tmp_path):
    fake = tmp_path / "song.mp3"
    fake.write_text("definitely not audio\n" * 100)
    with pytest.raises(AudioError) as info:
        Music.from_file(fake)
    assert "song.mp3" in _one_line(info.value)


def test_empty_file(tmp_path):
    (tmp_path / "empty.wav").write_bytes(b"")
    with pytest.raises(AudioError, match="empty"):
        Music.from_file(tmp_path / "empty.wav")


def test_silence(tmp_path):
    sf.write(tmp_path / "quiet.wav", np.zeros(22050 * 3, np.float32), 22050)
    with pytest.raises(AudioError, match="silent"):
        Music.from_file(tmp_path / "quiet.wav")


def test_too_short(tmp_path):
    write_song(tmp_path / "blip.wav", 0.2)
    with pytest.raises(AudioError, match="too short"):
        Music.from_file(tmp_path / "blip.wav")


def test_unknown_extension_and_missing_file(tmp_path):
    (tmp_path / "song.xyz").write_bytes(b"\0" * 100)
    with pytest.raises(AudioError, match="unsupported"):
        Music.from_file(tmp_path / "song.xyz")
    with pytest.raises(AudioError, match="no such file"):
        Music.from_file(tmp_path / "absent.wav")


def test_truncated_mp3(tmp_path):
    path = write_song(tmp_path / "song.mp3", 5.0, sr=44100, format="MP3")
    data = path.read_bytes()
    (tmp_path / "cut.mp3").write_bytes(data[: len(data) // 3])
    try:  # a cut mp3 either decodes what is there or fails with one line; never anything else
        music = Music.from_file(tmp_path / "cut.mp3")
        assert music.num_frames < 150
    except AudioError as error:
        _one_line(error)


# VmHWM is this process's own peak: getrusage's ru_maxrss would carry the pytest parent's peak
# over fork and exec, so the child could never report less than the parent and the test could not fail.
PEAK_RSS_SCRIPT = """
import re, sys
from choreo.music import Music
Music.from_file(sys.argv[1])
print(re.search(r"VmHWM:\\s+(\\d+) kB", open("/proc/self/status").read()).group(1))
"""


@pytest.mark.slow
def test_memory_is_flat_in_song_length(tmp_path):
    """Peak RSS for a 40-minute song stays within a small margin of a 4-minute one's."""
    rss = {}
    for minutes in (4, 40):
        path = tmp_path / f"song{minutes}.flac"
        with sf.SoundFile(path, "w", 22050, 1, format="FLAC") as handle:
            block = click_track(120, 60.0)
            for _ in range(minutes):
                handle.write(block)
        out = subprocess.run([sys.executable, "-c", PEAK_RSS_SCRIPT, str(path)], capture_output=True, text=True, check=True)
        rss[minutes] = int(out.stdout.strip()) / 1024  # MiB
    # Features for 40 min are 72000 x 35 float32 = 10 MB; allow that plus slack, not the 210 MB of audio.
    assert rss[40] - rss[4] < 60, rss


def test_streamed_log_mel_equals_the_whole_signal_computation():
    import librosa

    from choreo.music.mel import DB_FLOOR, N_FFT, stream_log_mel

    rng = np.random.default_rng(0)
    signal = (0.1 * rng.standard_normal(SAMPLE_RATE * 3 + 123)).astype(np.float32)
    mel = librosa.feature.melspectrogram(y=signal, sr=SAMPLE_RATE, n_fft=N_FFT, hop_length=512, n_mels=96)
    expected = ((np.clip(librosa.power_to_db(mel, ref=1.0, amin=1e-10, top_db=None), DB_FLOOR, 0) - DB_FLOOR) / -DB_FLOOR).T
    blocks = [signal[i : i + 5000] for i in range(0, len(signal), 5000)]  # blocks shorter than a window too
    streamed = stream_log_mel(blocks)
    assert streamed.shape == expected.shape == (1 + len(signal) // 512, 96)
    np.testing.assert_allclose(streamed, expected, atol=1e-6)


@pytest.fixture(scope="module")
def song(tmp_path_factory):
    return write_song(tmp_path_factory.mktemp("songs") / "song.wav", 9.0)


@pytest.mark.survivor
def test_an_excerpt_may_start_at_zero_or_within_the_first_second_and_have_one_end_only(song):
    assert Music.from_file(song, start=0.0, end=3.0).duration == pytest.approx(3.0, abs=1 / 30)
    assert Music.from_file(song, start=0.5, end=3.0).start == 0.5
    tail = Music.from_file(song, start=6.0)
    assert tail.start == 6.0 and tail.duration == pytest.approx(3.0, abs=1 / 30)
    head = Music.from_file(song, end=4.0)
    assert head.start == 0.0 and head.duration == pytest.approx(4.0, abs=1 / 30)


@pytest.mark.survivor
def test_bad_excerpts_are_refused_with_their_numbers(song):
    with pytest.raises(ParameterError, match=r"^start must be >= 0 seconds, got -1\.0$"):
        Music.from_file(song, start=-1.0)
    with pytest.raises(ParameterError, match=r"^end \(2\.0\) must come after start \(3\.0\)$"):
        Music.from_file(song, start=3.0, end=2.0)
    with pytest.raises(ParameterError, match=r"^end \(3\.0\) must come after start \(3\.0\)$"):
        Music.from_file(song, start=3.0, end=3.0)


@pytest.mark.survivor
def test_an_excerpt_is_decoded_from_its_start_and_reports_its_own_length(song):
    seen = []
    excerpt = Music.from_file(song, start=2.0, end=7.0, progress=lambda done, total: seen.append((done, total)))
    assert {total for _, total in seen} == {5.0} and seen[-1][0] == pytest.approx(5.0, abs=0.1)
    assert excerpt.start == 2.0 and excerpt.duration == pytest.approx(5.0, abs=1 / 30)
    clicks = excerpt.beat_times + 2.0  # the song's clicks fall on whole and half seconds
    assert len(clicks) >= 8 and np.abs(clicks * 2 - np.round(clicks * 2)).max() < 0.05


@pytest.mark.survivor
def test_a_music_from_a_file_carries_its_path_rate_and_default_fields(song):
    music = Music.from_file(song)
    assert music.path == song and music.fps == 30.0 and music.start == 0.0
    assert music.log_mel is None and music.timbre
    assert music.duration == pytest.approx(len(music.features) / 30.0)


@pytest.mark.survivor
def test_the_log_mel_comes_with_the_features_when_asked(song):
    from choreo.music.mel import log_mel_from_file

    music = Music.from_file(song, log_mel=True)
    assert music.log_mel.shape == (music.num_frames, 96)
    np.testing.assert_array_equal(music.log_mel, log_mel_from_file(song, 0.0, music.num_frames))
    rhythm = Music.from_file(song, log_mel=True, timbre=False)
    assert not rhythm.timbre and rhythm.log_mel.shape == (rhythm.num_frames, 96)


@pytest.mark.survivor
def test_a_music_from_an_array_resamples_and_carries_its_fields():
    samples = click_track(120.0, 6.0, 44100)  # float64, another rate
    music = Music.from_array(samples, 44100)
    assert music.path is None and music.fps == 30.0 and music.features.dtype == np.float32
    assert music.features.shape == (180, FEATURE_DIM) and music.duration == pytest.approx(6.0)
    assert music.tempo == pytest.approx(120.0, abs=1.0) and music.log_mel is None
    native = Music.from_array(click_track(120.0, 6.0, SAMPLE_RATE), SAMPLE_RATE, log_mel=True, timbre=False)
    assert native.log_mel.shape == (180, 96) and not native.timbre


@pytest.mark.survivor
def test_a_music_from_an_array_refuses_stereo_and_silence_by_name():
    with pytest.raises(ParameterError, match=r"^from_array expects a mono signal of shape \(N,\)$"):
        Music.from_array(np.zeros((2, SAMPLE_RATE)), SAMPLE_RATE)
    with pytest.raises(AudioError, match="^audio array is silent$"):
        Music.from_array(np.zeros(3 * SAMPLE_RATE), SAMPLE_RATE)


@pytest.mark.survivor
def test_a_stereo_file_is_read(tmp_path):
    stereo = np.stack([click_track(120.0, 4.0, 22050)] * 2, axis=1)
    sf.write(tmp_path / "stereo.wav", stereo, 22050)
    assert Music.from_file(tmp_path / "stereo.wav").num_frames == 120


@pytest.mark.fuzz_finding
def test_a_float_wav_of_huge_finite_samples_is_refused(tmp_path):
    """2e38 is finite, but the mono mix and the spectra overflow to inf (librosa's error before)."""
    import soundfile as sf

    from choreo.errors import AudioError
    from choreo.music import Music

    rate = 22050
    song = 0.3 * np.sin(2 * np.pi * 330 * np.arange(rate) / rate)
    song[100:200] = 2e38
    path = tmp_path / "loud.wav"
    sf.write(path, np.stack([song, song], 1).astype(np.float32), rate, subtype="FLOAT")
    with pytest.raises(AudioError, match="beyond"):
        Music.from_file(path)
