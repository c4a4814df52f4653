"""Numbers as people type them: one parser for every number choreo reads from a flag or a text file.

Python's ``float`` also takes ``0_5`` (read as 5), fullwidth and other Unicode digits, ``nan``,
``inf`` and ``1e999``; ``int`` takes thousands of digits, then fails past 4,300 with an error of
its own. None of those is a number a user means in a beat time or a flag: each slipped through a
check (NaN compares false with every bound) or overflowed later. Here a number is a plain ASCII
decimal, finite, and short; anything else is refused where it is read, with the text cut short.
"""

from __future__ import annotations

import math
import re

DECIMAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
INTEGER = re.compile(r"[+-]?[0-9]+")
MAX_CHARS = 40  # the longest number anyone types: 17 significant digits, a sign, a point and an exponent
SHOWN_CHARS = 24  # of a refused text, in a message


def decimal(text: str) -> float | None:
    """The value of ``text`` (spaces around it aside) when it is a plain finite decimal; else None."""
    text = text.strip()
    if len(text) > MAX_CHARS or not DECIMAL.fullmatch(text):
        return None
    value = float(text)
    return value if math.isfinite(value) else None  # 1e999 is inf


def integer(text: str) -> int | None:
    """The value of ``text`` when it is a plain decimal integer of at most MAX_CHARS; else None."""
    text = text.strip()
    return int(text) if len(text) <= MAX_CHARS and INTEGER.fullmatch(text) else None


def shown(text: str) -> str:
    """``text`` quoted for a one-line message, cut to SHOWN_CHARS: a 5,000-digit cell is not echoed."""
    return ascii(text if len(text) <= SHOWN_CHARS else text[:SHOWN_CHARS] + "...")
