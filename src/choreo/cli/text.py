"""User-supplied text (paths, joint names, genre labels, error messages) made safe to print.

Such text must not steer the terminal (ESC and OSC sequences, bidi overrides), break a one-line
message (a newline in a file name), crash a strict UTF-8 stream (the undecodable bytes of a
non-UTF-8 file name) or be read as rich markup (``[/x]`` raises, ``[red]`` recolours). Every
printing site passes it through :func:`plain` (print, stderr) or :func:`markup` (rich consoles).
"""

from __future__ import annotations

import re

from rich.markup import escape

# C0 and C1 controls, DEL, the Unicode line and paragraph separators, the bidi overrides and
# isolates, and the lone surrogates that stand for bytes of a name that is not UTF-8.
UNSAFE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069\ud800-\udfff]")
NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def plain(text: object) -> str:
    """``text`` on one line of printable characters: controls shown as escapes (``\\x1b``, ``\\n``),
    a byte of a non-UTF-8 name as ``\\xNN``."""
    return UNSAFE.sub(_visible, str(text))


def markup(text: object) -> str:
    """:func:`plain`, and rich markup in it escaped: for f-strings given to a rich console."""
    return escape(plain(text))


def _visible(match: re.Match) -> str:
    char = match.group()
    code = ord(char)
    if char in NAMED:
        return NAMED[char]
    if 0xDC80 <= code <= 0xDCFF:  # os.fsdecode's stand-in for the byte code - 0xDC00
        return f"\\x{code - 0xDC00:02x}"
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}"
