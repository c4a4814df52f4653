"""The beat-rate lock (benchmarks/beat_lock.py --finished) of the songs whose benchmark minute
reaches a closing silence, with and without the rest pass, on one render and one take.

    python -m experiments.rest_beat_lock [--seed 0]

docs/results.md, "Finishing passes" (Rest). Each dance's beats are compared, as the benchmark
does, at its own song's stated tempo against every other LMMS song's: the pairs it wins.
"""

from __future__ import annotations

import argparse
from choreo.finishing import finish
from choreo.generator import GenerationRequest
from choreo.metrics import salience_at, same_pulse
from choreo.music import Music, audio_duration

import benchmarks.beat_lock as bench  # benchmarks/beat_lock.py, which imports benchmarks/outside_songs.py
from benchmarks.outside_songs import outside_songs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--seconds", type=float, default=60.0)
    args = parser.parse_args()
    songs = outside_songs()
    backends = bench.generators()
    for song in songs:
        skip = bench.SKIP_SECONDS if audio_duration(song.path) >= bench.SKIP_SECONDS + 20 else 0.0
        music = Music.from_file(song.path, start=skip, end=skip + args.seconds, beats=bench.beat_source(song.bpm))
        if music.audible[1] > music.num_frames - music.fps:  # no closing second of silence: the rest changes nothing
            continue
        others = [s.bpm for s in songs if not same_pulse(s.bpm, song.bpm)]
        for name, backend in backends.items():
            motion = backend.generate(GenerationRequest(music, seed=args.seed))
            for label, audible in (("rest", music.audible), ("no rest", None)):
                profile = bench.beat_profile(finish(motion, music.beat_frames, audible=audible).joint_positions())
                own = salience_at(profile, bench.FPS, song.bpm)
                wins = sum(own > salience_at(profile, bench.FPS, bpm) for bpm in others)
                print(f"{song.name} ({music.duration:.1f} s, music until {music.audible[1] / music.fps:.1f} s) {name}, "
                      f"{label}: wins {wins} of {len(others)}", flush=True)


if __name__ == "__main__":
    main()
