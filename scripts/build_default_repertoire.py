"""Build the repertoire `choreo graph` ships with, from the bundled SGMD model's own dances.

    python scripts/build_default_repertoire.py [--data ../shared/data/m2d] [--out generators/choreo_graph/weights/repertoire-sgmd.npz]

M2D motion may not be redistributed, so the shipped repertoire holds no M2D frame: for each genre
the bundled SGMD checkpoint dances (seed 0, guidance 2 on the music only) to the first three M2D train-split
songs of that genre (the whole clip's music; tango has one), styled with that genre, and every
8 s clip of those dances (2 s apart) is described by the
bundled ChoreoGraph models. Each dance first goes through the speed limit every dance gets
(`choreo.finishing.speed_limit`: one-frame spins and limb flips spread over their neighbours);
clips where a joint still moves faster than real dancers' fastest 0.1 % of frames (10.39 m/s) or
the root faster than theirs (3.69 m/s, the speed limit's floor step; M2D's one tango travels
faster than 3 m/s in 8 % of its frames, so a lower limit leaves tango out) are left out. Only
generated motion is stored, never the songs or their features.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from choreo import load_backend
from choreo.datasets import TRAIN, load_dataset
from choreo.finishing import footsteps
from choreo.finishing.speed_limit import REAL_FLOOR_STEP, REAL_JOINT_SPEED, REFERENCE_FPS, speed_limit
from choreo.generator import GenerationRequest
from choreo.music import Music
from choreo_graph import DEFAULT_CHECKPOINT, DEFAULT_REPERTOIRE, SpeedLimits, build_repertoire_file

REPO = Path(__file__).resolve().parents[1]
SONGS_PER_GENRE = 3  # enough material that a walk restricted to one genre need not replay itself
# The sampler the shipped file was built with: the default until 2026-12-04, the travel guided in every genre as until
# 2026-12-05 (rebuilt with a waltz's travel unguided it changed the graph within noise: docs/graph.md).
SAMPLING = {"guidance": 2.0, "style_guidance": 1.0, "travel_guidance": 1.0}
LIMITS = SpeedLimits(joint=REAL_JOINT_SPEED, root=REAL_FLOOR_STEP * REFERENCE_FPS)  # m/s: real dancers' fastest 0.1 %


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--out", default=str(DEFAULT_REPERTOIRE))
    parser.add_argument("--checkpoint", default=str(DEFAULT_CHECKPOINT))
    parser.add_argument("--footsteps", action="store_true", help="cut the clips from dances footsteps has finished")
    args = parser.parse_args()
    sgmd = load_backend("sgmd")  # the bundled SGMD checkpoint
    clips = sorted((c for c in load_dataset(args.data) if c.split == TRAIN and c.audio_path), key=lambda c: c.name)
    dances = []
    for genre in sorted({c.genre for c in clips}):
        for clip in [c for c in clips if c.genre == genre][:SONGS_PER_GENRE]:
            music = Music.from_file(clip.audio_path, start=clip.audio_offset, end=clip.audio_offset + clip.motion.duration)
            motion = speed_limit(sgmd.generate(GenerationRequest(music, style=genre, seed=0, options=SAMPLING)))
            if args.footsteps:
                motion = footsteps(motion)
            dances.append((f"sgmd:{genre}:{clip.name}", motion, genre))
            print(f"danced {genre} to {clip.name}: {motion.duration:.1f} s", flush=True)
    repertoire = build_repertoire_file(dances, args.out, "bundled SGMD generations (M2D train songs)", stride=60,
                                       checkpoint=args.checkpoint, limits=LIMITS)
    print(f"wrote {args.out}: {len(repertoire)} clips, {Path(args.out).stat().st_size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
