"""Songs whose form is known, to score choreo.music.form against (benchmarks/form_analysis.py).

    python benchmarks/form_songs.py                  # build every song's audio once (cache), list them
    python benchmarks/form_songs.py --make-recipes   # re-derive form_songs.json (curation, splices)

Two kinds, both recorded in benchmarks/form_songs.json (truths and recipes only: the audio is not
ours to commit and is rebuilt on demand into the cache, ~/.cache/choreo/form-songs or
$CHOREO_CACHE_DIR/form-songs):

- "lmms": LMMS's demo songs (benchmarks/outside_songs.py renders them). The project file is the
  score: its song editor places clips on a tick grid, so which clips sound in each bar is known
  exactly, and a section is a run of bars with the same clips. Only songs whose form that way is
  clear (a few sections, at least one return, sections of several bars) are kept.
- "spliced": real ballroom recordings (M2D) cut into 8-bar segments at tracked bar lines and joined
  in a chosen order (A B A B, A A B A, ...). All segments come from one recording, so the tempo and
  the sound stay; a return takes the recording's own repeat of the passage where there is one, so
  the analysis cannot pass by spotting copied samples.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from outside_songs import CACHE as LMMS_CACHE, LMMS_PROJECTS, project_bpm, project_xml, render  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
RECIPES = Path(__file__).with_name("form_songs.json")
CACHE = Path(os.environ.get("CHOREO_CACHE_DIR", Path.home() / ".cache" / "choreo")) / "form-songs"
M2D = REPO.parent / "shared" / "data" / "m2d"

TICKS_PER_QUARTER = 48  # LMMS: 192 ticks per 4/4 bar; its tempo counts quarter notes
MIN_SECTION_BARS = 2  # a shorter run of bars (a fill, a break) joins its neighbour
CROSSFADE = 0.010  # seconds, at each splice
SEGMENT_BARS = 8
MAX_SECTIONS = 14
MAX_SECONDS = 120  # a spliced song's longest
SPLICE_FORMS = ("A B A B", "A A B A", "A B A C A", "A B A B C B")
SPLICE_CLIPS = ("DANCE_C_2", "DANCE_C_4", "DANCE_C_6", "DANCE_R_2", "DANCE_R_3", "DANCE_R_5", "DANCE_R_7",
                "DANCE_T_5", "DANCE_W_1", "DANCE_W_4", "DANCE_W_15", "DANCE_W_26", "DANCE_W_30")


@dataclass(frozen=True)
class FormSong:
    """One benchmark song: its audio, its truth [(start seconds, letter)], its metre (beats per
    bar, bar length in seconds: the scoring's tolerance) and split."""

    name: str
    path: Path
    sections: list[tuple[float, str]]
    beats_per_bar: int
    bar: float
    kind: str
    split: str


# ---------------------------------------------------------------- LMMS: the arrangement is the truth


@dataclass(frozen=True)
class Clip:
    """One clip placed in the song editor: [start, end) ticks and what it plays (track + content)."""

    key: str
    start: int
    end: int


@dataclass(frozen=True)
class Arrangement:
    bpm: float
    ticks_per_bar: int
    beats_per_bar: int
    clips: tuple[Clip, ...]

    @property
    def bars(self) -> int:
        return -(-max(c.end for c in self.clips) // self.ticks_per_bar) if self.clips else 0

    @property
    def seconds_per_bar(self) -> float:
        return self.ticks_per_bar / TICKS_PER_QUARTER * 60.0 / self.bpm


def _digest(*parts) -> str:
    return hashlib.sha1(repr(parts).encode()).hexdigest()[:10]


def _notes(pattern: ET.Element) -> tuple:
    """A pattern's content, order-free: what makes two clips on a track sound the same."""
    return tuple(sorted((int(n.get("pos", 0)), int(n.get("len", 0)), int(n.get("key", 0)))
                        for n in pattern.iter("note")))


def _audible(element: ET.Element) -> bool:
    return element.get("muted", "0") != "1"


def _bb_contents(song_tracks: list[ET.Element]) -> dict[int, str]:
    """Beat/bassline index -> a digest of what it plays. LMMS keeps all beat/basslines in one
    container: in each of its tracks the pattern at tick index * 192 belongs to beat/bassline index.
    Two indices that play the same notes get the same digest (they sound the same)."""
    contents: dict[int, list] = {}
    for track in song_tracks:
        for inner in track.findall("bbtrack/trackcontainer/track"):
            if not _audible(inner):
                continue
            for pattern in inner.findall("pattern"):
                notes = _notes(pattern)
                if notes:
                    contents.setdefault(int(pattern.get("pos", 0)) // 192, []).append((inner.get("name"), notes))
    return {index: _digest(sorted(parts)) for index, parts in contents.items()}


def _track_clips(track: ET.Element, track_index: int, bb_index: int | None, bbs: dict[int, str]) -> list[Clip]:
    """The audible clips of one song-editor track; empty patterns and beat/basslines are left out."""
    clips = []
    for element in track:
        if not _audible(element) or element.tag not in ("pattern", "bbtco", "sampletco"):
            continue
        start, length = int(element.get("pos", 0)), int(element.get("len", 0))
        if element.tag == "pattern":
            notes = _notes(element)
            key = f"t{track_index}:{_digest(notes)}" if notes else None
        elif element.tag == "bbtco":
            key = f"bb:{bbs[bb_index]}" if bb_index in bbs else None
        else:
            key = f"t{track_index}:{_digest(element.get('src'), length, element.get('off'))}"
        if key is not None and length > 0:
            clips.append(Clip(key, start, start + length))
    return clips


def parse_arrangement(xml: str) -> Arrangement:
    """The song editor of an LMMS project: tempo, bar length and every audible clip.

    Clips are named by content (the notes of a pattern and its track; a beat/bassline by what it
    plays), so a copy of a pattern placed later counts as the same music returning. Time
    signatures are read as bars of 192 * numerator / denominator ticks; bars longer than 4/4
    (8/4) are cut into 4/4 bars, what a listener hears."""
    root = ET.fromstring(xml)
    head = root.find("head")
    bpm = float(head.get("bpm", 140))
    numerator, denominator = int(head.get("timesig_numerator", 4)), int(head.get("timesig_denominator", 4))
    ticks_per_bar = 192 * numerator // denominator
    if ticks_per_bar % 192 == 0:
        ticks_per_bar = 192
    tracks = root.findall("song/trackcontainer/track")
    bbs = _bb_contents(tracks)
    clips, bb_index = [], 0
    for index, track in enumerate(tracks):
        own_bb = bb_index if track.get("type") == "1" else None
        bb_index += track.get("type") == "1"
        if _audible(track) and track.get("type") in ("0", "1", "2"):
            clips += _track_clips(track, index, own_bb, bbs)
    return Arrangement(bpm, ticks_per_bar, ticks_per_bar // TICKS_PER_QUARTER, tuple(clips))


def bar_sets(arrangement: Arrangement) -> list[frozenset[str]]:
    """For each bar, the clips that sound in at least half of it (a clip entering on the last beat
    is a pickup, not the bar's music)."""
    tpb = arrangement.ticks_per_bar
    sets = []
    for bar in range(arrangement.bars):
        lo, hi = bar * tpb, (bar + 1) * tpb
        sets.append(frozenset(c.key for c in arrangement.clips if min(hi, c.end) - max(lo, c.start) >= tpb / 2))
    while sets and not sets[-1]:
        sets.pop()
    return sets


def _runs(values: list) -> list[list]:
    """[first bar, bar count, value] for each maximal run of equal values."""
    runs: list[list] = []
    for bar, value in enumerate(values):
        if runs and runs[-1][2] == value:
            runs[-1][1] += 1
        else:
            runs.append([bar, 1, value])
    return runs


def bar_sections(sets: list[frozenset[str]], min_bars: int = MIN_SECTION_BARS) -> list[tuple[int, str]]:
    """Sections [(first bar, letter)]: runs of bars with the same clips; a run shorter than
    ``min_bars`` joins the section before it (the first one the one after); equal clip sets, equal
    letters, named A, B, C... in order of appearance."""
    runs = _runs(list(sets))
    merged: list[list] = []
    for run in runs:
        if merged and (run[1] < min_bars or run[2] == merged[-1][2]):
            merged[-1][1] += run[1]
        elif not merged or merged[-1][1] >= min_bars:
            merged.append(list(run))
        else:  # the song opened with a short run: it belongs to this one
            merged[-1] = [merged[-1][0], merged[-1][1] + run[1], run[2]]
    names: dict = {}
    from choreo.music.form import letters

    alphabet = letters(len(merged))
    return [(first, names.setdefault(value, alphabet[len(names)])) for first, _, value in merged]


def clear_form(sections: list[tuple[int, str]], bars: int) -> str | None:
    """Why a bar-level form is no use as a truth, or None when it is: at least 3 and fewer than 12
    sections (14: one long song with many returns is worth keeping), some letter returning, and most sections at least 4 bars long."""
    lengths = np.diff([first for first, _ in sections] + [bars])
    labels = [label for _, label in sections]
    if not 3 <= len(sections) <= MAX_SECTIONS:
        return f"{len(sections)} sections"
    if len(set(labels)) == len(labels):
        return "no section returns"
    if np.mean(lengths >= 4) < 0.75:
        return f"short sections ({list(lengths)} bars)"
    return None


def lmms_truth(project: Path) -> dict:
    """The json entry of one LMMS song, with "excluded" set to the reason it is no use."""
    arrangement = parse_arrangement(project_xml(project))
    sets = bar_sets(arrangement)
    sections = bar_sections(sets)
    reason = "tempo automated" if project_bpm(project) is None else clear_form(sections, len(sets))
    return {"name": project.stem, "kind": "lmms", "project": str(project.relative_to(LMMS_PROJECTS)),
            "bpm": arrangement.bpm, "beats_per_bar": arrangement.beats_per_bar, "bars": len(sets),
            "seconds_per_bar": arrangement.seconds_per_bar,
            "form": " ".join(label for _, label in sections),
            "sections": [[round(first * arrangement.seconds_per_bar, 3), label] for first, label in sections],
            "section_bars": [first for first, _ in sections], "excluded": reason}


def lmms_projects() -> list[Path]:
    return sorted((p for folder in ("demos", "shorties") for p in (LMMS_PROJECTS / folder).rglob("*.mmp*")),
                  key=lambda p: p.stem)


# ---------------------------------------------------------------- spliced M2D recordings


def splice(samples: np.ndarray, sr: int, pieces: list[tuple[float, float]], fade: float = CROSSFADE) -> np.ndarray:
    """The pieces [start, end) seconds of ``samples`` joined in order. Each join is a crossfade of
    ``fade`` seconds centred on the cut, from the outgoing piece's own continuation into the
    incoming one's lead-in, so there is no click and the song is exactly the pieces' length (the
    truth's section starts stay on the joins)."""
    half = int(round(fade * sr / 2))
    bounds = [(int(round(start * sr)), int(round(end * sr))) for start, end in pieces]
    out = np.concatenate([samples[lo:hi] for lo, hi in bounds]).astype(np.float32)
    ramp = np.linspace(0.0, 1.0, 2 * half, dtype=np.float32)
    clock = 0
    for (lo0, hi0), (lo1, hi1) in zip(bounds, bounds[1:]):
        clock += hi0 - lo0
        if half and hi0 + half <= len(samples) and lo1 >= half and half <= clock <= len(out) - half:
            outgoing, incoming = samples[hi0 - half:hi0 + half], samples[lo1 - half:lo1 + half]
            out[clock - half:clock + half] = outgoing * ramp[::-1] + incoming * ramp
    return out


def spliced_truth(pieces: list[list], order: str) -> list[list]:
    """[(start seconds in the spliced song, letter)] for consecutive pieces, equal letters joined."""
    sections, clock = [], 0.0
    for (start, end), label in zip(pieces, order.split()):
        if not sections or sections[-1][1] != label:
            sections.append([round(clock, 3), label])
        clock += end - start
    return sections


def build_spliced(recipe: dict, cache: Path = CACHE) -> Path:
    """The spliced song's WAV in the cache (built once from the M2D recording)."""
    out = cache / f"{recipe['name']}.wav"
    if not out.is_file():
        import soundfile as sf
        from choreo.music.audio import load_audio

        sr = 44100
        samples = load_audio(M2D / recipe["clip"] / "audio.mp3", sr)
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.with_suffix(".partial.wav")
        sf.write(partial, splice(samples, sr, [tuple(p) for p in recipe["pieces"]]), sr)
        partial.replace(out)
    return out


def bar_starts(music, beats_per_bar: int) -> np.ndarray:
    """Bar lines from tracked beats: every ``beats_per_bar``-th beat, in the phase whose beats
    carry the strongest onsets (the tracker gives beats, not downbeats)."""
    from choreo.music.features import ONSET_COLUMN

    beats = np.asarray(music.beat_times)
    onset = music.features[:, ONSET_COLUMN]
    frames = np.clip(np.round(beats * music.fps).astype(int), 0, len(onset) - 1)
    phase = max(range(beats_per_bar), key=lambda p: onset[frames[p::beats_per_bar]].mean())
    return beats[phase::beats_per_bar]


def bar_vectors(music, starts: np.ndarray) -> np.ndarray:
    """(bars, 32) unit vectors: each bar's mean chroma and standardised MFCC (harmony and timbre:
    what tells a return from a new passage). A bar runs from one start to the next."""
    from choreo.music.features import CHROMA_COLUMNS, MFCC_COLUMNS

    mfcc = music.features[:, MFCC_COLUMNS]
    mfcc = (mfcc - mfcc.mean(0)) / (mfcc.std(0) + 1e-6)
    chroma = music.features[:, CHROMA_COLUMNS]
    rows = []
    for lo, hi in zip(starts[:-1], starts[1:]):
        a, b = int(lo * music.fps), max(int(hi * music.fps), int(lo * music.fps) + 1)
        c, m = chroma[a:b].mean(0), mfcc[a:b].mean(0)
        rows.append(np.concatenate([c / (np.linalg.norm(c) + 1e-9), 0.5 * m / (np.linalg.norm(m) + 1e-9)]))
    rows = np.asarray(rows)
    return rows / (np.linalg.norm(rows, axis=1, keepdims=True) + 1e-9)


def segment_similarity(bars: np.ndarray, length: int = SEGMENT_BARS) -> np.ndarray:
    """(n, n): mean bar-by-bar cosine similarity of the ``length``-bar segments starting at each bar."""
    gram = bars @ bars.T
    n = len(bars) - length + 1
    return np.array([[np.mean([gram[i + k, j + k] for k in range(length)]) for j in range(n)] for i in range(n)])


def _apart(i: int, taken: list[int], length: int = SEGMENT_BARS) -> bool:
    return all(abs(i - j) >= length for j in taken)


def choose_segments(sim: np.ndarray, letters_needed: int, margin: int = 2) -> dict[str, list[int]]:
    """First bar of each letter's segment, and of its return when the recording has one.

    A: the segment with the strongest repeat elsewhere (then its return is the recording's own).
    Each later letter: the segment least like those chosen, preferring ones that repeat too. A
    return is the most similar segment apart from all chosen, if it is clearly more alike than
    the letters are to each other; otherwise the letter's own segment plays again."""
    n = len(sim)
    usable = list(range(margin, n - margin))
    def repeat(i, taken):
        others = [j for j in usable if _apart(j, taken + [i])]
        return max(others, key=lambda j: sim[i, j]) if others else None
    chosen: list[int] = []
    for index in range(letters_needed):
        candidates = [i for i in usable if _apart(i, chosen)]
        def score(i):
            again = repeat(i, chosen)
            strength = sim[i, again] if again is not None else 0.0
            return strength - (max(sim[i, j] for j in chosen) if chosen else 0.0) * 2
        chosen.append(max(candidates, key=score))
    between = max((sim[a, b] for a in chosen for b in chosen if a != b), default=0.0)
    plan: dict[str, list[int]] = {}
    taken = list(chosen)
    for letter, first in zip("ABC", chosen):
        again = repeat(first, taken)
        plan[letter] = [first]
        if again is not None and sim[first, again] > between + 0.05:
            plan[letter].append(again)
            taken.append(again)
    return plan


def _similarities(sim: np.ndarray, plan: dict[str, list[int]]) -> dict[str, float]:
    """The check that the truth sounds true: each letter against its return ("A~A'") and
    against the other letters ("A~B"); a return should be the more alike."""
    out = {f"{l}~{l}'": round(float(sim[b[0], b[-1]]), 3) for l, b in plan.items() if len(b) > 1}
    names = sorted(plan)
    out |= {f"{a}~{b}": round(float(sim[plan[a][0], plan[b][0]]), 3) for i, a in enumerate(names) for b in names[i + 1:]}
    return out


def section_similarity(music, sections: list[tuple[float, str]], bar: float) -> np.ndarray:
    """(sections, sections): how alike two of the truth's sections sound, bar k of one against
    bar k of the other (bar_vectors on a grid of ``bar`` seconds from 0), over the shorter one: a
    return plays the same bars in the same order."""
    starts = np.arange(0.0, music.duration - bar / 2, bar)
    vectors = bar_vectors(music, np.append(starts, starts[-1] + bar))
    edges = [int(round(start / bar)) for start, _ in sections] + [len(vectors)]
    spans = [vectors[a:max(b, a + 1)] for a, b in zip(edges[:-1], edges[1:])]
    aligned = lambda x, y: float(np.mean(np.sum(x[:len(y)] * y[:len(x)], axis=1)))  # noqa: E731
    return np.array([[aligned(x, y) for y in spans] for x in spans])


def unheard_form(music, sections: list[tuple[float, str]], bar: float) -> str | None:
    """Why the truth's returns do not sound like returns, or None when they do (the listening
    proxy of the curation): two sections with the same letter must be more alike than either is
    to any section with another letter."""
    sim = section_similarity(music, sections, bar)
    labels = [label for _, label in sections]
    for i, a in enumerate(labels):
        for j in range(i + 1, len(labels)):
            if labels[j] != a:
                continue
            others = [sim[k, m] for k in (i, j) for m, c in enumerate(labels) if c != a]
            if others and sim[i, j] <= max(others):
                return (f"sections {i} and {j} ({a}) sound less alike ({sim[i, j]:.2f}) than {a} and another "
                        f"letter ({max(others):.2f})")
    return None


def splice_recipe(clip: str, form: str) -> dict:
    """The json entry of one spliced song: pieces of ``clip``'s recording (seconds) in ``form``'s order."""
    from choreo.datasets.m2d import validation_clips
    from choreo.music import Music


    beats_per_bar = 3 if "_W_" in clip else 4
    music = Music.from_file(M2D / clip / "audio.mp3")
    starts = bar_starts(music, beats_per_bar)
    sim = segment_similarity(bar_vectors(music, starts))
    seconds_per_bar = float(np.median(np.diff(starts)))
    if len(form.split()) * SEGMENT_BARS * seconds_per_bar > MAX_SECONDS:  # slow music: a form of fewer pieces
        form = min(SPLICE_FORMS, key=lambda f: abs(len(f.split()) * SEGMENT_BARS * seconds_per_bar - 90))
    plan = choose_segments(sim, len(set(form.split())))
    seen: dict[str, int] = {}
    pieces = []
    for letter in form.split():  # the k-th time a letter plays: its k-th occurrence, in turn
        first = plan[letter][seen.get(letter, 0) % len(plan[letter])]
        seen[letter] = seen.get(letter, 0) + 1
        pieces.append([round(float(starts[first]), 3), round(float(starts[first + SEGMENT_BARS]), 3)])
    from choreo.datasets.m2d import clip_splits

    test = clip_splits().get(clip) == "test"
    return {"name": f"{clip}-{form.replace(' ', '')}", "kind": "spliced", "clip": clip, "form": form,
            "beats_per_bar": beats_per_bar, "tempo": round(float(music.tempo), 2), "pieces": pieces,
            "seconds_per_bar": round(seconds_per_bar, 4), "segment_bars": plan,
            "similarity": _similarities(sim, plan),
            "sections": spliced_truth(pieces, form), "split": "test" if test else "validation",
            "in_validation_clips": clip in validation_clips(), "excluded": None}


def _listen(recipe: dict) -> str | None:
    """unheard_form on the song's audio (rendered or spliced), prefixed so the json says so."""
    from choreo.music import Music

    if recipe["kind"] == "lmms":
        wav = render(LMMS_PROJECTS / recipe["project"], LMMS_CACHE / f"{recipe['name']}.wav")
    else:
        wav = build_spliced(recipe)
    reason = unheard_form(Music.from_file(wav), [tuple(s) for s in recipe["sections"]], recipe["seconds_per_bar"])
    return reason and f"listening proxy: {reason}"


def make_recipes(path: Path = RECIPES) -> None:
    """Write form_songs.json: the curated LMMS truths (excluded ones kept, with the reason) and
    one spliced song per chosen M2D clip, the forms taken in turn."""
    lmms = [lmms_truth(p) for p in lmms_projects()]
    spliced = [splice_recipe(clip, SPLICE_FORMS[i % len(SPLICE_FORMS)]) for i, clip in enumerate(SPLICE_CLIPS)]
    for song in lmms + spliced:
        if not song["excluded"]:
            song["excluded"] = _listen(song)
    kept = [song for song in lmms if not song["excluded"]]
    for index, song in enumerate(kept):
        song["split"] = ("validation", "test")[index % 2]
    for song in lmms:
        song.setdefault("split", None)
    text = {"description": __doc__.split("\n\n")[1], "songs": lmms + spliced}
    path.write_text(json.dumps(text, indent=1) + "\n")


# ---------------------------------------------------------------- the corpus


def load_recipes(path: Path = RECIPES) -> list[dict]:
    return json.loads(path.read_text())["songs"]


def form_songs(split: str = "all", include_excluded: bool = False, path: Path = RECIPES) -> list[FormSong]:
    """Every song of form_songs.json in ``split`` ("validation", "test" or "all"), audio built."""
    songs = []
    for recipe in load_recipes(path):
        if (recipe.get("excluded") and not include_excluded) or split not in ("all", recipe["split"]):
            continue
        if recipe["kind"] == "lmms":
            wav = render(LMMS_PROJECTS / recipe["project"], LMMS_CACHE / f"{recipe['name']}.wav")
        else:
            wav = build_spliced(recipe)
        bar = recipe.get("seconds_per_bar") or recipe["beats_per_bar"] * 60.0 / recipe["tempo"]
        songs.append(FormSong(recipe["name"], wav, [(float(s), str(l)) for s, l in recipe["sections"]],
                              int(recipe["beats_per_bar"]), float(bar), recipe["kind"], recipe["split"]))
    return songs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--make-recipes", action="store_true", help="re-derive form_songs.json")
    args = parser.parse_args()
    if args.make_recipes:
        make_recipes(RECIPES)
    for song in form_songs():
        print(f"{song.kind:8} {song.split:10} {song.name:45} {' '.join(l for _, l in song.sections):16} {song.path}")


if __name__ == "__main__":
    main()
