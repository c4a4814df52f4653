"""Music: decoding, 30 fps features aligned with motion, beats and tempo (each name loads its
module on first use: choreo.lazy)."""

from ..lazy import lazy_exports

_HOMES = {
    ".audio": ("MIN_DURATION", "SUPPORTED_EXTENSIONS", "audio_duration", "iter_audio_blocks", "load_audio"),
    ".beat_options": ("BeatOptions",),
    ".beat_source": ("BeatSource",),
    ".beats": ("BEAT_HOP", "estimate_beats", "estimate_tempo", "onset_envelopes", "onset_peaks"),
    ".features": ("BEAT_COLUMN", "FEATURE_DIM", "FEATURE_NAMES", "FPS", "HOP_LENGTH", "PEAK_COLUMN", "SAMPLE_RATE",
                  "frame_features", "stream_features"),
    ".music": ("Music",),
    ".rhythm": ("RHYTHM_DIM", "RHYTHM_NAMES", "beat_phase", "rhythm_channels", "stretch_features"),
}
_EXPORTS = {name: module for module, names in _HOMES.items() for name in names}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
