"""Music loading, 30 fps features, beats, streaming equivalence and one-line audio errors."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from choreo.errors import AudioError
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

REPO = Path(__file__).resolve().parents[1]
EXAMPLE_SONG = REPO / "examples" / "drum_and_bass_174bpm.wav"
M2D_SONG = REPO.parent / "shared" / "data" / "m2d" / "DANCE_C_2" / "audio.mp3"


def click_track(bpm: float, seconds: float, sr: int = 22050) -> np.ndarray:
    """Short decaying noise bursts exactly on the beat, over a quiet tone so no frame is silent."""
    rng = np.random.default_rng(0)
    signal = 0.01 * np.sin(2 * np.pi * 220 * np.arange(int(seconds * sr)) / sr)
    burst = rng.normal(size=int(0.03 * sr)) * np.exp(-np.arange(int(0.03 * sr)) / (0.005 * sr))
    for beat in np.arange(0, seconds, 60.0 / bpm):
        start = int(beat * sr)
        end = min(len(signal), start + len(burst))
        signal[start:end] += burst[: end - start]
    return signal.astype(np.float32)


def write_song(path: Path, seconds: float, sr: int = 22050, bpm: float = 120.0, **kwargs) -> Path:
    sf.write(path, click_track(bpm, seconds, sr), sr, **kwargs)
    return path


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
