"""Where the faster foot follows the body: foot~root split into slow and fast parts.

    python scripts/experiments/foot_root_bands.py [--songs DANCE_C_4 DANCE_R_3] [--seed 1]

Issue 45 (docs/results.md, "What the feet and the beats still miss"). For each M2D song, the real
dancer and SGMD's whole dance (the CLI's defaults, the genre as style): the correlation of the
faster foot's horizontal speed with the root's (foot~root), then of their parts below 0.5 Hz and
above it, and the mean speeds of both. A skater's feet follow the body at every time scale; a
stepping dancer's only over seconds, as the body travels. Last, which comes first within a step:
the lag (frames, + when the root follows the foot) at which the two speeds' parts above 0.5 Hz
correlate most, within half a second, and how fast the faster foot moves around the pelvis.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import choreo
from choreo.datasets import load_dataset
from choreo.metrics.stepping import foot_speeds, horizontal_speeds
from choreo.motion.filters import low_pass

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "scripts"))
from evaluate_whole_songs import song_of  # noqa: E402

FPS, SPLIT_HZ = 30.0, 0.5
LAGS = range(-15, 16)  # frames: half a second either way


def lagged_correlation(foot: np.ndarray, root: np.ndarray, lag: int) -> float:
    """Correlation of the foot's speed with the root's ``lag`` frames later."""
    if lag < 0:
        return lagged_correlation(root, foot, -lag)
    return float(np.corrcoef(foot[: len(foot) - lag], root[lag:])[0, 1])


def bands(positions: np.ndarray) -> dict[str, float]:
    left, right = foot_speeds(positions, FPS)
    faster, root = np.maximum(left, right), horizontal_speeds(positions[:, :1], FPS)[:, 0]
    slow_foot, slow_root = low_pass(faster, FPS, SPLIT_HZ), low_pass(root, FPS, SPLIT_HZ)
    return {"foot~root": np.corrcoef(faster, root)[0, 1], "slow": np.corrcoef(slow_foot, slow_root)[0, 1],
            "fast": np.corrcoef(faster - slow_foot, root - slow_root)[0, 1],
            "faster foot m/s": faster.mean(), "root m/s": root.mean(),
            "faster foot above 0.5 Hz, s.d.": (faster - slow_foot).std(),
            "faster foot 10th / 90th percentile": "{:.2f} / {:.2f}".format(*np.percentile(faster, [10, 90])),
            "root after foot: lag, correlation": lead_of(faster - slow_foot, root - slow_root),
            "faster foot around the pelvis, median m/s": np.median(np.maximum(*foot_speeds(positions - positions[:, :1], FPS)))}


def lead_of(foot: np.ndarray, root: np.ndarray) -> str:
    """"lag frames, correlation" at the lag where the root's speed follows the foot's most closely."""
    correlations = {lag: lagged_correlation(foot, root, lag) for lag in LAGS}
    best = max(correlations, key=correlations.get)
    return f"{best:+d}, {correlations[best]:.2f} (at 0: {correlations[0]:.2f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--songs", nargs="+", default=["DANCE_C_4", "DANCE_R_3"])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--checkpoint", default=None, help="an SGMD checkpoint (default: the bundled one)")
    args = parser.parse_args()
    clips = {c.name: c for c in load_dataset(args.data)}
    backend = choreo.load_backend("sgmd", args.checkpoint)
    print("| song | dancer | foot~root | below 0.5 Hz | above | faster foot m/s | root m/s | faster foot above 0.5 Hz, "
          "s.d. | faster foot 10th / 90th percentile | root after foot: lag, correlation | faster foot around the pelvis, "
          "median m/s |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name in args.songs:
        clip = clips[name]
        music = song_of(clip)
        dances = {"real": clip.motion.joint_positions()[: len(music.features)],
                  "SGMD": choreo.dance(music, backend, style=clip.genre, seed=args.seed).joint_positions()}
        for who, positions in dances.items():
            print(f"| {name} | {who} | " + " | ".join(v if isinstance(v, str) else f"{v:.3f}"
                                                     for v in bands(positions).values()) + " |")


if __name__ == "__main__":
    main()
