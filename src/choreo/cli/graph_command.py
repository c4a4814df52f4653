"""`choreo graph`: the ChoreoGraph backend (dance from a motion repertoire) and `choreo graph build`."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer
from typer.core import TyperGroup

from .generate_command import (BEAT_LOCK, BEAT_TRACKER, BEATS, BPM, CHECKPOINT, FOOT_LOCK, FOOTSTEPS, OUTPUT, RIG, SEED, SONG, SPEED_LIMIT, THREADS,
                               Settings, beat_source, dance_one, load_backend)
from .numbers import Number
from .progress import progress_bar, stderr_console
from .text import markup


class DanceByDefault(TyperGroup):
    """`choreo graph SONG ...` means `choreo graph dance SONG ...`; `build` stays a subcommand."""

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h"):
            args = ["dance", *args]
        return super().parse_args(ctx, args)


graph_app = typer.Typer(
    cls=DanceByDefault, no_args_is_help=True, add_completion=False,
    help="ChoreoGraph: dance assembled from a motion repertoire, warped onto the music's beats.\n\n"
         "Example: choreo graph song.mp3 -o dance.bvh",
)


@graph_app.command("dance")
def graph_dance(
    song: Path = SONG, output: List[str] = OUTPUT,
    repertoire: Optional[Path] = typer.Option(None, help="Repertoire from choreo graph build (default: the bundled one)."),
    checkpoint: Optional[Path] = CHECKPOINT,
    style: Optional[str] = typer.Option(None, help="Only use repertoire clips of this genre (default: chosen by the music)."),
    top_k: int = typer.Option(512, "--top-k", "-k", help="Candidate clips per 4 s of music (the paper's K)."),
    motion_graph: bool = typer.Option(False, "--motion-graph", help="Ablation: a plain motion graph (first node of each segment only)."),
    no_retempo: bool = typer.Option(False, "--no-retempo", help="Ablation: use each clip's middle 4 s unwarped."),
    warp_smoothing: Optional[float] = typer.Option(None, parser=Number("--warp-smoothing"), help="Sigma (frames) smoothing each clip's re-timing (default 8); "
                                                   "0 = the paper's raw DTW path: feet slide twice as much, motion beats recur more regularly."),
    take_variation: Optional[float] = typer.Option(None, parser=Number("--take-variation"), help="Noise, as a share of the costs' spread, that each second of the walk "
                                                   "draws from --seed (default 0.1); 0 = the paper's deterministic greedy walk."),
    seed: int = typer.Option(0, parser=SEED.parser, help="Which take of the song: each seed is another walk through the repertoire."),
    format: Optional[str] = typer.Option(None, "--format", "-f", help="Output format; default from the extension."),
    preview: bool = typer.Option(False, "--preview", help="Also render OUTPUT-stem.mp4 with the music."),
    beat_lock: bool = BEAT_LOCK, foot_lock: bool = FOOT_LOCK, speed_limit: bool = SPEED_LIMIT, footsteps: bool = FOOTSTEPS,
    rig: Optional[str] = RIG, bpm: Optional[float] = BPM, beats: Optional[Path] = BEATS, beat_tracker: str = BEAT_TRACKER,
    threads: Optional[int] = THREADS,
) -> None:
    """Dance to a song with clips of a repertoire, re-timed onto the music and joined by a dynamic graph.

    Examples:
      choreo graph song.mp3 -o dance.bvh
      choreo graph song.mp3 -o dance.bvh --repertoire my_moves.npz -k 128
      choreo graph song.mp3 -o dance.npz --style waltz --preview
      choreo graph song.mp3 -o dance.bvh --warp-smoothing 0      # the paper's raw warps
    """
    from choreo_graph.config import GraphConfig

    graph_options = {key: value for key, value in (("warp_smoothing", warp_smoothing), ("take_variation", take_variation))
                     if value is not None}
    GraphConfig(top_k=top_k, **graph_options)  # checked now, not after the song's analysis
    settings = Settings(style, checkpoint, "graph", None, None, None, seed, format, preview, beat_lock, foot_lock, rig,
                        speed_limit, beats=beat_source(bpm, beats, beat_tracker), threads=threads, footsteps=footsteps)
    backend = load_backend(settings, repertoire=repertoire, top_k=top_k, dynamic=not motion_graph, retempo=not no_retempo,
                           **graph_options)
    dance_one(backend, song, output, settings)


@graph_app.command("build")
def graph_build(
    output: Path = typer.Option(..., "-o", "--output", help="Repertoire file to write (.npz)."),
    data: Optional[Path] = typer.Option(None, help="Dataset folder (M2D, AIST++ or BVH files) to cut 8 s clips from."),
    motions: List[Path] = typer.Option([], "--motion", help="A motion file to include (repeat); genre from --genre."),
    genre: Optional[str] = typer.Option(None, help="Genre label for --motion files."),
    split: str = typer.Option("train", help="Dataset split to use: train, test or all."),
    stride: float = typer.Option(2.0, help="Seconds between the starts of consecutive 8 s clips."),
    max_speed: Optional[float] = typer.Option(None, help="Leave out clips where a joint ever moves faster (m/s): glitches."),
    max_root_speed: Optional[float] = typer.Option(None, help="Leave out clips where the root ever moves faster (m/s)."),
    checkpoint: Optional[Path] = CHECKPOINT,
) -> None:
    """Build a repertoire: every 8 s clip of a dataset split or of given motions, described by the models.

    Examples:
      choreo graph build --data ../shared/data/m2d -o m2d_train.npz
      choreo graph build --motion a.bvh --motion b.bvh --genre waltz -o mine.npz --stride 1
      choreo graph build --motion gen.bvh --max-speed 8 --max-root-speed 3 -o clean.npz   # drop glitchy clips
    """
    from choreo_graph import build_repertoire_file
    from choreo_graph.repertoire import SpeedLimits

    from ..constraints import as_smpl
    from ..errors import ParameterError
    from ..fileio import check_output_dir
    from ..formats import read_motion

    if (data is None) == (not motions):
        raise ParameterError("give either --data or --motion files")
    if stride <= 0 or any(limit is not None and limit <= 0 for limit in (max_speed, max_root_speed)):
        raise ParameterError("--stride, --max-speed and --max-root-speed must be positive")
    check_output_dir(output)
    if data is not None:
        from ..datasets import load_dataset, select_split

        clips = select_split(load_dataset(data), split)
        sources = [(c.name, c.motion, c.genre) for c in clips]
        source = f"{data.name} ({split})"
    else:
        sources = [(m.stem, as_smpl(read_motion(m), 30.0), genre) for m in motions]
        source = f"{len(motions)} motion files"
    with progress_bar("describing clips") as update:
        repertoire = build_repertoire_file(sources, output, source, max(1, round(stride * 30)), checkpoint,
                                           SpeedLimits(max_speed, max_root_speed), update)
    stderr_console.print(markup(f"wrote {output}: {len(repertoire)} clips of 8 s from {source}"), highlight=False)
