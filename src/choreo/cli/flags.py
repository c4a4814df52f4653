"""Command-line flags made from settings dataclasses, so each option is declared once.

A field made with :func:`choreo.options.option` carries its help and flag names; its
default is the field's. :func:`flag_parameters` turns a dataclass's such fields into typer
parameters (for a command's signature, see :func:`with_parameters`) and :func:`given_values`
reads them back, leaving out the ones not given, so the dataclass's own defaults apply.
"""

from __future__ import annotations

import inspect
import sys
import types
import typing
from dataclasses import Field
from pathlib import Path
from typing import Any, Callable, Optional

import typer

from ..options import FLAG, field_default, flag_fields
from .numbers import Number


def flag_parameters(options_type: type, defaults: dict | None = None, given_only: bool = True,
                    panel: str | None = None) -> list[inspect.Parameter]:
    """One keyword parameter per flag field of ``options_type``. With ``given_only`` a flag not
    given parses to None, so that the dataclass (or what reads it) picks the default, and help
    shows the field's default, or what a None default stands for: ``defaults`` (a field's name to
    its value) or the flag's ``default_text``. Without, the flag's default is the field's. ``panel``:
    the heading help lists them under."""
    hints = _flag_hints(options_type)
    return [_parameter(f, hints[f.name], (defaults or {}).get(f.name), given_only, panel) for f in flag_fields(options_type)]


def given_values(options_type: type, values: dict[str, Any]) -> dict[str, Any]:
    """The flag fields of ``options_type`` taken out of ``values`` (a command's arguments), those
    not given left out; comma lists become tuples of numbers."""
    hints, given = _flag_hints(options_type), {}
    for f in flag_fields(options_type):
        value = values.pop(f.name)
        if value is not None:
            given[f.name] = _numbers(_names(f)[0], value) if _base_type(hints[f.name]) is tuple else value
    return given


def with_parameters(command: Callable, extra: list[inspect.Parameter]) -> Callable:
    """``command`` with ``extra`` keyword parameters added to the signature typer reads (they
    arrive in ``**kwargs``)."""
    signature = inspect.signature(command, eval_str=True)
    own = [p for p in signature.parameters.values() if p.kind != inspect.Parameter.VAR_KEYWORD]
    command.__signature__ = signature.replace(parameters=own + extra)
    return command


def _flag_hints(options_type: type) -> dict[str, Any]:
    """The types of ``options_type``'s flag fields. Only theirs: a request's other fields may name
    types its module imports for type checkers alone, which ``typing.get_type_hints`` cannot resolve."""
    namespace = vars(sys.modules[options_type.__module__])
    return {f.name: eval(f.type, namespace) if isinstance(f.type, str) else f.type  # noqa: S307 - the module's own annotation
            for f in flag_fields(options_type)}


def _parameter(f: Field, hint, shown_default, given_only: bool, panel: str | None) -> inspect.Parameter:
    flag = f.metadata[FLAG]
    default = field_default(f)
    shown_default = default if default is not None else shown_default
    default = None if given_only else default
    kind = _base_type(hint)
    names = _names(f, kind)
    shown = flag.default_text or (None if shown_default is None else _shown(shown_default))
    help_text = flag.help + (f" \\[default: {shown}]" if default is None and shown is not None else "")
    extra: dict[str, Any] = {}
    if kind is float or (kind is int and flag.bounds):
        extra["parser"] = Number(names[0].split("/")[0], *(flag.bounds or ()), whole=kind is int)
    if flag.existing_file:
        kind, extra = Path, {"exists": True, "dir_okay": False}
    if kind is tuple:  # a comma list, read by given_values
        kind = str
    option = typer.Option(default, *names, help=help_text, show_default=default is not None, rich_help_panel=panel, **extra)
    return inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY, default=option,
                             annotation=kind if default is not None else Optional[kind])


def _base_type(hint):
    """int of ``int | None``; tuple of ``tuple[float, ...] | None``."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        hint = next(a for a in typing.get_args(hint) if a is not type(None))
    return typing.get_origin(hint) or hint


def _names(f: Field, kind: type | None = None) -> tuple[str, ...]:
    """The flag's names: its own, or --field-name (a bool: --field-name/--no-field-name)."""
    dashed = f.name.replace("_", "-")
    return f.metadata[FLAG].names or ((f"--{dashed}/--no-{dashed}",) if kind is bool else (f"--{dashed}",))


def _shown(value) -> str:
    if isinstance(value, tuple):
        return ",".join(f"{v:g}" for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def _numbers(flag: str, text) -> tuple[float, ...]:
    """Comma-separated numbers of a flag, or a one-line error naming the flag."""
    from ..errors import ParameterError

    try:
        return tuple(float(part) for part in str(text).split(","))
    except ValueError:
        raise ParameterError(f"{flag} wants comma-separated numbers such as 0.85,1,1.18, got {text!r}") from None
