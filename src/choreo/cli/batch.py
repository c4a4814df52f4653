"""Batches split over machines: shards that cover every song once, re-runs that do only what is missing.

A cluster array job or a CI matrix runs the same command N times with ``--shard K/N``. Each run
must pick its songs from the argument list alone, whatever order the shell expanded it in, so
the split sorts the songs first and deals them out like cards: shard K takes songs K, K + N, ...
(balanced to one song). ``--skip-existing`` leaves a song alone when every output it would write
is there and whole: choreo writes atomically, but a copy cut short or another tool can leave a
zero-byte or truncated file, so each is checked by its structure (``choreo.formats.complete``).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from ..errors import OutputError, ParameterError
from ..numbers import shown

# ASCII digits (\d also takes fullwidth ones), at most 9 of them: int() of thousands fails (exit 70)
SHARD = re.compile(r"\s*([0-9]{1,9})\s*/\s*([0-9]{1,9})\s*")


@dataclass(frozen=True)
class Shard:
    index: int  # 1-based, as Slurm's and GitHub's 1..N numbering reads
    count: int

    @classmethod
    def parse(cls, text: str) -> "Shard":
        match = SHARD.fullmatch(text)
        if not match:
            raise ParameterError(f"--shard takes K/N, e.g. 2/8 (the second of eight), got {shown(text)}")
        index, count = int(match[1]), int(match[2])
        if not 1 <= index <= count:
            raise ParameterError(f"--shard {index}/{count}: K must be 1 to N")
        return cls(index, count)

    def select(self, songs: Sequence[Path]) -> list[Path]:
        """This shard's songs, in their sorted order."""
        ordered = sorted(songs, key=lambda song: (song.name, os.fsencode(song)))
        return ordered[self.index - 1:: self.count]


def batch_formats(text: str | None, rig: str | None = None) -> list[str]:
    """The formats of --out-dir's ``--format`` list (default bvh), each once (``bvh,BVH,.bvh`` is one
    file), all checked before the first song: a list of none (``,``) danced every song and wrote
    nothing, an unknown name failed song by song."""
    from ..formats import FORMATS, check_output_format

    names = [name.strip().lower().lstrip(".") for name in ("bvh" if text is None else text).split(",")]
    formats = list(dict.fromkeys(name for name in names if name))
    if not formats:
        raise ParameterError(f"--format {shown(text)} names no format (e.g. bvh,npz)")
    unknown = [name for name in formats if name not in FORMATS]
    if unknown:  # exit 3, as an unknown -o extension is
        raise OutputError(f"--format: unknown motion format {shown(unknown[0])} (supported: {', '.join(FORMATS)})")
    for name in formats:
        check_output_format(f"dance.{name}", None, rig)  # --rig and Blender, before any song
    return formats


def already_written(outputs: Sequence[str]) -> bool:
    """Whether every output file is there and whole (see the module's docstring); stdout never is."""
    from ..formats.complete import looks_complete

    return bool(outputs) and all(path != "-" and looks_complete(path) for path in outputs)
