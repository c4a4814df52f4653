"""Geometric ("manual") features (32), after the AIST++ API's Müller-style boolean relations.

Each feature is a yes/no question about a frame (is the right wrist in front of the body's plane?
is the left knee bent?), averaged over frames 1..T-1 into a fraction. Reproduced for
comparability, including what the reference does that one might not expect:
- velocities use a frame time of 1/120 s whatever the real frame rate;
- thresholds scale with a fixed template body (humerus 0.2568 m, shoulder width 0.3908 m,
  hip width 0.1192 m), not with the dancer;
- the "move" relation measures its third joint's motion and ignores its fourth argument;
- Y is up (the "lowest joint" reference is the minimum y of the frame).
Vectorised over frames; tests compare it with a literal per-frame implementation.
"""

from __future__ import annotations

import numpy as np

GEOMETRIC_FRAME_TIME = 1.0 / 120.0
_NAMES = ("root", "lhip", "rhip", "belly", "lknee", "rknee", "spine", "lankle", "rankle", "chest", "ltoes",
          "rtoes", "neck", "linshoulder", "rinshoulder", "head", "lshoulder", "rshoulder", "lelbow", "relbow",
          "lwrist", "rwrist", "lhand", "rhand")
J = {name: i for i, name in enumerate(_NAMES)}
# Template body measures (AIST++ API, from the SMPL template's joints).
HUMERUS = float(np.linalg.norm(np.subtract([1.99113488e-01, 2.36807942e-01, -1.80702247e-02],
                                           [4.54445392e-01, 2.21158922e-01, -4.10167128e-02])))
SHOULDER_WIDTH = float(np.linalg.norm(np.subtract([1.99113488e-01, 2.36807942e-01, -1.80702247e-02],
                                                  [-1.91692337e-01, 2.36928746e-01, -1.23055102e-02])))
HIP_WIDTH = float(np.linalg.norm(np.subtract([5.64076714e-02, -3.23069185e-01, 1.09197125e-02],
                                             [-6.24834076e-02, -3.31302464e-01, 1.50412619e-02])))


def _dot(a, b):
    return (a * b).sum(-1)


def _unit_length(v):
    return np.linalg.norm(v, axis=-1)


class _Frames:
    """Current (frames 1..T-1) and previous (0..T-2) positions, plus the virtual points."""

    def __init__(self, positions: np.ndarray):
        self.now, self.prev = positions[1:], positions[:-1]
        n = len(self.now)
        lowest = self.now[..., 1].min(axis=1)
        self.virtual = {
            "zero": np.zeros((n, 3)), "y_unit": np.tile([0.0, 1.0, 0.0], (n, 1)),
            "minus_y_unit": np.tile([0.0, -1.0, 0.0], (n, 1)),
            "y_min": np.stack([np.zeros(n), lowest, np.zeros(n)], axis=-1),
        }  # fmt: skip

    def at(self, name):
        return self.virtual[name] if name in self.virtual else self.now[:, J[name]]

    def before(self, name):
        return self.prev[:, J[name]]


def _plane(f, a, b, c, p, threshold):
    """Is p more than threshold in front of the plane through a, b, c (normal (c-a) x (b-a))?"""
    normal = np.cross(f.at(c) - f.at(a), f.at(b) - f.at(a))
    with np.errstate(invalid="ignore", divide="ignore"):
        return _dot(normal, f.at(p) - f.at(a)) / _unit_length(normal) > threshold


