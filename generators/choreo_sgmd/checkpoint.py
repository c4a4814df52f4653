"""Self-describing checkpoints: configs as dicts, weights and statistics as tensors.

Everything in the file is a tensor, dict, list, str, int or float, so ``torch.load(...,
weights_only=True)`` reads it without executing code. The model rebuilds from the file alone.
"""

from __future__ import annotations

import os
from pathlib import Path

import torch

from choreo.errors import InputError
from choreo.fileio import atomic_output

FORMAT_VERSION = 1
GENERATOR_NAME = "sgmd"


def save_checkpoint(state: dict, path: str | os.PathLike) -> None:
    state = {"format_version": FORMAT_VERSION, "generator": GENERATOR_NAME, **state}
    with atomic_output(path) as handle:
        torch.save(state, handle)


def load_checkpoint(path: str | os.PathLike) -> dict:
    path = Path(path)
    if not path.is_file():
        raise InputError(f"checkpoint {path} does not exist")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many kinds for a damaged file
        raise InputError(f"{path} is not a readable checkpoint ({type(error).__name__})") from None
    if not isinstance(state, dict) or state.get("generator") != GENERATOR_NAME:
        found = state.get("generator") if isinstance(state, dict) else None
        raise InputError(f"{path} is not an SGMD checkpoint (generator: {found or 'unknown'})")
    if state.get("format_version") != FORMAT_VERSION:
        raise InputError(f"{path} has checkpoint format {state.get('format_version')}, expected {FORMAT_VERSION}")
    return state
