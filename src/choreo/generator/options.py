"""Backend options: each backend declares its generation options as a dataclass, and whatever a
user or script passes is checked against it, by name, before any work is done."""

from __future__ import annotations

from dataclasses import fields
from typing import Any, Mapping, TypeVar

from ..errors import ParameterError

Options = TypeVar("Options")


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
