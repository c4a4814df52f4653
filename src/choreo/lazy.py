"""Packages whose names load their module on first use (PEP 562).

Why: every CLI start imports each backend plugin's package to find it, and builds its flags from
settings dataclasses that live beside the work they set (choreo.music.beat_options,
choreo.motion.delivery_options). If those packages' ``__init__`` imported every module, ``choreo
--help`` and a mistyped flag would wait for numpy, scipy and torch.
"""

from __future__ import annotations

from importlib import import_module


def lazy_exports(package: str, exports: dict[str, str], namespace: dict):
    """``(__getattr__, __dir__)`` for ``package``, whose exports (``name -> .submodule``) are
    imported from their submodule when first asked for and then kept in ``namespace``."""

    def __getattr__(name: str):
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        namespace[name] = getattr(import_module(exports[name], package), name)
        return namespace[name]

    def __dir__():
        return sorted(set(namespace) | set(exports))

    return __getattr__, __dir__
