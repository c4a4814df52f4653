"""Stepping: do the feet plant and carry the body, or glide along with it?

PFC weighs sliding by the root's acceleration, so a dancer who skates at an even pace scores well.
These three figures look at the feet directly (Y up, joint positions in metres):

- planted share: frames where one foot (its ankle or its toe) moves under 0.15 m/s horizontally.
  Real M2D dancers' shares: docs/results.md, "Whole songs".
- foot-root correlation: Pearson correlation, over frames, of the faster foot's horizontal speed
  with the root's. A stepping dancer's feet alternate between standing and swinging (low); a
  skater's feet travel with the body (high).
- support slide: metres the slower foot travels horizontally per metre the root travels. The
  slower foot is the one that should carry the body: 0 when it never moves, about 1 when both
  feet glide along with the root.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..skeleton import LEFT_ANKLE_FOOT, RIGHT_ANKLE_FOOT

PLANTED_SPEED = 0.15  # m/s horizontally: a foot slower than this stands
STEADY_SPEED = 1e-6  # m/s: a speed varying less than this is constant (no correlation to take)
UP_AXIS = 1  # Y up


@dataclass(frozen=True)
class Stepping:
    """One dance's stepping figures, and the sums a set's figures are pooled from."""

    frames: int  # frames with a speed (the dance's frames - 1)
    planted_frames: int
    foot_root_correlation: float  # NaN when either speed is constant
    support_travel: float  # metres the slower foot travelled
    root_travel: float  # metres the root travelled

    @property
    def planted_share(self) -> float:
        return self.planted_frames / self.frames if self.frames else float("nan")

    @property
    def support_slide(self) -> float:
        return self.support_travel / self.root_travel if self.root_travel > 0 else float("nan")


def horizontal_speeds(positions: np.ndarray, fps: float) -> np.ndarray:
    """(T, J, 3) positions -> (T - 1, J) horizontal speeds in m/s."""
    step = np.diff(np.asarray(positions, dtype=np.float64), axis=0)
    step[..., UP_AXIS] = 0.0
    return np.linalg.norm(step, axis=-1) * fps


def foot_speeds(positions: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """(left, right) feet's horizontal speeds per frame: each foot's slower joint (ankle or toe),
    since a heel or a toe that stands is a foot that pivots, not one that slides."""
    speeds = horizontal_speeds(positions, fps)
    return speeds[:, list(LEFT_ANKLE_FOOT)].min(axis=1), speeds[:, list(RIGHT_ANKLE_FOOT)].min(axis=1)


def stepping(positions: np.ndarray, fps: float) -> Stepping:
    """Stepping figures of one dance (T, 24, 3)."""
    positions = np.asarray(positions, dtype=np.float64)
    if len(positions) < 3:
        return Stepping(max(len(positions) - 1, 0), 0, float("nan"), 0.0, 0.0)
    left, right = foot_speeds(positions, fps)
    slower, faster = np.minimum(left, right), np.maximum(left, right)
    root = horizontal_speeds(positions[:, :1], fps)[:, 0]
    return Stepping(len(slower), int((slower < PLANTED_SPEED).sum()), _correlation(faster, root),
                    float(slower.sum() / fps), float(root.sum() / fps))


def pooled(dances: list[Stepping]) -> tuple[float, float, float]:
    """(planted share, foot-root correlation, support slide) of a set: shares and slides pooled over
    all frames and metres, the correlation averaged over the dances that have one."""
    frames = sum(d.frames for d in dances)
    root = sum(d.root_travel for d in dances)
    correlations = [d.foot_root_correlation for d in dances if np.isfinite(d.foot_root_correlation)]
    return (sum(d.planted_frames for d in dances) / frames if frames else float("nan"),
            float(np.mean(correlations)) if correlations else float("nan"),
            sum(d.support_travel for d in dances) / root if root > 0 else float("nan"))


def median_root_speed(dances: list[np.ndarray], fps: float) -> float:
    """Median horizontal root speed (m/s) over every frame of a set of dances (T, 24, 3): how far a
    style travels, which a gliding dancer overdoes."""
    speeds = [horizontal_speeds(np.asarray(d)[:, :1], fps)[:, 0] for d in dances if len(d) >= 2]
    return float(np.median(np.concatenate(speeds))) if speeds else float("nan")


def pace_and_feet_by_genre(dances: list[np.ndarray], real: list[np.ndarray], genres: list[str], fps: float) -> str:
    """"root m/s cha-cha 0.32 (0.50), ...; foot~root cha-cha 0.34 (0.15), ...": each genre's median
    horizontal root speed and foot-root correlation, real dancers' on the same windows in brackets.
    Per genre because the genres differ: real waltz (captured at 5.9 fps, interpolated) has a
    foot-root correlation of 0.47, real cha-cha and rumba 0.14-0.15."""
    speeds, feet = [], []
    for genre in sorted(set(genres)):
        mine = [d for d, g in zip(dances, genres) if g == genre]
        theirs = [d for d, g in zip(real, genres) if g == genre]
        speeds.append(f"{genre} {median_root_speed(mine, fps):.2f} ({median_root_speed(theirs, fps):.2f})")
        correlation = [pooled([stepping(d, fps) for d in group])[1] for group in (mine, theirs)]
        feet.append(f"{genre} {correlation[0]:.2f} ({correlation[1]:.2f})")
    return "root m/s " + ", ".join(speeds) + "; foot~root " + ", ".join(feet)


def _correlation(a: np.ndarray, b: np.ndarray) -> float:
    if a.std() < STEADY_SPEED or b.std() < STEADY_SPEED:
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])
