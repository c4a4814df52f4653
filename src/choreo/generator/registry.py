"""Discover generator plugins through Python entry points."""

from __future__ import annotations

from importlib.metadata import entry_points

from ..errors import ChoreoError, ParameterError
from .base import Generator, GeneratorPlugin

ENTRY_POINT_GROUP = "choreo.generators"


def available_plugins() -> dict[str, GeneratorPlugin]:
    """Every registered plugin by name; a plugin that fails to import is reported, not fatal."""
    plugins: dict[str, GeneratorPlugin] = {}
    for entry in entry_points(group=ENTRY_POINT_GROUP):
        try:
            plugin = entry.load()
        except Exception as error:  # a broken third-party plugin must not break the CLI
            plugin = GeneratorPlugin(entry.name, "(failed to load)", ready=False,
                                     status=f"import error: {type(error).__name__}: {error}")
        if not isinstance(plugin, GeneratorPlugin):
            plugin = GeneratorPlugin(entry.name, "(invalid plugin object)", ready=False,
                                     status=f"{entry.value} is not a GeneratorPlugin")
        plugins[entry.name] = plugin
    return dict(sorted(plugins.items()))


def load_generator(name: str, **kwargs) -> Generator:
    """Build the generator registered as ``name``."""
    plugins = available_plugins()
    if name not in plugins:
        known = ", ".join(plugins) or "none installed"
        raise ParameterError(f"unknown generator {name!r} (available: {known})")
    plugin = plugins[name]
    if not plugin.ready or plugin.factory is None:
        raise ChoreoError(f"generator {name!r} is not available yet: {plugin.status}")
    return plugin.factory(**kwargs)
