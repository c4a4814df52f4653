"""How often choreo.music.form finds a song's form: sections on the right bar lines, letters right.

    python benchmarks/form_analysis.py [--split validation|test|all] [--json out.json]

The songs and their truths are benchmarks/form_songs.py's (LMMS demo songs whose arrangement is the
truth, and M2D recordings spliced in a known order). A song passes when both hold:
- boundaries: every true boundary has a found one within one bar, and every found one a true one;
- labels: the repeat structure is the truth's up to renaming: each true section is read as the
  found letter most of its bars carry, and two true sections have equal letters exactly when
  their found letters are equal.
The target is at least 90 % of the songs passing. Music analyses are cached (keyed on the file's
path, size and mtime) so a rerun only costs the form analysis.
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from form_songs import CACHE, FormSong, form_songs  # noqa: E402

MUSIC_CACHE = CACHE / "music"


@dataclass(frozen=True)
class Score:
    song: str
    split: str
    truth: str
    found: str
    boundaries_ok: bool
    labels_ok: bool

    @property
    def passed(self) -> bool:
        return self.boundaries_ok and self.labels_ok


def boundaries_match(truth: list[float], found: list[float], bar: float) -> bool:
    """Every true boundary has a found one within ``bar`` seconds, and the other way round
    (boundaries are section starts after the first; the song's start is no boundary)."""
    near = lambda a, bs: any(abs(a - b) <= bar + 1e-6 for b in bs)  # noqa: E731
    return all(near(t, found) for t in truth) and all(near(f, truth) for f in found)


def label_at(sections: list[tuple[float, str]], time: float) -> str:
    """The letter of the section playing at ``time``."""
    label = sections[0][1]
    for start, letter in sections:
        if start <= time + 1e-6:
            label = letter
    return label


def labels_match(truth: list[tuple[float, str]], found: list[tuple[float, str]], duration: float, bar: float) -> bool:
    """The repeat structure is the truth's up to renaming. Each true section takes the found
    letter of most of its bars (sampled at bar centres); then equal true letters must have equal
    found letters and different ones different."""
    ends = [start for start, _ in truth[1:]] + [duration]
    read = []
    for (start, _), end in zip(truth, ends):
        centres = np.arange(start + bar / 2, max(end, start + bar / 2 + 1e-3), bar)
        read.append(Counter(label_at(found, t) for t in centres).most_common(1)[0][0])
    pairs = range(len(truth))
    return all((truth[i][1] == truth[j][1]) == (read[i] == read[j]) for i in pairs for j in pairs)


def score(name: str, split: str, truth: list[tuple[float, str]], found: list[tuple[float, str]],
          duration: float, bar: float) -> Score:
    """Both checks for one song; ``bar`` is the song's bar length in seconds."""
    return Score(name, split, " ".join(l for _, l in truth), " ".join(l for _, l in found),
                 boundaries_match([s for s, _ in truth[1:]], [s for s, _ in found[1:]], bar),
                 labels_match(truth, found, duration, bar))


def cached_music(path: Path):
    """Music.from_file(path), pickled under the cache keyed on path, size and mtime."""
    from choreo.music import Music

    stat = path.stat()
    key = f"{path.stem}-{stat.st_size}-{int(stat.st_mtime)}.pkl"
    cached = MUSIC_CACHE / key
    if cached.is_file():
        return pickle.loads(cached.read_bytes())
    music = Music.from_file(path)
    MUSIC_CACHE.mkdir(parents=True, exist_ok=True)
    cached.write_bytes(pickle.dumps(music))
    return music


def analyse(song: FormSong, analyse_form=None) -> Score:
    """Run the form analysis on one song and score it."""
    if analyse_form is None:
        from choreo.music.form import analyse_form
    music = cached_music(song.path)
    form = analyse_form(music, beats_per_bar=song.beats_per_bar)
    found = [(s.start, s.label) for s in form.sections]
    return score(song.name, song.split, song.sections, found, music.duration, song.bar)


def report(scores: list[Score]) -> str:
    """The table and the share passing, per split and overall."""
    lines = [f"{'song':42} {'split':10} {'truth':14} {'found':22} bounds labels"]
    for s in scores:
        lines.append(f"{s.song[:42]:42} {s.split:10} {s.truth:14} {s.found[:22]:22} "
                     f"{'ok' if s.boundaries_ok else '--':6} {'ok' if s.labels_ok else '--'}")
    for split in sorted({s.split for s in scores}) + ["all"]:
        chosen = [s for s in scores if split in ("all", s.split)]
        passed = sum(s.passed for s in chosen)
        lines.append(f"{split}: {passed}/{len(chosen)} pass ({100 * passed / max(len(chosen), 1):.0f} %; target 90 %)")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--split", default="all", choices=["validation", "test", "all"])
    parser.add_argument("--json", type=Path, help="write the scores here")
    args = parser.parse_args()
    scores = [analyse(song) for song in form_songs(args.split)]
    print(report(scores))
    if args.json:
        args.json.write_text(json.dumps([asdict(s) | {"passed": s.passed} for s in scores], indent=1) + "\n")


if __name__ == "__main__":
    main()
