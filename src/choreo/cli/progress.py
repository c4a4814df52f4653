"""Rich progress bars for long work, written to stderr so stdout stays clean for `-o -`."""

from __future__ import annotations

import contextlib
from typing import Callable, Iterator

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

stderr_console = Console(stderr=True)
stdout_console = Console()


@contextlib.contextmanager
def progress_bar(description: str, total: float | None = None) -> Iterator[Callable[..., None]]:
    """Yield ``update(done, total=None, name=None)`` driving one bar; hidden when not a terminal."""
    columns = [TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
               TextColumn("{task.fields[item]}"), TimeElapsedColumn(), TimeRemainingColumn()]
    with Progress(*columns, console=stderr_console, transient=False, disable=not stderr_console.is_terminal) as bar:
        task = bar.add_task(description, total=total, item="")

        def update(done: float, total: float | None = None, name: str | None = None) -> None:
            bar.update(task, completed=done, total=total if total is not None else bar.tasks[0].total,
                       item=name or "")

        yield update
