"""`choreo train NAME`: train a generator backend on a dataset folder."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .progress import progress_bar, stderr_console


def train(
    generator: str = typer.Argument(..., help="Backend to train, e.g. sgmd (see choreo generators)."),
    data: Path = typer.Option(..., help="Dataset folder: M2D, AIST++ or BVH files with audio beside them."),
    out: Path = typer.Option(..., help="Folder for checkpoints (last.pt is rewritten atomically)."),
    config: Optional[str] = typer.Option(None, help="sgmd: model configuration: cpu (default), cpu15 (the cpu model at 15 fps), small, paper, tiny."),
    steps: Optional[int] = typer.Option(None, help="Train until this many optimiser steps (graph: steps of each of its three stages)."),
    batch_size: Optional[int] = typer.Option(None, help="Windows per step (default 32)."),
    prompt: Optional[str] = typer.Option(None, help="sgmd: style prompt kind: description (default), name or onehot."),
    style_mode: Optional[str] = typer.Option(None, help="sgmd ablations: modulation (default), concat or none (EDGE)."),
    style_init: Optional[str] = typer.Option(None, help="sgmd: the style FC's initial weights, random (default) or zero (starts as the no-style model)."),
    style_dropout: Optional[float] = typer.Option(None, help="sgmd: share of training windows shown without their style (default 0.1)."),
    checkpoint_every: Optional[int] = typer.Option(None, help="sgmd: steps between checkpoints and validations (default 500)."),
    seed: Optional[int] = typer.Option(None, help="Seed of initialisation, batches and noise (default 0)."),
    mirror: Optional[bool] = typer.Option(None, "--mirror/--no-mirror", help="sgmd: also train on mirrored dances (default off: mirrored M2D dances score FID_k 376)."),
    stretch: Optional[str] = typer.Option(None, help="sgmd: paces to also train at, music stretched along, e.g. 0.85,1,1.18 (default 1: off)."),
    turns: Optional[str] = typer.Option(None, help="sgmd: also train on every clip turned by these angles about the vertical, e.g. 0,90,180,270 (default 0: off)."),
    genre_balance: Optional[float] = typer.Option(None, help="sgmd: 0 draws windows uniformly (default), 1 draws every genre equally."),
    rhythm: Optional[bool] = typer.Option(None, "--rhythm/--no-rhythm", help="sgmd: feed beat phase and tempo to the model (default off, as the bundled model)."),
    prediction: Optional[str] = typer.Option(None, help="sgmd: what the network predicts, x0 (default) or v."),
    sigma_data: Optional[float] = typer.Option(None, help="sgmd with --prediction v: the data's standard deviation the skip assumes (default 1)."),
    snr_gamma: Optional[float] = typer.Option(None, help="sgmd: weigh each window's loss by min(SNR, this) (min-SNR; default 0: off)."),
    reconstruction_weight: Optional[float] = typer.Option(None, help="sgmd: weight of the x0 reconstruction loss (default 6.36, 10 x EDGE's 0.636)."),
    foot_weight: Optional[float] = typer.Option(None, help="sgmd: weight of the foot term, planted feet that move (default 10.942, EDGE's)."),
    contact_source: Optional[str] = typer.Option(None, help="sgmd: contacts the foot term pins: predicted (the model's own, EDGE; default) or target (the data's)."),
    stepping_weight: Optional[float] = typer.Option(None, help="sgmd: weight of the feet's world speeds against the data's, in (m/s)^2 (default 0: off)."),
    leg_weight: Optional[float] = typer.Option(None, help="sgmd: weight of the legs' rotation channels inside the x0 term (default 1: as every channel)."),
    root_speed_weight: Optional[float] = typer.Option(None, help="sgmd: weight of the root's horizontal speed against the data's, direction-free, in (m/s)^2 (default 0: off)."),
    init_from: Optional[Path] = typer.Option(None, help="sgmd: fine-tune from this training state (same network; its step count carries on)."),
    hold_out_validation: bool = typer.Option(False, "--hold-out-validation", help="sgmd on M2D: train without the validation clips (docs/m2d.md) and validate on them."),
    resume: bool = typer.Option(False, "--resume", help="Continue from OUT/last.pt (same data order and noise as if never stopped)."),
) -> None:
    """Train a backend; rich progress shows loss, validation loss and throughput.

    Examples:
      choreo train sgmd --data ../shared/data/m2d --out runs/sgmd --steps 8000
      choreo train sgmd --data ~/aistpp --config paper --out runs/paper --resume
      choreo train sgmd --data ../shared/data/m2d --out runs/edge --style-mode none --steps 2000
      choreo train sgmd --data ../shared/data/m2d --out runs/plain --stretch 1 --genre-balance 0 --no-rhythm
      choreo train sgmd --data ../shared/data/m2d --out runs/feet --init-from runs/sgmd/last.pt --contact-source target
      choreo train graph --data ../shared/data/m2d --out runs/graph --steps 1200
    """
    from ..errors import ChoreoError, ParameterError
    from ..fileio import check_output_folder
    from ..generator import available_plugins
    from ..generator.options import parse_options

    plugins = available_plugins()
    if generator not in plugins:
        raise ParameterError(f"unknown generator {generator!r} (available: {', '.join(plugins)})")
    plugin = plugins[generator]
    if plugin.train is None or plugin.train_options is None:
        raise ChoreoError(f"generator {generator!r} cannot be trained yet: {plugin.status}")
    if not data.is_dir():
        raise ParameterError(f"--data {data} is not a folder")
    if init_from is not None and not init_from.is_file():
        raise ParameterError(f"--init-from {init_from} is not a file")
    check_output_folder(out)  # before the data loads, which takes minutes

    given = {"config": config, "steps": steps, "batch_size": batch_size, "prompt": prompt, "style_mode": style_mode,
             "style_init": style_init, "style_dropout": style_dropout, "checkpoint_every": checkpoint_every, "seed": seed,
             "mirror": mirror, "genre_balance": genre_balance, "rhythm": rhythm, "prediction": prediction,
             "sigma_data": sigma_data, "snr_gamma": snr_gamma, "reconstruction_weight": reconstruction_weight,
             "foot_weight": foot_weight, "contact_source": contact_source, "stepping_weight": stepping_weight,
             "leg_weight": leg_weight, "root_speed_weight": root_speed_weight,
             "hold_out_validation": hold_out_validation or None,
             "init_from": None if init_from is None else str(init_from),
             "stretch": None if stretch is None else _numbers("--stretch", stretch, "0.85,1,1.18"),
             "turns": None if turns is None else _numbers("--turns", turns, "0,90,180,270")}
    options = parse_options(generator, plugin.train_options, {k: v for k, v in given.items() if v is not None})
    with progress_bar(f"training {generator}") as update:
        def report(p):
            extra = f"loss {p.loss:.4f}" + (f", validation {p.validation_loss:.4f}" if p.validation_loss is not None else "")
            stage = f"{p.stage}: " if p.stage else ""
            update(p.step, p.max_steps, f"{stage}{extra}, {p.windows_per_second:.0f} windows/s")

        try:
            path = plugin.train(data, out, options, resume=resume, progress=report)
        except ValueError as error:  # bad configuration names and the like
            raise ParameterError(str(error)) from None
    from .text import markup

    stderr_console.print(f"wrote {markup(path)}")


def _numbers(flag: str, text: str, example: str) -> tuple[float, ...]:
    """Comma-separated numbers of a flag, or a one-line error naming the flag."""
    from ..errors import ParameterError

    try:
        return tuple(float(part) for part in text.split(","))
    except ValueError:
        raise ParameterError(f"{flag} wants comma-separated numbers such as {example}, got {text!r}") from None
