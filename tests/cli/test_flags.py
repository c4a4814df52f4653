"""choreo.cli.flags: command-line flags made from settings dataclasses, so each option is declared once."""

from dataclasses import dataclass

import typer
from typer.testing import CliRunner

from choreo.cli.flags import flag_parameters, given_values, with_parameters
from choreo.options import option


@dataclass(frozen=True, kw_only=True)
class Knobs:
    count: int = option(3, "How many.")
    ratio: float | None = option(None, "A ratio.", default_text="the model's")
    loud: bool = option(False, "Be loud.", "--loud/--quiet")
    paces: tuple[float, ...] | None = option(None, "Paces, comma-separated.")
    hidden: int = 7  # not a flag


def knobs_app(given_only: bool = True) -> tuple[typer.Typer, dict]:
    seen = {}

    def command(**values):
        seen.clear()
        seen.update(given_values(Knobs, values))

    app = typer.Typer()
    app.command()(with_parameters(command, flag_parameters(Knobs, given_only=given_only)))
    return app, seen


def test_fields_made_with_option_are_the_flags():
    assert [p.name for p in flag_parameters(Knobs)] == ["count", "ratio", "loud", "paces"]


def test_flags_not_given_are_left_to_the_dataclass():
    app, seen = knobs_app()
    assert CliRunner().invoke(app, []).exit_code == 0 and seen == {}
    assert CliRunner().invoke(app, ["--count", "5", "--quiet", "--paces", "0.5,1", "--ratio", "0.25"]).exit_code == 0
    assert seen == {"count": 5, "loud": False, "paces": (0.5, 1.0), "ratio": 0.25}
    assert Knobs(**seen) == Knobs(count=5, ratio=0.25, loud=False, paces=(0.5, 1.0))


def test_without_given_only_every_flag_has_the_fields_default():
    app, seen = knobs_app(given_only=False)
    assert CliRunner().invoke(app, []).exit_code == 0
    assert seen == {"count": 3, "loud": False}  # ratio and paces default to None: not given


def test_help_shows_the_dataclass_defaults():
    app, _ = knobs_app()
    text = " ".join(CliRunner().invoke(app, ["--help"], env={"COLUMNS": "240"}).output.split())
    assert "How many. [default: 3]" in text and "A ratio. [default: the model's]" in text


def test_a_float_flag_refuses_what_is_not_a_finite_number():
    app, seen = knobs_app()
    result = CliRunner().invoke(app, ["--ratio", "nan"])
    assert result.exit_code != 0 and seen == {}
