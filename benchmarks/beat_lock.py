"""Beat-rate lock on songs from outside M2D whose tempo is known (LMMS's demo songs).

    python benchmarks/beat_lock.py [--seconds 60] [--m2d ../shared/data/m2d] [--beats choreo|stated|madmom]   # needs `apt-get install lmms`

Each song (a minute from 10 s in) is danced by both bundled generators with their defaults, and
each dance is also scored after choreo.finishing's beat lock (side by side, same dance). How
strongly a dance's motion beats recur at a tempo is `choreo.metrics.tempo_salience`. A dance is
locked to its song when its beats recur more strongly at its own song's tempo than at another
song's: the share of (dance, other song) pairs where that holds is 50 % for dances that ignore
the tempo and 100 % for perfect lock (pairs whose tempi are the same pulse are skipped). The
same share for real dancers is the reference: M2D's clips against the tempo choreo's analysis
hears in their music (M2D states no tempo); the generators are scored the same way on M2D's
test songs, the music they were trained for. Also printed: how often that analysis hears the
stated tempo of the outside songs (the generators dance to what it hears). ``--beats stated``
dances the outside songs to their stated tempo as a user who knows it would (``--bpm``), and
``--beats madmom`` to madmom's beats everywhere (``--beat-tracker madmom``); ``--finished`` scores
the dances after every finishing pass (speed limit, beat lock, footsteps) instead of the beat
lock alone.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from choreo.generator import GenerationRequest
from choreo.finishing import beat_lock, finish
from choreo.metrics import beat_align_score, beat_autocorrelation, motion_beats, salience_at, same_pulse
from choreo.music import BeatOptions, BeatSource, Music, audio_duration

sys.path.insert(0, str(Path(__file__).parent))  # its sibling too when imported (experiments/rest_beat_lock.py)
from outside_songs import outside_songs  # noqa: E402

SKIP_SECONDS = 10.0  # past the intro
FPS = 30.0
SLOWEST_BPM = 40.0  # the beat autocorrelation of each dance is kept up to two periods of this


@dataclass
class Danced:
    name: str
    bpm: float  # the song's tempo: stated (outside songs) or heard (M2D)
    heard_bpm: float  # what choreo's music analysis hears
    dances: dict[str, np.ndarray]  # each dancer's beat autocorrelation (read at any tempo)


def beat_profile(joint_positions: np.ndarray) -> np.ndarray:
    return beat_autocorrelation(joint_positions, int(2 * 60.0 * FPS / SLOWEST_BPM) + 1)


SGMD_CHECKPOINT: Path | None = None  # --sgmd-checkpoint: score another SGMD model than the bundled one
SEED = 0  # --seed: another take of every dance (the lock shares move by several points from take to take)
FINISHED = False  # --finished: every finishing pass as the CLI applies them (speed limit, beat lock, footsteps)
BEATS = "choreo"  # --beats: whose beats the songs are danced to (choreo's tracker, the stated tempo, madmom's)


def beat_source(stated_bpm: float | None) -> BeatSource:
    if BEATS == "stated" and stated_bpm is not None:
        return BeatOptions(bpm=stated_bpm).source()
    return BeatOptions(beat_tracker="madmom" if BEATS == "madmom" else "choreo").source()


def generators() -> dict:
    from choreo import load_backend

    return {"SGMD": load_backend("sgmd", SGMD_CHECKPOINT), "ChoreoGraph": load_backend("graph")}


LOCK_SECONDS: list[tuple[float, float]] = []  # (seconds the beat lock took, seconds of dance)
BEAT_ALIGN: dict[str, list[float]] = {}  # each dancer's BeatAlign against the music's beats


def generated(backends: dict, music: Music, where: str) -> dict[str, np.ndarray]:
    """Each backend's dance (seed SEED), as it comes and after the beat lock: beat profiles."""
    profiles = {}
    for name, backend in backends.items():
        motion = backend.generate(GenerationRequest(music, seed=SEED))
        started = time.perf_counter()
        locked = (finish(motion, music.beat_frames, audible=music.audible) if FINISHED
                  else beat_lock(motion, music.beat_frames).motion)
        LOCK_SECONDS.append((time.perf_counter() - started, motion.duration))
        for label, dance in ((name, motion), (f"{name} + {'finishing' if FINISHED else 'beat lock'}", locked)):
            positions = dance.joint_positions()
            profiles[label] = beat_profile(positions)
            BEAT_ALIGN.setdefault(f"{label} ({where})", []).append(beat_align_score(music.beat_frames, motion_beats(positions)))
    return profiles


def dance_outside_songs(seconds: float) -> list[Danced]:
    backends, danced = generators(), []
    for song in outside_songs():
        skip = SKIP_SECONDS if audio_duration(song.path) >= SKIP_SECONDS + 20 else 0.0
        music = Music.from_file(song.path, start=skip, end=skip + seconds, beats=beat_source(song.bpm))
        danced.append(Danced(song.name, song.bpm, music.tempo, generated(backends, music, "outside songs")))
        print(f"danced {song.name} ({song.bpm:g} bpm, heard {music.tempo:.1f})", flush=True)
    return danced


