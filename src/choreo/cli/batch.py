"""Batches split over machines: shards that cover every song once, re-runs that do only what is missing.

A cluster array job or a CI matrix runs the same command N times with ``--shard K/N``. Each run
must pick its songs from the argument list alone, whatever order the shell expanded it in, so
the split sorts the songs first and deals them out like cards: shard K takes songs K, K + N, ...
(balanced to one song). ``--skip-existing`` leaves a song alone when every output it would write
is there: outputs are written atomically, so a file that exists is complete.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from ..errors import ParameterError
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


def already_written(outputs: Sequence[str]) -> bool:
    """Whether every output file is there (atomic writes: present means complete); stdout never is."""
    return bool(outputs) and all(path != "-" and Path(path).is_file() for path in outputs)