def _normal_plane(f, n1, n2, a, p, threshold):
    """Is p more than threshold along n2 - n1 from the plane through a with that normal?"""
    normal = f.at(n2) - f.at(n1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return _dot(normal, f.at(p) - f.at(a)) / _unit_length(normal) > threshold


def _angle(f, j1, j2, k1, k2, degrees_range):
    """Is the angle between j2 - j1 and k2 - k1 strictly inside the range (degrees)?"""
    j, k = f.at(j2) - f.at(j1), f.at(k2) - f.at(k1)
    with np.errstate(invalid="ignore", divide="ignore"):
        angle = np.degrees(np.arccos(_dot(j, k) / (_unit_length(j) * _unit_length(k))))
    return (angle > degrees_range[0]) & (angle < degrees_range[1])


def _move(f, j1, j2, j3, _unused, threshold):
    """Does j3 move (relative to j1) faster than threshold along j2 - j1? (4th argument unused.)"""
    velocity = (f.at(j3) - f.at(j1)) - (f.before(j3) - f.before(j1))
    direction = f.at(j2) - f.at(j1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return _dot(velocity, direction) / _unit_length(direction) / GEOMETRIC_FRAME_TIME > threshold


def _normal_move(f, j1, j2, j3, j4, threshold):
    """Does j4 move (relative to j1) faster than threshold along (j3 - j1) x (j2 - j1)?"""
    velocity = (f.at(j4) - f.at(j1)) - (f.before(j4) - f.before(j1))
    direction = np.cross(f.at(j3) - f.at(j1), f.at(j2) - f.at(j1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return _dot(velocity, direction) / _unit_length(direction) / GEOMETRIC_FRAME_TIME > threshold


def _fast(f, j, threshold):
    return _unit_length(f.at(j) - f.before(j)) / GEOMETRIC_FRAME_TIME > threshold


hl, sw, hw = HUMERUS, SHOULDER_WIDTH, HIP_WIDTH
RELATIONS = (  # the 32 questions, in the reference's order
    (_normal_move, ("neck", "rhip", "lhip", "rwrist", 1.8 * hl)),
    (_normal_move, ("neck", "lhip", "rhip", "lwrist", 1.8 * hl)),
    (_normal_plane, ("chest", "neck", "neck", "rwrist", 0.2 * hl)),
    (_normal_plane, ("chest", "neck", "neck", "lwrist", 0.2 * hl)),
    (_move, ("belly", "chest", "chest", "rwrist", 1.8 * hl)),
    (_move, ("belly", "chest", "chest", "lwrist", 1.8 * hl)),
    (_angle, ("relbow", "rshoulder", "relbow", "rwrist", (0, 110))),
    (_angle, ("lelbow", "lshoulder", "lelbow", "lwrist", (0, 110))),
    (_normal_plane, ("lshoulder", "rshoulder", "lwrist", "rwrist", 2.5 * sw)),
    (_move, ("lwrist", "rwrist", "rwrist", "lwrist", 1.4 * hl)),
    (_move, ("rwrist", "root", "lwrist", "root", 1.4 * hl)),
    (_move, ("lwrist", "root", "rwrist", "root", 1.4 * hl)),
    (_fast, ("rwrist", 2.5 * hl)),
    (_fast, ("lwrist", 2.5 * hl)),
    (_plane, ("root", "lhip", "ltoes", "rankle", 0.38 * hl)),
    (_plane, ("root", "rhip", "rtoes", "lankle", 0.38 * hl)),
    (_normal_plane, ("zero", "y_unit", "y_min", "rankle", 1.2 * hl)),
    (_normal_plane, ("zero", "y_unit", "y_min", "lankle", 1.2 * hl)),
    (_normal_plane, ("lhip", "rhip", "lankle", "rankle", 2.1 * hw)),
    (_angle, ("rknee", "rhip", "rknee", "rankle", (0, 110))),
    (_angle, ("lknee", "lhip", "lknee", "lankle", (0, 110))),
    (_fast, ("rankle", 2.5 * hl)),
    (_fast, ("lankle", 2.5 * hl)),
    (_angle, ("neck", "root", "rshoulder", "relbow", (25, 180))),
    (_angle, ("neck", "root", "lshoulder", "lelbow", (25, 180))),
    (_angle, ("neck", "root", "rhip", "rknee", (50, 180))),
    (_angle, ("neck", "root", "lhip", "lknee", (50, 180))),
    (_plane, ("rankle", "neck", "lankle", "root", 0.5 * hl)),
    (_angle, ("neck", "root", "zero", "y_unit", (70, 110))),
    (_normal_plane, ("zero", "minus_y_unit", "y_min", "rwrist", -1.2 * hl)),
    (_normal_plane, ("zero", "minus_y_unit", "y_min", "lwrist", -1.2 * hl)),
    (_fast, ("root", 2.3 * hl)),
)


def geometric_features(positions: np.ndarray) -> np.ndarray:
    """(32,) fraction of frames 1..T-1 for which each relation holds; ``positions`` (T, 24, 3), Y up."""
    frames = _Frames(np.asarray(positions, dtype=np.float64))
    answers = np.stack([relation(frames, *args) for relation, args in RELATIONS], axis=-1)
    return answers.mean(axis=0).astype(np.float32)
