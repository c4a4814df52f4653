"""Options declared once: a settings dataclass's field carries its flag and help, and whatever a
user or script passes is checked against the dataclass, by name, before any work is done.

A backend declares its generation options (``GeneratorPlugin.options``) and its training options
(``GeneratorPlugin.train_options``) as dataclasses; the core declares the finishing passes
(``choreo.finishing.Finishing``), the request (``choreo.pipeline.DanceRequest``), the beat source
(``choreo.music.BeatOptions``) and the delivery (``choreo.motion.delivery.Delivery``) the same way. Fields made with :func:`option` become command-line
flags (``choreo.cli.flags``), their defaults read from the field, so no default is written twice.
"""

from __future__ import annotations

from dataclasses import MISSING, Field, dataclass, field, fields
from typing import Any, Mapping, TypeVar

from .errors import ParameterError

Options = TypeVar("Options")
FLAG = "choreo.flag"  # the metadata key of a field that is a command-line flag


@dataclass(frozen=True)
class Flag:
    """How a field shows on the command line."""

    help: str
    names: tuple[str, ...] = ()  # default: --field-name (a bool: --field-name/--no-field-name)
    existing_file: bool = False  # a path that must name a file (checked before any work)
    default_text: str | None = None  # what help shows as the default where the field's own is None
    bounds: tuple[float, float] | None = None  # a number flag's range, refused while the flags are parsed


def option(default: Any = None, help: str = "", *names: str, existing_file: bool = False,
           default_text: str | None = None, bounds: tuple[float, float] | None = None) -> Any:
    """A dataclass field with ``default`` that is also the flag ``names`` (see :class:`Flag`)."""
    flag = Flag(help, names, existing_file, default_text, bounds)
    return field(default=default, metadata={FLAG: flag})


def flag_fields(options_type: type) -> list[Field]:
    """The fields of ``options_type`` that are command-line flags, in declaration order."""
    return [f for f in fields(options_type) if FLAG in f.metadata]


def field_default(f: Field) -> Any:
    return f.default_factory() if f.default is MISSING and f.default_factory is not MISSING else f.default


def forwarded(config_type: type, options) -> dict:
    """The options (a dataclass or a dict) that ``config_type`` has a field of the same name for, those
    left at None out: how a backend hands its training options to the configurations they set."""
    values = options if isinstance(options, dict) else {f.name: getattr(options, f.name) for f in fields(options)}
    names = {f.name for f in fields(config_type)} & set(values)
    return {name: values[name] for name in sorted(names) if values[name] is not None}


def option_names(options_type: type) -> list[str]:
    return sorted(f.name for f in fields(options_type))


def parse_options(backend: str, options_type: type[Options], given: Mapping[str, Any], base: Options | None = None) -> Options:
    """``options_type`` built from ``given`` (over ``base``, or over its defaults); a name it does
    not have, or a value it refuses, is a one-line ParameterError naming the backend."""
    from dataclasses import replace

    unknown = sorted(set(given) - set(option_names(options_type)))
    if unknown:
        raise ParameterError(f"{backend} has no option{'s' if len(unknown) > 1 else ''} {', '.join(unknown)} "
                             f"(its options: {', '.join(option_names(options_type))})")
    try:
        return replace(base, **given) if base is not None else options_type(**given)
    except (TypeError, ValueError) as error:
        raise ParameterError(f"{backend}: {error}") from None
