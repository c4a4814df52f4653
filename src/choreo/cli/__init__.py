"""The `choreo` command line: thin Typer commands over the library.

Commands parse and validate arguments, call one library function, and print. Every
:class:`~choreo.errors.ChoreoError` becomes one line on stderr and a non-zero exit code.
"""

from __future__ import annotations

import os
import sys
import warnings

from ..threads import bound_omp_threads
from .app import app
from .interrupts import signals_raise
from .streams import standard_streams
from .text import plain


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit code (also used by tests).

    SIGINT and SIGTERM unwind the command as exceptions (see :mod:`.interrupts`), so outputs and
    children are cleaned up; the exit code is then the shell's 128 + signal (130, 143)."""
    bound_omp_threads()  # before torch loads
    with standard_streams(), signals_raise() as received:
        try:
            code = _run(argv)
        except KeyboardInterrupt:  # past typer's reach, e.g. while an error was being printed
            code = 130
    if received.signum is not None or code == 130:
        _print_error(f"interrupted ({received.name})")
        return received.exit_code
    return code


def _run(argv: list[str] | None) -> int:
    """The command's exit code: every ChoreoError one line on stderr, anything else a bug (70)."""
    from ..errors import ChoreoError

    try:
        with warnings.catch_warnings():
            if not os.environ.get("CHOREO_DEBUG"):
                # numpy's overflow / invalid-value notes mean nothing to a user, and what they warn of
                # is checked where it matters (non-finite motion, audio and features are refused).
                warnings.filterwarnings("ignore", category=RuntimeWarning)
            warnings.showwarning = _show_warning(warnings.showwarning)
            code = app(args=argv, prog_name="choreo", standalone_mode=False)  # typer: Ctrl-C is 130
            sys.stdout.flush()  # what print() buffered: a full disk shows only now
    except ChoreoError as error:
        _print_error(str(error))
        return error.exit_code
    except SystemExit as exit_:
        return exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
    except Exception as error:
        # Usage errors (unknown command, bad option) come from click, which typer may vendor: one
        # line too, naming the help to read instead of click's usage block. Anything else is a bug.
        if callable(getattr(error, "format_message", None)) and isinstance(getattr(error, "exit_code", None), int):
            context = getattr(error, "ctx", None)
            help_hint = f" (see {context.command_path} --help)" if context is not None else ""
            _print_error(error.format_message() + help_hint)
            return error.exit_code
        if type(error).__name__ == "Abort":
            _print_error("aborted")
            return 1
        if os.environ.get("CHOREO_DEBUG"):
            raise
        _print_error(f"internal error ({type(error).__name__}: {error}); set CHOREO_DEBUG=1 for a traceback")
        return 70
    return code if isinstance(code, int) else 0


def _show_warning(show):
    """``warnings.showwarning`` that prints choreo's own notes (:class:`~choreo.errors.ChoreoNote`)
    as one ``note:`` line in choreo's words, not Python's warning with its source line; others as ``show``."""
    from ..errors import ChoreoNote

    def shown(message, category, filename, lineno, file=None, line=None):
        if not issubclass(category, ChoreoNote):
            return show(message, category, filename, lineno, file, line)
        print_note(str(message))

    return shown


def print_note(message: str) -> None:
    """One ``note:`` line on stderr: something done with the user's files that they should know."""
    from .progress import stderr_console
    from .text import markup

    stderr_console.print(f"[yellow]note:[/yellow] {markup(message.strip())}", highlight=False)


def _print_error(message: str) -> None:
    """One line on stderr, whatever the message holds (newlines, escapes, undecodable bytes)."""
    print(f"choreo: error: {plain(message.strip()) or 'failed'}", file=sys.stderr)


def run() -> None:  # pragma: no cover - console script
    code = main()
    ignore_signals_at_exit()
    sys.exit(code)


def ignore_signals_at_exit() -> None:
    """The command is over: a Ctrl-C or SIGTERM now, while Python shuts down, would raise inside
    its exit handlers and print their traceback (11 lines) over a dance already written."""
    import signal

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_IGN)


__all__ = ["app", "ignore_signals_at_exit", "main", "run"]
