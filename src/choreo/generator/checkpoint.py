"""Checkpoint files every backend writes and reads the same way.

A checkpoint is a dict of tensors, dicts, lists, strings and numbers tagged with the backend's
name and a format version, so ``torch.load(..., weights_only=True)`` reads it without executing
code and a file from the other backend (or an older format) is refused with one line.
"""

from __future__ import annotations

import contextlib
import os
from typing import Iterator

from ..errors import ChoreoError, InputError
from ..fileio import atomic_output, input_file
from .archive import check_checkpoint_archive


def write_checkpoint(state: dict, path: str | os.PathLike, generator: str, format_version: int) -> None:
    """Write ``state`` tagged with its backend and format, atomically."""
    import torch

    with atomic_output(path) as handle:
        torch.save({"format_version": format_version, "generator": generator, **state}, handle)


def read_checkpoint(path: str | os.PathLike, generator: str, label: str, format_version: int) -> dict:
    """The state dict of a ``generator`` checkpoint; ``label`` names it in errors ("an SGMD")."""
    import torch

    path = input_file(path, "checkpoint")
    check_checkpoint_archive(path)  # sizes first: torch believes what the file says
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many kinds for a damaged file
        raise InputError(f"{path} is not a readable checkpoint ({type(error).__name__})") from None
    if not isinstance(state, dict) or state.get("generator") != generator:
        found = state.get("generator") if isinstance(state, dict) else None
        raise InputError(f"{path} is not {label} checkpoint (generator: {found or 'unknown'})")
    if state.get("format_version") != format_version:
        raise InputError(f"{path} has checkpoint format {state.get('format_version')}, expected {format_version}")
    return state


# What a state of the right format but wrong content raises where it is used: a missing key, a
# string for a dict, unknown config keys, a tensor of another shape.
STATE_ERRORS = (KeyError, TypeError, ValueError, RuntimeError, AttributeError, IndexError)


@contextlib.contextmanager
def damaged_checkpoint(where: str | os.PathLike, label: str) -> Iterator[None]:
    """Inside the block, STATE_ERRORS are the file's fault: one line naming it (``label``: "SGMD
    checkpoint"), exit 2, not a bug. Choreo's own errors (a setting that differs) pass unchanged."""
    try:
        yield
    except ChoreoError:
        raise
    except STATE_ERRORS as error:
        raise InputError(f"{where}: damaged {label} ({type(error).__name__}: "
                         f"{' '.join(str(error).split())[:120]})") from None
