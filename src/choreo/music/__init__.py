"""Music: decoding, 30 fps features aligned with motion, beats and tempo."""

from .audio import MIN_DURATION, SUPPORTED_EXTENSIONS, audio_duration, iter_audio_blocks, load_audio
from .beats import estimate_beats, estimate_tempo, onset_peaks
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

__all__ = [
    "BEAT_COLUMN", "FEATURE_DIM", "FEATURE_NAMES", "FPS", "HOP_LENGTH", "MIN_DURATION", "Music", "PEAK_COLUMN",
    "SAMPLE_RATE", "SUPPORTED_EXTENSIONS", "audio_duration", "estimate_beats", "estimate_tempo", "frame_features",
    "iter_audio_blocks", "load_audio", "onset_peaks", "stream_features",
]  # fmt: skip
