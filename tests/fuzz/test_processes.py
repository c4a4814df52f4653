"""A short, deterministic run of the process fuzzer (tests/fuzz/processes.py, issue 38): a
choreo process interrupted at a random moment, or writing to an odd output target, ends cleanly
(exit 0 with a complete output, or 130/143/2/3 with one line and nothing left behind). The long
run is ``python -m tests.fuzz.processes``."""

import pytest


@pytest.fixture(scope="module")
def fuzz():
    from tests.fuzz import processes

    return processes


def test_four_cases_of_each_surface_are_clean(fuzz, tmp_path):
    # render is left out: it needs its tools and takes seconds just to check that it works
    done = fuzz.run(None, 4, seed=3, findings=tmp_path / "findings", verbose=False,
                    commands=("convert-bvh-npz", "convert-npz-glb", "info-wav"))
    assert len([c for c in done if c.surface == "interrupt"]) == 4
    assert len([c for c in done if c.surface == "target"]) == 4
    findings = [f"{c.surface} {c.name}: {c.detail}\n{c.result.stderr if c.result else ''}"
                for c in done if c.verdict == "FINDING"]
    assert not findings, "\n".join(findings)
