"""Where a song's beats come from: a tracker (choreo's own, or madmom's opt-in one), a tempo the
user knows, or beat times they give.

Why one value for it: the beats drive the features' beat column (what SGMD reads), the music's
beat times and tempo, and through them the beat lock. A :class:`BeatSource` goes to the one
place a song is analysed (``Music.from_file`` / ``from_array``, then
``choreo.music.features.assemble_features``), so every consumer sees the same beats and no
backend needs to know where they came from.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import InputError
from .beat_file import BeatFile
from .beats import beats_at_tempo, estimate_beats


@dataclass(frozen=True, eq=False)
class BeatSource:
    """A tracker (neither bpm nor given set), a tempo in bpm (phase still tracked), or given beats."""

    bpm: float | None = None
    given: BeatFile | None = None
    tracker: str = "choreo"  # whose tracker hears the beats when neither bpm nor given is set

    @property
    def label(self) -> str:
        """What a dance's metadata records: "tracked", "bpm N", the beats file's name, or madmom's
        tracker with its licence."""
        if self.bpm is not None:
            return f"bpm {self.bpm:g}"
        if self.tracker == "madmom":
            from .madmom_tracker import LICENCE

            return f"madmom ({LICENCE})"
        return self.given.name if self.given is not None else "tracked"

    def heard(self, track) -> "BeatSource":
        """This source with madmom's beats in it, ``track()`` giving them (seconds, the excerpt's
        time); any other source as it is. Why here: madmom listens to the audio itself, at its own
        sample rate, not to the onset envelopes the other sources are placed on."""
        if self.tracker != "madmom" or self.given is not None:
            return self
        return replace(self, given=BeatFile(name="madmom", times=np.asarray(track(), dtype=np.float64)))

    def place(self, envelopes: np.ndarray, envelope_fps: float) -> tuple[float, np.ndarray]:
        """(tempo in bpm, beat times in seconds) for a song whose (2, H) onset envelopes
        (choreo.music.beats.onset_envelopes) are given; they also say where the song ends."""
        if self.bpm is not None:
            return self.bpm, beats_at_tempo(envelopes, envelope_fps, self.bpm)
        if self.given is None:
            return estimate_beats(envelopes, envelope_fps)
        return _tempo_of(self.given.times), self._inside(envelopes.shape[1] / envelope_fps, 1.0 / envelope_fps)

    def excerpt(self, start: float, end: float | None) -> "BeatSource":
        """The same source for the song's [start, end] seconds: given beats moved to the excerpt's
        time and cut to it."""
        if self.given is None or (not start and end is None):
            return self
        times = self.given.times
        keep = (times >= start) & (times <= (end if end is not None else np.inf))
        downbeats = None if self.given.downbeats is None else self.given.downbeats[keep]
        return replace(self, given=replace(self.given, times=times[keep] - start, downbeats=downbeats))

    def _inside(self, seconds: float, tolerance: float) -> np.ndarray:
        times = self.given.times
        if len(times) and times[-1] > seconds + tolerance:
            raise InputError(f"{self.given.name}: a beat at {times[-1]:g} s is past the song's end ({seconds:.2f} s)")
        return times


def _tempo_of(times: np.ndarray) -> float:
    """The tempo given beats keep: 60 / their median spacing (0 for a single beat)."""
    return float(60.0 / np.median(np.diff(times))) if len(times) >= 2 else 0.0
