"""The beat flags (``--bpm``, ``--beats``, ``--beat-tracker``) of every command that reads a song,
declared once: :class:`BeatOptions`, whose :meth:`~BeatOptions.source` is the song's
choreo.music.beat_source.BeatSource. Free of numpy, so that building the command line does not load it."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import ParameterError
from ..options import option

if TYPE_CHECKING:
    from .beat_source import BeatSource

MIN_BPM, MAX_BPM = 20.0, 300.0  # a tempo outside is a typo, not a dance
TRACKERS = ("choreo", "madmom")  # choreo's own (licence-clean, the default); madmom's RNN (non-commercial)


@dataclass(frozen=True, kw_only=True)
class BeatOptions:
    """The beat flags as given (declared here once for every command that reads a song); their
    :meth:`source` is checked, and a beats file read, before any work."""

    bpm: float | None = option(None, "The song's tempo, if you know it: beats exactly 60/BPM s apart, placed on the "
                                     "song's onsets (default: the tracker's tempo).", "--bpm")
    beats: Path | None = option(None, "Beat times to dance to: seconds one a line, or a CSV with a header "
                                      "(time\\[,downbeat]) as DAWs and beat trackers export.", "--beats")
    beat_tracker: str = option("choreo", "Who hears the beats: choreo (licence-clean) or madmom (pip install "
                                         "\"choreo\\[madmom]\"; its models are CC BY-NC-SA 4.0: non-commercial use only).",
                               "--beat-tracker")

    @property
    def given(self) -> bool:
        """Whether any flag replaces choreo's tracker."""
        return self.bpm is not None or self.beats is not None or self.beat_tracker != "choreo"

    def source(self) -> "BeatSource":
        """The source these flags name (default: choreo's tracker); madmom: checked that it is installed."""
        from .beat_file import read_beat_file
        from .beat_source import BeatSource

        if self.bpm is not None and self.beats is not None:
            raise ParameterError("give --bpm or --beats, not both")
        if self.beat_tracker not in TRACKERS:
            raise ParameterError(f"--beat-tracker must be one of {', '.join(TRACKERS)}, got {self.beat_tracker!r}")
        if self.beat_tracker != "choreo":
            if self.bpm is not None or self.beats is not None:
                raise ParameterError("--bpm and --beats replace the tracker: give them without --beat-tracker")
            from .madmom_tracker import load_madmom

            load_madmom()
            return BeatSource(tracker=self.beat_tracker)
        if self.bpm is not None:
            if not (math.isfinite(self.bpm) and MIN_BPM <= self.bpm <= MAX_BPM):
                raise ParameterError(f"--bpm must be {MIN_BPM:g} to {MAX_BPM:g}, got {self.bpm:g}")
            return BeatSource(bpm=float(self.bpm))
        return BeatSource(given=read_beat_file(self.beats)) if self.beats is not None else BeatSource()
