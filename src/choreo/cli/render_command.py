"""`choreo render`: a preview video, GIF or picture strip of a motion, or a diagnostic plot."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Optional

import typer

SIZE = re.compile(r"\s*([0-9]{1,9})\s*[xX]\s*([0-9]{1,9})\s*")  # ASCII digits: int() also reads fullwidth ones

from ..numbers import shown
from .numbers import Number
from .preview import render_preview
from .progress import stderr_console
from .text import markup


def render(
    motion: Path = typer.Argument(..., help="Motion file: BVH, NPZ, AIST++ pkl, JSON, glb; - reads stdin."),
    output: str = typer.Option(..., "-o", "--output", help="preview.mp4 (.mov/.mkv/.webm), .gif, .png (a strip of moments) or .html (a page any browser plays)."),
    music: Optional[Path] = typer.Option(None, help="Song to mux into the video (and whose beats --plot beats draws)."),
    plot: Optional[str] = typer.Option(None, help="Instead of the dancer: 'beats' (music vs motion beats), 'path' (root from above) or 'form' (the song's "
                                             "sections and bar self-similarity beside the dance's; needs --music)."),
    size: str = typer.Option("640x480", help="Frame size WIDTHxHEIGHT in pixels."),
    fps: Optional[float] = typer.Option(None, parser=Number("--fps", 1, 120), help="Frame rate of the preview (default: the motion's; a GIF's is capped: GIF frame delays are coarse)."),
    strip: int = typer.Option(6, help="PNG: how many moments side by side (1: the middle frame)."),
) -> None:
    """Render a motion: a shaded 3D figure the camera follows, with the music; or a beats/path plot.

    Examples:
      choreo render dance.bvh --music song.mp3 -o preview.mp4
      choreo render dance.bvh --music song.mp3 -o preview.html
      choreo generate song.mp3 -o - -f npz | choreo render - --music song.mp3 -o preview.mp4
      choreo render dance.bvh -o strip.png --strip 8
      choreo render dance.bvh --music song.mp3 --plot beats -o beats.png
      choreo render dance.bvh --plot path -o path.svg
      choreo render dance.bvh --music song.mp3 --plot form -o form.png
    """
    from ..formats import read_motion

    config = render_config(size, fps, strip)
    dance = read_motion(motion)
    if plot is not None:
        from ..render.plots import render_plot

        song = None
        if music is not None:
            from ..music import Music

            song = Music.from_file(music, timbre=plot == "form")
        render_plot(plot, dance, output, song)
    elif Path(output).suffix.lower() == ".html":
        render_html(dance, output, music)
    else:
        render_preview(dance, Path(output), config, music)
    stderr_console.print(f"wrote {markup(output)}", highlight=False)


def render_config(size: str, fps: float | None, strip: int):
    from ..errors import ParameterError
    from ..render import RenderConfig

    from ..render.video import MAX_SIDE, MAX_STRIP, MIN_SIDE

    match = SIZE.fullmatch(size)
    if not match:
        raise ParameterError(f"--size {shown(size)} must look like 640x480")
    side = Number("--size", MIN_SIDE, MAX_SIDE, whole=True)  # each side, before a frame is allocated
    return RenderConfig(width=side(match[1]), height=side(match[2]), fps=fps,
                        strip_frames=Number("--strip", 1, MAX_STRIP, whole=True)(str(strip)))


def render_html(motion, output: str, music: Path | None) -> None:
    """One self-contained page: the dancer, the song inlined and its beats on the timeline."""
    from ..fileio import atomic_output
    from ..render.html import write_html_preview

    beats = None
    if music is not None:
        from ..music import Music

        beats = Music.from_file(music, timbre=False).beat_times
    with atomic_output(output, binary=True) as handle:
        write_html_preview(motion, music, beats, handle)
