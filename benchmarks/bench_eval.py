"""How fast is `choreo.metrics.evaluate`? 100 five-second clips at 30 fps against 100 more.

Target (issue): 100 clips evaluated in under 10 s on a 2-core CPU. Also times the vectorised
kinetic features against a literal per-frame loop of the reference definition, side by side.

    python benchmarks/bench_eval.py
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from choreo.metrics import Dance, MetricWarning, evaluate, kinetic_features
from choreo.metrics.reference_loops import literal_kinetic, random_dances

TARGET_SECONDS = 10.0


def main() -> None:
    generated, truth = random_dances(100, seed=0), random_dances(100, seed=1)
    beats = np.arange(8, 150, 15)
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        evaluate([Dance(f"g{i}", p, beats) for i, p in enumerate(generated)],
                 [Dance(f"t{i}", p) for i, p in enumerate(truth)])
    seconds = time.perf_counter() - started
    print(f"evaluate: 100 generated + 100 ground-truth clips of 150 frames: {seconds:.2f} s "
          f"({seconds / TARGET_SECONDS:.2f} x the 10 s target)")

    sample = generated[0] - generated[0][:1, :1]
    started = time.perf_counter()
    for _ in range(3):
        literal_kinetic(sample)
    loop = (time.perf_counter() - started) / 3
    started = time.perf_counter()
    for _ in range(30):
        kinetic_features(sample)
    vectorised = (time.perf_counter() - started) / 30
    print(f"kinetic features of one clip: literal loop {loop * 1000:.1f} ms, vectorised {vectorised * 1000:.2f} ms "
          f"({loop / vectorised:.0f}x faster)")


if __name__ == "__main__":
    main()
