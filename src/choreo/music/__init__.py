"""Music: decoding, 30 fps features aligned with motion, beats and tempo."""

from .audio import MIN_DURATION, SUPPORTED_EXTENSIONS, audio_duration, iter_audio_blocks, load_audio
from .beat_source import BeatSource
from .beats import BEAT_HOP, estimate_beats, estimate_tempo, onset_envelopes, onset_peaks
from .features import (
    BEAT_COLUMN,
    FEATURE_DIM,
    FEATURE_NAMES,
    FPS,
    HOP_LENGTH,
    PEAK_COLUMN,
    SAMPLE_RATE,
    frame_features,
    stream_features,
)
from .music import Music
from .rhythm import RHYTHM_DIM, RHYTHM_NAMES, beat_phase, rhythm_channels, stretch_features

__all__ = [
    "BEAT_COLUMN", "BeatSource", "FEATURE_DIM", "FEATURE_NAMES", "FPS", "HOP_LENGTH", "MIN_DURATION", "Music", "PEAK_COLUMN", "RHYTHM_DIM", "RHYTHM_NAMES",
    "BEAT_HOP", "SAMPLE_RATE", "SUPPORTED_EXTENSIONS", "audio_duration", "onset_envelopes", "estimate_beats", "estimate_tempo", "frame_features",
    "iter_audio_blocks", "load_audio", "onset_peaks", "stream_features", "beat_phase", "rhythm_channels", "stretch_features",
]  # fmt: skip
