"""The generator interface every backend implements, and the plugin registry."""

from .base import GenerationRequest, Generator, GeneratorPlugin, TrainProgress
from .registry import ENTRY_POINT_GROUP, available_plugins

__all__ = ["ENTRY_POINT_GROUP", "GenerationRequest", "Generator", "GeneratorPlugin", "available_plugins",
           "TrainProgress"]