def m2d_dancers(clips) -> list[Danced]:
    """Every M2D clip's real dance; test clips also danced by both generators to the same music."""
    from choreo.datasets import TEST

    backends, danced = generators(), []
    for clip in (c for c in clips if c.audio_path):
        music = Music.from_file(clip.audio_path, start=clip.audio_offset, end=clip.audio_offset + clip.motion.duration,
                                beats=beat_source(None))
        dances = {"real dancers": beat_profile(clip.motion.joint_positions())}
        if clip.split == TEST:
            BEAT_ALIGN.setdefault("real dancers (M2D test songs)", []).append(
                beat_align_score(music.beat_frames, motion_beats(clip.motion.joint_positions())))
        if clip.split == TEST:
            dances |= generated(backends, music, "M2D test songs")
        danced.append(Danced(clip.name, music.tempo, music.tempo, dances))
    return danced


def own_tempo_wins(danced: list[Danced], dancer: str) -> float:
    """Share of (dance, other song) pairs where the dance's beats recur more at its own song's tempo."""
    danced = [d for d in danced if dancer in d.dances]
    wins = [salience_at(d.dances[dancer], FPS, d.bpm) > salience_at(d.dances[dancer], FPS, other.bpm)
            for d in danced for other in danced if not same_pulse(other.bpm, d.bpm)]
    return float(np.mean(wins)) if wins else float("nan")


def lock_row(label: str, danced: list[Danced], dancer: str) -> str:
    songs = sum(dancer in d.dances for d in danced)
    return f"| {dancer} ({label}) | {songs} | {100 * own_tempo_wins(danced, dancer):.0f} % |"


def markdown(outside: list[Danced], m2d: list[Danced]) -> list[str]:
    names = list(outside[0].dances)
    as_heard = [replace(d, bpm=d.heard_bpm) for d in outside]  # what the generators were given
    heard = np.mean([same_pulse(d.heard_bpm, d.bpm) for d in outside])
    lines = [
        "| song | stated bpm | heard by choreo | " + " | ".join(f"{n}: salience at the song's tempo" for n in names) + " |",
        "| --- | ---: | ---: | " + " | ".join("---:" for _ in names) + " |",
        *(f"| {d.name} | {d.bpm:g} | {d.heard_bpm:.1f}{'' if same_pulse(d.heard_bpm, d.bpm) else ' (wrong)'} | "
          + " | ".join(f"{salience_at(d.dances[n], FPS, d.bpm):.2f}" for n in names) + " |" for d in outside),
        "",
        "| dancer | songs | beats recur more at their own song's tempo than at another's (50 % = no lock) |",
        "| --- | ---: | ---: |",
        *(lock_row("outside songs, stated tempo", outside, n) for n in names),
        *(lock_row("outside songs, tempo heard by choreo", as_heard, n) for n in names),
    ]
    if m2d:
        test = [d for d in m2d if len(d.dances) > 1]
        lines += [lock_row("all M2D clips, tempo heard by choreo", m2d, "real dancers"),
                  *(lock_row("M2D test songs, tempo heard by choreo", test, n) for n in ["real dancers", *names])]
    lines += ["", "| dancer | BeatAlign (mean over dances) |", "| --- | ---: |",
              *(f"| {name} | {np.mean(values):.3f} |" for name, values in BEAT_ALIGN.items())]
    if LOCK_SECONDS:
        spent, danced_seconds = np.sum(LOCK_SECONDS, axis=0)
        lines += ["", f"The {'finishing passes' if FINISHED else 'beat lock'} took {spent:.1f} s for {danced_seconds / 60:.1f} min of dance "
                      f"({60 * spent / danced_seconds:.2f} s per minute)."]
    lines += ["", f"choreo's music analysis hears the stated tempo (or half or double it, within 4 %) in "
              f"{100 * heard:.0f} % of the outside songs."]
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--m2d", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "data" / "m2d")
    parser.add_argument("--sgmd-checkpoint", type=Path, help="an SGMD checkpoint to score instead of the bundled one")
    parser.add_argument("--seed", type=int, default=0, help="the generators' seed (another take of every dance)")
    parser.add_argument("--beats", choices=["choreo", "stated", "madmom"], default="choreo",
                        help="dance to choreo's tracked beats, the outside songs' stated tempo (--bpm), or madmom's beats")
    parser.add_argument("--finished", action="store_true",
                        help="score the dances as the CLI writes them (speed limit, beat lock, footsteps), not the beat lock alone")
    args = parser.parse_args()
    global SGMD_CHECKPOINT, SEED, BEATS, FINISHED
    SGMD_CHECKPOINT, SEED, BEATS, FINISHED = args.sgmd_checkpoint, args.seed, args.beats, args.finished
    started = time.perf_counter()
    outside = dance_outside_songs(args.seconds)
    if not outside:
        raise SystemExit("no LMMS demo songs: `apt-get install lmms` first")
    if args.m2d.is_dir():
        from choreo.datasets import load_dataset

        m2d = m2d_dancers(load_dataset(args.m2d))
    else:
        m2d = []
    print("\n".join(markdown(outside, m2d)))
    print(f"({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
