"""Paths and CLI helpers shared by tests in several folders (import them: ``from tests.helpers import run_cli``)."""

from pathlib import Path

from choreo.cli import main

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent
EXAMPLE_SONG = REPO / "examples" / "drum_and_bass_174bpm.wav"
AISTPP_FIXTURES = REPO / "tests" / "fixtures" / "aistpp"


def run_cli(capsys, *args):
    code = main(list(map(str, args)))
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code, err, exit_code=2):
    assert code == exit_code, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("choreo: error: ")
    assert "Traceback" not in err
