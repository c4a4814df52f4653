"""JSON documents whose bulk is numbers, read into numpy without a Python object per number.

``json.loads`` makes a float object and a list slot for every number: a 119 MB M2D skeletons.json
took 4.4 GB that way. Here the members named by the caller whose value is a regular array of
numbers (any depth up to :data:`MAX_ARRAY_DEPTH`) are cut out of the text, parsed by numpy in one pass and put
back as a float64 array; the small rest is parsed by ``json``. An array that is ragged, holds
anything but JSON numbers, or sits inside a string is left to ``json`` untouched, so the result
is what ``json.loads`` gives, with arrays for number lists. Nesting too deep for Python (10^6
brackets) is a ``ValueError``, as malformed JSON is, never a ``RecursionError``.
"""

from __future__ import annotations

import json
import math
import re
import secrets
import warnings
from typing import Collection

import numpy as np

MAX_ARRAY_DEPTH = 8
OUTLINE = str.maketrans("", "", "0123456789.eE+- \t\r\n")  # what stays is brackets and commas
DIGIT = re.compile("[0-9]")
ADJACENT = re.compile(r"[0-9.eE+-]\s+[0-9.eE+-]")  # two numbers with no comma between them
# a string (skipped whole, so nothing inside one is touched), and the number array that may follow as its value
MEMBER = re.compile(r'("[^"\\]*(?:\\.[^"\\]*)*")(?:\s*:\s*(\[[-+0-9.eE,\s\[\]]*\]))?')
PUNCTUATION = str.maketrans("[],", "   ")


def loads(text: str, arrays_at: Collection[str] = ()):
    """``json.loads(text)``, with the value of each member named in ``arrays_at`` given as a float64
    ndarray where it is a regular number array (elsewhere, and for other names, as ``json`` gives it)."""
    arrays, pieces, last = [], [], 0
    tag = f"\0numbers-{secrets.token_hex(8)}-"  # a document cannot forge it: it does not know the tag
    for member in MEMBER.finditer(text):
        span = member.span(2)
        wanted = span[0] >= 0 and json.loads(member.group(1)) in arrays_at
        array = _number_array(text[span[0]:span[1]]) if wanted else None
        if array is not None:
            pieces += [text[last:span[0]], json.dumps(f"{tag}{len(arrays)}")]
            arrays.append(array)
            last = span[1]
    pieces.append(text[last:])
    rest = "".join(pieces)
    del pieces

    def restore(members: list) -> dict:
        return {key: arrays[int(value[len(tag):])] if isinstance(value, str) and value.startswith(tag) else value
                for key, value in members}

    try:
        return json.loads(rest, object_pairs_hook=restore)
    except RecursionError:
        raise ValueError("JSON nested too deeply") from None


def _number_array(text: str) -> np.ndarray | None:
    """``text`` (brackets, commas, numbers) as an array when it is a regular number array: its
    outline (the text without numbers and spaces) is that of a regular array, and numpy reads one
    number per element (an array of no numbers at all is left to json). Without a regular expression substitution: that would make a string per
    number. Numpy is a little more lenient than JSON (``+1``, ``.5``, ``01``)."""
    outline = text.translate(OUTLINE)
    shape = _shape(outline)
    if shape is None or not DIGIT.search(text) or outline != _outline(shape) or ADJACENT.search(text):
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns, and stops, where a number does not parse
        try:
            values = np.fromstring(text.translate(PUNCTUATION), dtype=np.float64, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    return values.reshape(shape) if values.size == math.prod(shape) else None


def _shape(outline: str) -> tuple[int, ...] | None:
    """The shape a regular array with this outline has, read off its first element at each depth;
    checked against the whole outline by the caller (and an empty one, ``[]`` like ``[1]``, by
    the count of numbers)."""
    depth = len(outline) - len(outline.lstrip("["))
    if not 0 < depth <= MAX_ARRAY_DEPTH:
        return None
    shape = []
    for level in range(depth):
        end = outline.find("]" * (depth - level), level)
        inner = depth - level - 1
        shape.append(outline.count("]" * inner + "," + "[" * inner, level, end) + 1)
    return tuple(shape)


def _outline(shape: tuple[int, ...]) -> str:
    """The outline of a regular array of ``shape``: its text without numbers and spaces."""
    outline = ""
    for size in reversed(shape):
        outline = "[" + ",".join([outline] * size) + "]"
    return outline
