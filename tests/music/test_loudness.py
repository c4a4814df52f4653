"""Loudness per frame and the span of a song with music to dance to."""

import numpy as np
import soundfile as sf

from choreo.music import Music
from choreo.music.loudness import FLOOR_DB, LoudnessStream, audible_span, frame_loudness

SR = 15360  # choreo's analysis rate: 512 samples a frame at 30 fps


def tone(seconds: float, amplitude: float = 0.5, hz: float = 220.0) -> np.ndarray:
    t = np.arange(int(seconds * SR)) / SR
    return (amplitude * np.sin(2 * np.pi * hz * t)).astype(np.float32)


def test_a_sine_reads_its_rms_and_silence_the_floor():
    loudness = frame_loudness(np.concatenate([tone(1.0, 0.5, 240.0), np.zeros(SR, np.float32)]))
    assert len(loudness) == 60
    np.testing.assert_allclose(loudness[:30], 20 * np.log10(0.5 / np.sqrt(2)), atol=0.05)
    np.testing.assert_array_equal(loudness[30:], FLOOR_DB)


def test_streamed_loudness_equals_the_whole_signal_s_in_any_blocks():
    samples = np.random.default_rng(0).normal(0, 0.1, 5 * SR + 77).astype(np.float32)
    stream = LoudnessStream()
    for block in np.split(samples, [1000, 1001, 9000, 40000]):
        stream.push(block)
    np.testing.assert_array_equal(stream.finish(), frame_loudness(samples))


def test_the_audible_span_leaves_out_quiet_ends_but_not_quiet_notes():
    song = np.concatenate([np.zeros(2 * SR), tone(3.0), tone(0.2, 0.05), np.zeros(SR // 5, np.float32),  # a soft note, a gap
                           tone(3.0), tone(4.0, 0.5 * 10 ** (-50 / 20)), np.zeros(SR)])  # a tail 50 dB down, then silence
    first, stop = audible_span(frame_loudness(song))
    assert abs(first - 60) <= 8  # where the music starts, to within the smoothing
    assert abs(stop - 30 * 8.4) <= 8  # the tail 50 dB down does not count: no music to dance to
    assert audible_span(frame_loudness(tone(3.0, 0.001))) == (0, 90)  # a quiet song throughout is still music


def test_music_knows_its_audible_span_from_a_file_or_an_array(tmp_path):
    song = np.concatenate([tone(4.0), np.zeros(3 * SR, np.float32)])
    path = tmp_path / "song.wav"
    sf.write(path, song, SR, subtype="FLOAT")
    from_file, from_array = Music.from_file(path), Music.from_array(song, SR)
    np.testing.assert_array_equal(from_file.loudness, from_array.loudness)
    assert len(from_file.loudness) == from_file.num_frames == 210
    assert abs(from_file.audible[1] - 120) <= 8 and from_file.audible[0] == 0
    rebuilt = Music(path=None, duration=7.0, fps=30.0, features=from_file.features, beat_times=from_file.beat_times,
                    tempo=from_file.tempo)
    assert rebuilt.audible == (0, 210)  # stored features without loudness: music throughout
