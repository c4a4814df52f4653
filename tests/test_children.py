"""Tests of choreo.children.

Markers say where a test came from: hardening (pyproject.toml, tests/README.md)."""

import subprocess

import pytest


@pytest.mark.hardening
def test_an_interrupt_while_a_child_starts_is_raised_once_the_child_is_held_and_kills_it(monkeypatch):
    """The flake this fixes: a SIGTERM inside Popen left ffmpeg running, unknown, and it wrote its
    output after choreo had removed the temporary."""
    from choreo import children

    real, started = subprocess.Popen, []

    def popen(*args, **kwargs):
        process = real(*args, **kwargs)
        started.append(process)
        assert children.starting_a_child()
        children.defer_interrupt(KeyboardInterrupt("SIGTERM"))  # what choreo's handler does now
        return process

    monkeypatch.setattr(children.subprocess, "Popen", popen)
    with pytest.raises(KeyboardInterrupt):
        with children.child_process(["sleep", "30"]):
            pytest.fail("the block must not run once an interrupt is pending")
    assert started[0].returncode is not None  # killed and reaped
    assert not children.starting_a_child()
