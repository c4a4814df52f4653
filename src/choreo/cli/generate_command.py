"""`choreo generate`: music in, dance out, through a generator backend."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .progress import progress_bar, stderr_console


def generate(
    song: Path = typer.Argument(..., help="Audio file: wav, mp3, ogg, flac or opus."),
    output: str = typer.Option(..., "-o", "--output", help="Output motion file (.bvh, .npz, .json, .npy) or - for stdout."),
    style: Optional[str] = typer.Option(None, help="Genre (waltz, rumba, ...), its index, or a free-text description."),
    checkpoint: Optional[Path] = typer.Option(None, help="Trained checkpoint (from choreo train)."),
    generator: str = typer.Option("sgmd", help="Backend (see choreo generators)."),
    steps: int = typer.Option(50, help="Sampling steps (DDIM)."),
    guidance: float = typer.Option(2.0, help="Classifier-free guidance weight on the music."),
    seed: int = typer.Option(0, help="Random seed: same seed, same dance."),
    format: Optional[str] = typer.Option(None, "--format", "-f", help="Output format; default from the extension."),
) -> None:
    """Generate a dance for a song.

    Examples:
      choreo generate song.mp3 -o dance.bvh --style waltz --checkpoint runs/sgmd/last.pt
      choreo generate song.mp3 -o dance.npz --style "slow, romantic, hips leading" --checkpoint last.pt --seed 7
    """
    from ..errors import ChoreoError
    from ..fileio import check_output_dir
    from ..formats import write_motion
    from ..generator import GenerationRequest, available_plugins
    from ..music import Music

    plugins = available_plugins()
    plugin = plugins.get(generator)
    if plugin is None or plugin.factory is None:
        raise ChoreoError(f"generator {generator!r} is not available")
    if checkpoint is None:
        raise ChoreoError(f"{generator} has no default checkpoint yet ({plugin.status}); pass --checkpoint")
    if output != "-":
        check_output_dir(output)
    backend = plugin.factory(checkpoint)
    with progress_bar(f"analysing {song.name}") as update:
        music = Music.from_file(song, progress=lambda done, total: update(round(done), round(total)))
    request = GenerationRequest(music, style=style, seed=seed, options={"steps": steps, "guidance": guidance})
    with progress_bar("dancing", 100) as update:
        motion = backend.generate(request, progress=lambda fraction: update(round(fraction * 100), 100))
    notice = motion.metadata.get("style_notice")
    if notice:
        stderr_console.print(f"[yellow]note:[/yellow] {notice}")
    write_motion(motion, output, format=format)
    if output != "-":
        stderr_console.print(f"wrote {output}: {motion.duration:.1f} s of {motion.metadata.get('genre') or 'dance'} "
                             f"at {motion.fps:g} fps ({generator}, {steps} steps, guidance {guidance:g}, seed {seed})")
