"""`choreo graph`: the ChoreoGraph backend (dance from a motion repertoire) and `choreo graph build`."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer
from typer.core import TyperGroup

from .dancing import LOOP, OUTPUT, PREVIEW, SONG, DanceFlags, dance_one, dancing_command
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
@dancing_command("graph", choose_generator=False)
def graph_dance(
    song: Path = SONG, output: List[str] = OUTPUT,
    repertoire: Optional[Path] = typer.Option(None, help="Repertoire from choreo graph build (default: the bundled one)."),
    preview: bool = PREVIEW, loop: bool = LOOP,
    dance: DanceFlags = None,
) -> None:
    """Dance to a song with clips of a repertoire, re-timed onto the music and joined by a dynamic graph.

    --style only uses repertoire clips of that genre (default: chosen by the music); each --seed is
    another take, another walk through the repertoire.

    Examples:
      choreo graph song.mp3 -o dance.bvh
      choreo graph song.mp3 -o dance.bvh --repertoire my_moves.npz -k 128
      choreo graph song.mp3 -o dance.npz --style waltz --preview
      choreo graph song.mp3 -o dance.bvh --warp-smoothing 0      # the paper's raw warps
      choreo graph song.mp3 -o idle.fbx --rig mixamo --loop      # a looping idle dance
    """
    request = dance.request(repertoire=repertoire, loop=loop)
    dance_one(request, song, dance.outputs(output, preview))


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
    checkpoint: Optional[Path] = typer.Option(None, help="The models that describe the clips (default: the bundled ones)."),
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
