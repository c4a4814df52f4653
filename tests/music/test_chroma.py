"""choreo's numpy chroma_cens against librosa's (the bundled models were trained on librosa's values).

Equality is exact, not approximate: a last-bit difference in the constant-Q transform can push a
value across a CENS quantisation threshold and move the output by a few hundredths, so the port
reproduces librosa's arithmetic and this checks every bit.
"""

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from choreo.music.audio import load_audio
from choreo.music.chroma import chroma_cens

librosa = pytest.importorskip("librosa")  # a test dependency: the reference the port must equal
SR, HOP = 15360, 512  # choreo's feature rate: one hop is one frame at 30 fps
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "drum_and_bass_174bpm.wav"


def _librosa_cens(y, sr=SR, hop=HOP):
    with warnings.catch_warnings():  # "n_fft=... is too large" on short signals
        warnings.simplefilter("ignore")
        return librosa.feature.chroma_cens(y=y, sr=sr, hop_length=hop, tuning=0.0, n_chroma=12)


def _assert_equal_to_librosa(y, sr=SR, hop=HOP):
    ours, theirs = chroma_cens(y, sr, hop), _librosa_cens(y, sr, hop)
    assert ours.shape == theirs.shape == (12, 1 + len(y) // hop)
    assert ours.dtype == theirs.dtype
    np.testing.assert_array_equal(ours, theirs)
    return ours


@pytest.fixture(scope="module")
def example_song():
    """The example song decoded and resampled to 15360 Hz mono as choreo does it."""
    return load_audio(EXAMPLE, SR)


@pytest.mark.parametrize("start, seconds", [(0.0, 4.0), (5.3, 3.0)])
def test_equals_librosa_on_the_example_song(example_song, start, seconds):
    y = example_song[int(start * SR): int((start + seconds) * SR)]
    assert _assert_equal_to_librosa(y).any()


def test_a_pure_tone_peaks_at_its_pitch_class():
    t = np.arange(3 * SR) / SR
    for hz, pitch_class in ((440.0, 9), (261.63, 0), (185.0, 6)):  # A4, C4, F#3
        y = (0.5 * np.sin(2 * np.pi * hz * t)).astype(np.float32)
        chroma = _assert_equal_to_librosa(y)
        middle = chroma[:, 30:-30]
        assert (middle.argmax(axis=0) == pitch_class).all()
        np.testing.assert_allclose(np.linalg.norm(middle, axis=0), 1.0, rtol=1e-6)


def test_silence_and_very_short_signals():
    silent = _assert_equal_to_librosa(np.zeros(SR, np.float32))
    assert not silent.any()  # stays zero: no division by a zero norm
    rng = np.random.default_rng(0)
    for n in (0, 1, 100, HOP - 1, HOP):
        _assert_equal_to_librosa((0.1 * rng.normal(size=n)).astype(np.float32))


@pytest.mark.parametrize("n", [HOP * 40 + 1, 31337, 2 * SR - 1])
def test_odd_lengths(n):
    rng = np.random.default_rng(n)
    t = np.arange(n) / SR
    y = (0.3 * np.sin(2 * np.pi * 330 * t) + 0.05 * rng.normal(size=n)).astype(np.float32)
    _assert_equal_to_librosa(y)


def test_other_rates_hops_and_float64():
    rng = np.random.default_rng(3)
    noise = rng.normal(size=22050).astype(np.float32) * 0.1
    _assert_equal_to_librosa(noise[:11025], 22050, 500)  # the hop halves only once: 500, 250, 125, 125...
    _assert_equal_to_librosa(noise, 44100, 1024)  # the signal is halved once before the top octave
    _assert_equal_to_librosa(rng.normal(size=SR // 2) * 0.1)  # float64 in, float64 out, as librosa


def test_computing_chroma_never_imports_librosa():
    code = ("import sys, numpy as np; from choreo.music.chroma import chroma_cens; "
            "c = chroma_cens(np.sin(np.arange(20000) / 10).astype(np.float32), 15360, 512); "
            "print(c.shape, 'librosa' in sys.modules, 'numba' in sys.modules)")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "(12, 40) False False"
