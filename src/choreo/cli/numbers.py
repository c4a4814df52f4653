"""Number flags read by :mod:`choreo.numbers`, each within the bounds of what it feeds.

Click's own FLOAT and INT types take ``nan``, ``inf``, ``0_5`` and fullwidth digits, and any
magnitude: such values were accepted and failed late (a dance of NaN frames) or overflowed into
an internal error (a frame rate of ``inf``, a seed of 31 digits). A :class:`Number` (a typer
``parser``) refuses them while the flags are parsed, before any work, in one line naming the flag
(exit 2). Bounds are the constants of the code the value goes to, so flag and library agree.
"""

from __future__ import annotations

import math

from ..errors import ParameterError
from ..numbers import decimal, integer, shown


class Number:
    """Parser of the float flag ``flag`` in [low, high] (``whole``: an int flag). Called on a number
    (a default, or a value typer already parsed), it checks the bounds alone."""

    def __init__(self, flag: str, low: float = -math.inf, high: float = math.inf, whole: bool = False):
        self.flag, self.low, self.high, self.whole = flag, low, high, whole
        self.__name__ = "INTEGER" if whole else "FLOAT"  # typer shows it as the metavar

    def __call__(self, value):
        number = self._parsed(value) if isinstance(value, str) else value
        if number is not None and not self.low <= number <= self.high:  # NaN fails too
            raise ParameterError(f"{self.flag} must be {_range(self.low, self.high)}, got {shown(_text(number))}")
        return number

    def _parsed(self, text: str) -> float:
        number = (integer if self.whole else decimal)(text)
        if number is None:
            kind = "a whole number" if self.whole else "a finite number"
            raise ParameterError(f"{self.flag} takes {kind}, got {shown(text)}")
        return number


def _range(low: float, high: float) -> str:
    if high == math.inf:
        return f"at least {_text(low)}"
    return f"at most {_text(high)}" if low == -math.inf else f"{_text(low)} to {_text(high)}"


def _text(number: float) -> str:
    return str(number) if isinstance(number, int) else f"{number:g}"
