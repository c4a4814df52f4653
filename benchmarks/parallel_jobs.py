"""Jobs that share the machine: one, two and four `choreo generate` at once, side by side.

    python benchmarks/parallel_jobs.py [--seconds 60] [--repeats 2]

Each row starts N fresh `choreo generate` processes of the same 60 s song at the same moment (as
`xargs -P N` or a CI matrix on one runner would) and times until the last one ends (median of
``--repeats``). "torch's default" forces one thread per core in every job (``--threads`` set to
the machine's CPUs), as choreo did before its thread policy; "policy" lets each job choose
(choreo.threads). The ratios are to one job alone under the same setting. Targets (issue 37):
one job alone no slower than torch's default, two within 1.5 x one alone, four within 2.7 x.
Run it on an otherwise idle machine: the policy sees other work and yields to it.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import write_song

CLI = "import sys; from choreo.cli import main; sys.exit(main(sys.argv[1:]))"


def run_together(song: Path, folder: Path, jobs: int, threads: int | None) -> float:
    """Wall seconds until ``jobs`` simultaneous generates of ``song`` have all finished."""
    flags = [] if threads is None else ["--threads", str(threads)]
    env = {k: v for k, v in os.environ.items() if k != "OMP_NUM_THREADS"}
    started = time.perf_counter()
    processes = [subprocess.Popen([sys.executable, "-c", CLI, "generate", str(song), "-o", str(folder / f"job{i}.npz"),
                                   *flags], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
                 for i in range(jobs)]
    for process in processes:
        _, err = process.communicate()
        if process.returncode != 0:
            raise SystemExit(f"choreo generate failed: {err.decode()[-300:]}")
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    with tempfile.TemporaryDirectory() as folder:
        song = write_song(Path(folder), args.seconds)
        print(f"| jobs at once | torch's default ({cores} threads each), wall s | x one alone | policy, wall s | x one alone |")
        print("| ---: | ---: | ---: | ---: | ---: |")
        alone = {}
        for jobs in (1, 2, 4):
            walls = {}
            for setting in (cores, None):
                walls[setting] = statistics.median(run_together(song, Path(folder), jobs, setting)
                                                   for _ in range(args.repeats))
                alone.setdefault(setting, walls[setting])
            print(f"| {jobs} | {walls[cores]:.2f} | {walls[cores] / alone[cores]:.2f} | {walls[None]:.2f} | "
                  f"{walls[None] / alone[None]:.2f} |", flush=True)
        print(f"\none job alone, policy against torch's default: {alone[None] / alone[cores]:.2f} x "
              f"({args.seconds:g} s song, {args.repeats} repeats)")


if __name__ == "__main__":
    main()
