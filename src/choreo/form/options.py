"""The form flags of every dancing command, declared once (free of numpy, like the beat flags)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ParameterError
from ..options import option


AUTO = "auto"  # --form auto: the form analysed from the music (choreo.music.form.analyse_form)


@dataclass(frozen=True, kw_only=True)
class FormOptions:
    """How the song's form shapes the dance: none (the default: every section danced afresh), the
    analysed one (``--form auto``) or the user's, and how exactly a return's dance returns.

    Off by default because the analysis finds the right sections and letters in half of the songs
    of known form (docs/form.md): a wrong return is a phrase copied where the music does not repeat."""

    form: str | None = option(None, "The song's form, for a dance whose returning sections return: TIME=LETTER entries, "
                                    "a letter that comes back is a return (e.g. 0:00=A,0:16=B,0:32=A), or auto to "
                                    "analyse it from the music. Default: every section danced afresh.", "--form")
    returns: float = option(1.0, "How exactly a returning section's dance returns: 0 dances it afresh, 1 repeats the "
                                 "first one's phrase on the new beats.", "--returns", bounds=(0.0, 1.0))
    mirror_returns: bool = option(False, "Let every other return come back mirrored (left and right swapped).",
                                  "--mirror-returns")

    def __post_init__(self):
        if not (math.isfinite(self.returns) and 0.0 <= self.returns <= 1.0):
            raise ParameterError(f"--returns must be 0 to 1, got {self.returns:g}")
        if self.given:
            from ..music.form import parse_form

            parse_form(self.form, math.inf)  # its syntax, before any song is read

    @property
    def given(self) -> bool:
        """Whether the user wrote the form out."""
        return self.form is not None and self.form.strip().lower() != AUTO

    @property
    def active(self) -> bool:
        """Whether the dance is shaped at all: a form asked for, and returns not 0."""
        return self.form is not None and self.returns > 0

    @property
    def analysed(self) -> bool:
        """Whether the form comes from the music (--form auto, returns not 0)."""
        return self.active and not self.given

    def of(self, music, style: str | None = None):
        """The song's form (choreo.music.form.Form): the one given, the analysed one with --form
        auto, else None (nothing to analyse)."""
        from ..music.form import analyse_form, beats_per_bar, parse_form

        if self.given:
            return parse_form(self.form, music.duration)
        return analyse_form(music, beats_per_bar(style)) if self.active else None
