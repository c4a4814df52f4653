"""Tests of choreo.music.audio.

Markers say where a test came from: fuzz_finding (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("rate", [2, 3999, 1_000_000])
def test_a_wav_claiming_an_absurd_sample_rate_is_refused_at_once(tmp_path, rate):
    """Found by the fuzzer (HANG): a 19 kB WAV whose header said 2 Hz was resampled into 80 minutes of song."""
    import soundfile

    from choreo.errors import AudioError
    from choreo.music.audio import audio_duration

    path = tmp_path / "odd.wav"
    soundfile.write(path, np.zeros(9600, np.float32), rate)
    with pytest.raises(AudioError, match=f"sample rate of {rate} Hz"):
        audio_duration(path)
