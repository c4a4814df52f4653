"""Rich progress bars for long work, written to stderr so stdout stays clean for `-o -`."""

from __future__ import annotations

import contextlib
import time
from typing import Callable, Iterator

from rich.console import Console

from .text import markup

stderr_console = Console(stderr=True, soft_wrap=True)  # one message, one line, whatever the width
LOG_INTERVAL = 30.0  # seconds between plain progress lines when stderr is not a terminal
stdout_console = Console()


@contextlib.contextmanager
def progress_bar(description: str, total: float | None = None) -> Iterator[Callable[..., None]]:
    """Yield ``update(done, total=None, name=None)`` driving one bar.

    ``description`` and ``name`` may hold user-supplied text (song and clip names): it is printed
    as text, never as markup. Off a terminal (logs, batch jobs) the bar is hidden and a plain line is printed at most every
    ``LOG_INTERVAL`` seconds instead, so a job run under nohup still shows that it is alive.
    """
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    columns = [TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
               TextColumn("{task.fields[item]}"), TimeElapsedColumn(), TimeRemainingColumn()]
    description = markup(description)
    with Progress(*columns, console=stderr_console, transient=False, disable=not stderr_console.is_terminal) as bar:
        task = bar.add_task(description, total=total, item="")

        last_line = time.monotonic()

        def update(done: float, total: float | None = None, name: str | None = None) -> None:
            nonlocal last_line
            bar.update(task, completed=done, total=total if total is not None else bar.tasks[0].total,
                       item=markup(name or ""))
            if bar.disable and time.monotonic() - last_line >= LOG_INTERVAL:
                last_line = time.monotonic()
                of = f"/{bar.tasks[0].total:g}" if bar.tasks[0].total else ""
                stderr_console.print(f"{description}: {done:g}{of} {markup(name or '')}".rstrip(), highlight=False)

        yield update
