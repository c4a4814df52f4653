"""The Typer application and its commands."""

from __future__ import annotations

import typer

from . import commands
from .eval_command import evaluate
from .generate_command import generate, inbetween, inpaint, trajectory
from .graph_command import graph_app
from .render_command import render
from .train_command import train_app

app = typer.Typer(
    name="choreo",
    help="Music to dance: generate, edit, convert and evaluate skeleton animations.\n\n"
    "Example: choreo info examples/drum_and_bass_174bpm.wav",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode="rich",
)

app.command("generate")(generate)
app.command("inbetween")(inbetween)
app.command("inpaint")(inpaint)
app.command("trajectory")(trajectory)
app.command("info")(commands.info)
app.command("convert")(commands.convert)
app.command("generators")(commands.generators)
app.command("prepare")(commands.prepare)
app.command("eval")(evaluate)
app.add_typer(train_app, name="train")
app.command("render")(render)
app.add_typer(graph_app, name="graph")
