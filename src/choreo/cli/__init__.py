"""The `choreo` command line: thin Typer commands over the library.

Commands parse and validate arguments, call one library function, and print. Every
:class:`~choreo.errors.ChoreoError` becomes one line on stderr and a non-zero exit code.
"""

from __future__ import annotations

import os
import sys
import warnings

from .app import app


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit code (also used by tests)."""
    from ..errors import ChoreoError

    try:
        with warnings.catch_warnings():
            if not os.environ.get("CHOREO_DEBUG"):
                # numpy's overflow / invalid-value notes mean nothing to a user, and what they warn of
                # is checked where it matters (non-finite motion, audio and features are refused).
                warnings.filterwarnings("ignore", category=RuntimeWarning)
            app(args=argv, prog_name="choreo", standalone_mode=False)
    except ChoreoError as error:
        _print_error(str(error))
        return error.exit_code
    except KeyboardInterrupt:
        _print_error("interrupted")
        return 130
    except SystemExit as exit_:
        return exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
    except Exception as error:
        # Usage errors (unknown command, bad option) come from click, which typer may vendor: they
        # know how to show themselves. Anything else is a bug.
        if callable(getattr(error, "show", None)) and isinstance(getattr(error, "exit_code", None), int):
            error.show()
            return error.exit_code
        if type(error).__name__ == "Abort":
            _print_error("aborted")
            return 1
        if os.environ.get("CHOREO_DEBUG"):
            raise
        _print_error(f"internal error ({type(error).__name__}: {error}); set CHOREO_DEBUG=1 for a traceback")
        return 70
    return 0


def _print_error(message: str) -> None:
    first_line = message.strip().splitlines()[0] if message.strip() else "failed"
    print(f"choreo: error: {first_line}", file=sys.stderr)


def run() -> None:  # pragma: no cover - console script
    sys.exit(main())


__all__ = ["app", "main", "run"]
