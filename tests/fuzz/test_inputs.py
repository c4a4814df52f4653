"""A short, deterministic run of the input fuzzer (tests/fuzz/inputs.py, issue 18): mutated
files of every format choreo reads are refused in one line or accepted, never an internal error,
a hang or a memory blow-up. The long run is ``python -m tests.fuzz.inputs``."""

import pytest


@pytest.fixture(scope="module")
def fuzz():
    from tests.fuzz import inputs

    return inputs


def test_mutations_are_deterministic(fuzz):
    import random

    seeds = fuzz.make_seeds(("bvh", "csv", "npz"))
    for fmt, files in seeds.items():
        first = [fuzz.mutate(fmt, random.Random(f"7:{i}"), files) for i in range(20)]
        assert first == [fuzz.mutate(fmt, random.Random(f"7:{i}"), files) for i in range(20)]


def test_a_short_fuzz_run_finds_no_internal_error(fuzz, tiny_checkpoint, tmp_path):
    report = fuzz.run(fuzz.FORMATS, inputs=40 * len(fuzz.FORMATS), seconds=None, seed=18, workers=2, timeout=10.0,
                      memory_cap=1 << 30, findings=tmp_path, sgmd_checkpoint=tiny_checkpoint)
    tried = {fmt: sum(counts.values()) for fmt, counts in report.counts.items()}
    assert tried == {fmt: 40 for fmt in fuzz.FORMATS}
    found = [f"{cls} {fmt}: {detail.splitlines()[0]}" for fmt, cls, detail, _, _ in report.findings.values()]
    assert report.bad() == 0, "\n".join(found)
    for fmt in fuzz.FORMATS:  # the mutations reach past the first check, and not every one is refused
        assert report.counts[fmt]["accepted" if fmt in fuzz.CACHE_FORMATS else "refused"] > 0  # a bad entry: a miss


def test_the_harness_tells_hangs_memory_and_crashes_apart(fuzz, tmp_path, monkeypatch):
    import os
    import signal
    import time

    def hang(path):
        time.sleep(60)

    def blow_up(path):
        return bytearray(8 << 30)

    def crash(path):
        os.kill(os.getpid(), signal.SIGKILL)

    monkeypatch.setattr(fuzz, "warm_up", lambda seeds: None)
    monkeypatch.setitem(fuzz.TARGETS, "csv", hang)
    monkeypatch.setitem(fuzz.TARGETS, "npy", blow_up)
    monkeypatch.setitem(fuzz.TARGETS, "bvh", crash)
    report = fuzz.run(("csv", "npy", "bvh"), inputs=6, seconds=None, seed=0, workers=2, timeout=1.0,
                      memory_cap=1 << 30, findings=tmp_path)
    assert report.counts["csv"]["HANG"] == 2 and report.counts["npy"]["MEMORY"] == 2
    assert report.counts["bvh"]["CRASH"] == 2
    assert {path.parent.name for path in tmp_path.glob("*/*.txt")} == {"csv", "npy", "bvh"}  # each one saved
