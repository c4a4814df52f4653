"""Discover generator plugins through Python entry points."""

from __future__ import annotations

from importlib import import_module
from importlib.metadata import entry_points

from .base import GeneratorPlugin

ENTRY_POINT_GROUP = "choreo.generators"
IN_TREE = {"sgmd": "choreo_sgmd", "graph": "choreo_graph"}  # found without entry points (a checkout run from PYTHONPATH)


def available_plugins() -> dict[str, GeneratorPlugin]:
    """Every registered plugin by name; a plugin that fails to import is reported, not fatal."""
    plugins: dict[str, GeneratorPlugin] = {}
    for entry in entry_points(group=ENTRY_POINT_GROUP):
        try:
            plugin = entry.load()
        except Exception as error:  # a broken third-party plugin must not break the CLI
            plugin = GeneratorPlugin(name=entry.name, summary="(failed to load)", ready=False,
                                     status=f"import error: {type(error).__name__}: {error}")
        if not isinstance(plugin, GeneratorPlugin):
            plugin = GeneratorPlugin(name=entry.name, summary="(invalid plugin object)", ready=False,
                                     status=f"{entry.value} is not a GeneratorPlugin")
        plugins[entry.name] = plugin
    for name, module in IN_TREE.items():
        if name not in plugins:
            try:
                plugins[name] = import_module(module).plugin
            except ImportError:
                pass
    return dict(sorted(plugins.items()))
