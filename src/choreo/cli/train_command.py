"""`choreo train NAME`: train a generator backend on a dataset folder.

The core knows no backend's settings: each backend's subcommand is made, when it is called, from
its plugin's ``train_options`` dataclass (its option() fields are the flags, their help and
defaults read from there), beside the options every training shares (--data, --out, --resume).
"""

from __future__ import annotations

from pathlib import Path

import typer
from typer.core import TyperGroup

from .flags import flag_parameters, given_values, with_parameters
from .progress import progress_bar, stderr_console


class BackendCommands(TyperGroup):
    """One subcommand per installed backend that can be trained, made only when it is called
    (its defaults may come from modules heavier than a CLI start should import)."""

    def list_commands(self, ctx):
        from ..generator import available_plugins

        return [name for name, plugin in available_plugins().items() if plugin.train is not None]

    def get_command(self, ctx, name):
        from ..generator import available_plugins

        plugin = available_plugins().get(name)
        if plugin is None or plugin.train is None or plugin.train_options is None:
            return None
        app = typer.Typer(add_completion=False, rich_markup_mode="rich")
        app.command(name)(training_command(plugin))
        return typer.main.get_command(app)


train_app = typer.Typer(
    cls=BackendCommands, no_args_is_help=True, add_completion=False, rich_markup_mode="rich",
    help="Train a backend; rich progress shows loss, validation loss and throughput.\n\n"
         "Examples:\n\n"
         "  choreo train sgmd --data ../shared/data/m2d --out runs/sgmd --steps 8000\n\n"
         "  choreo train graph --data ../shared/data/m2d --out runs/graph --steps 1200\n\n"
         "choreo train NAME --help lists a backend's own options (docs/sgmd.md, docs/graph.md: the bundled recipes).",
)


def training_command(plugin):
    """The command training ``plugin``: the shared options and its own."""
    options_type = plugin.train_options
    shown = options_type.shown_defaults() if hasattr(options_type, "shown_defaults") else {}

    def train(
        data: Path = typer.Option(..., help="Dataset folder: M2D, AIST++ or BVH files with audio beside them."),
        out: Path = typer.Option(..., help="Folder for checkpoints (last.pt is rewritten atomically)."),
        resume: bool = typer.Option(False, "--resume", help="Continue from OUT/last.pt (same data order and noise as "
                                                              "if never stopped)."),
        **values,
    ) -> None:
        from ..errors import ParameterError
        from ..fileio import check_output_folder
        from ..options import parse_options

        if not data.is_dir():
            raise ParameterError(f"--data {data} is not a folder")
        given = given_values(options_type, values)
        if "init_from" in given:
            given["init_from"] = str(given["init_from"])
        check_output_folder(out)  # before the data loads, which takes minutes
        options = parse_options(plugin.name, options_type, given)
        with progress_bar(f"training {plugin.name}") as update:
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

    train.__doc__ = (f"Train {plugin.name}: {plugin.summary}.\n\n    Example:\n"
                     f"      choreo train {plugin.name} --data ../shared/data/m2d --out runs/{plugin.name}\n")
    return with_parameters(train, flag_parameters(options_type, shown, panel=f"{plugin.name} options"))
