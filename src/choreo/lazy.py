"""Packages whose names load their module on first use.

Why: the command line is built from settings dataclasses that live beside the work they set
(choreo.music.beat_options, choreo.motion.delivery_options). Importing them runs their package's
``__init__``; if that imported every module, ``choreo --help`` and a mistyped flag would wait for
numpy and scipy.
"""

from __future__ import annotations

import importlib
from typing import Any, Callable


def lazy_exports(package: str, homes: dict[str, tuple[str, ...]]) -> tuple[Callable[[str], Any], list[str]]:
    """The ``__getattr__`` and ``__all__`` of ``package``, whose names are ``homes``' (submodule ->
    the names it defines): each imported from its submodule when first asked for."""
    home_of = {name: module for module, names in homes.items() for name in names}

    def __getattr__(name: str) -> Any:
        if name not in home_of:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module = importlib.import_module(f"{package}.{home_of[name]}")
        value = getattr(module, name)
        setattr(importlib.import_module(package), name, value)  # asked once
        return value

    return __getattr__, sorted(home_of)
