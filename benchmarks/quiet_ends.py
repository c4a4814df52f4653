"""How much of each outside song is silence at its ends, and where the rest pass stops the dancer.

    python benchmarks/quiet_ends.py            # the LMMS demo songs (benchmarks/outside_songs.py renders them)
    python benchmarks/quiet_ends.py --dance    # also dance each (SGMD, defaults, seed 0) and read its metadata

For docs/results.md, "Finishing passes" (Rest). Silence is choreo.music.loudness.audible_span's:
more than 40 dB under the song's loud level.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import choreo
from choreo.motion.beats import mean_joint_speed
from choreo.music import Music
from choreo.skeleton.legs import LEGS

from outside_songs import outside_songs


ANKLES = [leg[2] for leg in LEGS]  # the left and the right ankle, as footsteps (choreo.finishing.footsteps) names them


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dance", action="store_true", help="also dance each song and report where it rests")
    args = parser.parse_args()
    songs = outside_songs()
    if not songs:
        sys.exit("no outside songs: apt-get install lmms")
    print("| song | seconds | music from | music until | quiet tail s |"
          + (" rests from | still after the music | feet at rest, cm above standing |" if args.dance else ""))
    print("| --- | ---: | ---: | ---: | ---: |" + (" ---: | ---: | ---: |" if args.dance else ""))
    tails = []
    for song in songs:
        music = Music.from_file(song.path, timbre=args.dance)
        first, stop = music.audible
        tail = (music.num_frames - stop) / music.fps
        tails.append(tail)
        row = f"| {song.name} | {music.duration:.1f} | {first / music.fps:.1f} | {stop / music.fps:.1f} | {tail:.1f} |"
        if args.dance:
            dance = choreo.dance(music, style="cha-cha", seed=0)
            rests = dance.metadata.get("rest", {}).get("rests_from")
            positions = dance.joint_positions()
            speed = mean_joint_speed(positions) * dance.fps
            after = speed[stop + round(music.fps):]  # from a second after the music: the ease is over
            still = "-" if len(after) == 0 else f"{np.mean(after < 1e-6):.2f}"
            ankles = positions[:, ANKLES, 1]
            standing = np.median(ankles.min(axis=1))  # the lower ankle's usual height: a foot on the floor
            at_rest = rests is not None and rests < music.duration - 0.1  # not only a wait at the start
            feet = " / ".join(f"{100 * (h - standing):.0f}" for h in ankles[-1]) if at_rest else "-"
            row += f" {'-' if rests is None else f'{rests:.1f}'} | {still} | {feet} |"
        print(row, flush=True)
    tails = np.array(tails)
    print(f"\n{len(tails)} songs; quiet tail of 1 s or more: {int((tails >= 1).sum())}; median tail {np.median(tails):.1f} s")


if __name__ == "__main__":
    main()
