"""How many threads a dance is computed on: the CPUs this process may use, less those other work keeps busy.

torch's default is one thread per core of the machine. Beside other jobs (``xargs -P``, GNU
parallel, a CI matrix on one runner) its threads then spin against each other's: two `choreo
generate` at once on two cores sampled several times slower than one alone (docs/results.md,
"Jobs side by side"). So before each dance the
count is chosen again from what is true now: the CPUs this process may run on (its affinity
mask and its cgroup's CPU quota) less the tasks other processes have running at this moment
(the kernel's instantaneous count in /proc/loadavg). ``--threads N`` and ``OMP_NUM_THREADS``
win over the guess, up to the CPUs allowed: torch and libgomp start as many threads as they are
told, and 99,999 of them end the process with a segmentation fault and no message.

The count never changes a dance. A matrix product torch splits over two threads sums in another
order than one thread does, and the difference grows through a diffusion chain (an 8 s dance
differed from its 79th frame on between ``--threads 1`` and ``2``). So torch always computes
with one thread, and the threads share the work by pieces fixed in advance (``in_parallel``:
the sampler's chunks of windows), each piece computed the same way whatever the count.
"""

from __future__ import annotations

import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Callable, Iterable, TypeVar

LOADAVG = Path("/proc/loadavg")
CGROUP_V2_MAX = Path("/sys/fs/cgroup/cpu.max")
CGROUP_V1 = Path("/sys/fs/cgroup/cpu")
SAMPLES, SAMPLE_INTERVAL = 5, 0.004  # seconds: the runnable count is read a few times, its median kept
T, R = TypeVar("T"), TypeVar("R")
_workers = 1  # pieces in_parallel computes at once: set by use_threads


def allowed_cpus() -> int:
    """CPUs this process may run on: its affinity mask, capped by its cgroup's CPU quota."""
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    quota = cgroup_cpu_quota()
    return max(1, min(cpus, math.ceil(quota)) if quota else cpus)


def cgroup_cpu_quota() -> float | None:
    """CPUs' worth of time the cgroup allows (cpu.max, or v1's cfs quota / period); None: no limit."""
    try:
        if CGROUP_V2_MAX.exists():
            quota, period = CGROUP_V2_MAX.read_text().split()[:2]
        else:
            quota = (CGROUP_V1 / "cpu.cfs_quota_us").read_text().strip()
            period = (CGROUP_V1 / "cpu.cfs_period_us").read_text().strip()
    except (OSError, ValueError):
        return None
    if quota in ("max", "-1") or float(period) <= 0:
        return None
    return float(quota) / float(period)


def busy_elsewhere() -> int:
    """Tasks of other processes running or waiting for a CPU now (median of a few quick reads).

    Between reads this process spins rather than sleeps: jobs started together reach this point
    together, and a job asleep here looks idle to the others, so each would take every CPU."""
    counts = []
    for i in range(SAMPLES):
        if i:
            deadline = time.perf_counter() + SAMPLE_INTERVAL
            while time.perf_counter() < deadline:
                pass
        try:
            running = int(LOADAVG.read_text().split()[3].split("/")[0])
        except (OSError, ValueError, IndexError):
            return 0
        counts.append(running - own_running_threads())
    return max(0, sorted(counts)[len(counts) // 2])


def own_running_threads() -> int:
    """This process's threads in state R (the reading one included)."""
    running = 0
    for stat in Path("/proc/self/task").glob("*/stat"):
        try:
            running += stat.read_text().rsplit(")", 1)[1].split()[0] == "R"
        except (OSError, IndexError):
            continue
    return max(running, 1)


def choose_threads(requested: int | None = None) -> int:
    """``requested`` (--threads), else OMP_NUM_THREADS, else the idle share of the allowed CPUs;
    never more than the allowed CPUs (more only spin against each other)."""
    cpus = allowed_cpus()
    if requested:
        return min(requested, cpus)
    given = os.environ.get("OMP_NUM_THREADS", "").strip()
    if _is_count(given) and int(given) > 0:
        return min(int(given), cpus)
    return max(1, min(cpus, cpus - busy_elsewhere()))


def bound_omp_threads() -> None:
    """Cap OMP_NUM_THREADS (a setting from the environment) at the allowed CPUs. Called before torch
    loads: libgomp reads it once, when it loads, and starts that many threads at its first loop."""
    given = os.environ.get("OMP_NUM_THREADS")
    if given:
        os.environ["OMP_NUM_THREADS"] = bounded_thread_setting(given, allowed_cpus())


def bounded_thread_setting(value: str, cpus: int) -> str:
    """``value`` (a count, or OpenMP's comma-separated counts per nesting level) with every count
    capped at ``cpus``; anything else is left as it is, for OpenMP to ignore."""
    counts = [part.strip() for part in value.split(",")]
    if not all(_is_count(count) for count in counts):
        return value
    return ",".join(str(min(int(count), cpus)) for count in counts)


def _is_count(text: str) -> bool:
    """ASCII digits only: ``str.isdigit`` also takes superscripts and other scripts' digits."""
    return text.isascii() and text.isdigit()


def use_threads(requested: int | None = None) -> int:
    """Choose the thread count for the work about to start (``in_parallel`` uses it) and keep torch's
    own at one, so the count cannot change a result; returns it."""
    import torch

    global _workers
    _workers = choose_threads(requested)
    if torch.get_num_threads() != 1:
        torch.set_num_threads(1)
    return _workers


def in_parallel(function: Callable[[T], R], pieces: Iterable[T]) -> list[R]:
    """``[function(piece) for piece in pieces]``, on as many threads as ``use_threads`` chose. Each
    piece is computed whole by one thread, so the results do not depend on the count; torch's
    gradient mode (thread-local) is carried into the workers."""
    import torch

    pieces = list(pieces)
    if _workers == 1 or len(pieces) < 2:
        return [function(piece) for piece in pieces]
    grad = torch.is_grad_enabled()

    def work(piece: T) -> R:
        with torch.set_grad_enabled(grad):
            return function(piece)

    with ThreadPoolExecutor(min(_workers, len(pieces))) as pool:
        return list(pool.map(work, pieces))
