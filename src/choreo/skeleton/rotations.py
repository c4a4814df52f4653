"""Rotation conversions: axis-angle, quaternion (w, x, y, z), matrix, 6D, Euler.

Written once against the array API standard (through ``array_api_compat``), so the same code runs
on torch tensors (training needs gradients through them) and on numpy arrays (reading a BVH, FK
for a plot) without importing torch: `choreo info dance.bvh` starts without it. Every public
function returns the kind of array it was given; numpy inputs are computed in float64 and
returned in their own float dtype. Conventions: rotations act on column vectors
(``v' = R @ v``); quaternions are unit, scalar first; the 6D form is the first two *rows* of the
matrix (Zhou et al. 2019, as in EDGE's 151-d frame vector).
"""

from __future__ import annotations

import functools

import numpy as np
from array_api_compat import array_namespace as compat_namespace
from array_api_compat import is_numpy_array

__all__ = [
    "axis_angle_to_matrix",
    "matrix_to_axis_angle",
    "axis_angle_to_quaternion",
    "quaternion_to_axis_angle",
    "quaternion_to_matrix",
    "matrix_to_quaternion",
    "matrix_to_rot6d",
    "rot6d_to_matrix",
    "quaternion_multiply",
    "quaternion_conjugate",
    "quaternion_slerp",
    "elementary_rotation",
    "euler_to_matrix",
    "matrix_to_euler",
    "continuous_euler",
]


def _float64_for_numpy(fn):
    """numpy arrays in: computed in float64, returned in the first array's float dtype (float64
    for integer input). Tensors pass through untouched."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        arrays = [a for a in args if is_numpy_array(a)]
        if not arrays:
            return fn(*args, **kwargs)
        dtype = arrays[0].dtype
        out_dtype = dtype if np.issubdtype(dtype, np.floating) else np.float64
        result = fn(*(np.asarray(a, dtype=np.float64) if is_numpy_array(a) else a for a in args), **kwargs)
        return result.astype(out_dtype, copy=False)

    return wrapper


def array_namespace(*arrays):
    """numpy itself for numpy arrays (NumPy >= 2.1 follows the array API standard, and
    array_api_compat's numpy wrapper would cost 0.2 s of imports at start-up); array_api_compat's
    namespace for torch tensors."""
    if all(is_numpy_array(a) for a in arrays):
        return np
    return compat_namespace(*arrays)


def _norm(xp, x):
    return xp.linalg.vector_norm(x, axis=-1, keepdims=True)


def _sqrt_positive(xp, x):
    """sqrt(max(x, 0)) with a zero gradient at 0 instead of inf (the inner where keeps sqrt's
    argument positive, so no nan enters the backward pass)."""
    positive = x > 0
    return xp.where(positive, xp.sqrt(xp.where(positive, x, xp.ones_like(x))), xp.zeros_like(x))


@_float64_for_numpy
def axis_angle_to_quaternion(axis_angle):
    """(..., 3) rotation vectors -> (..., 4) unit quaternions. Stable near zero angle."""
    xp = array_namespace(axis_angle)
    angle = _norm(xp, axis_angle)
    half = angle / 2
    small = xp.abs(angle) < 1e-6
    # sin(a/2)/a -> 1/2 - a^2/48 for small a (Taylor), avoiding 0/0.
    safe_angle = xp.where(small, xp.ones_like(angle), angle)
    scale = xp.where(small, 0.5 - angle * angle / 48, xp.sin(half) / safe_angle)
    return xp.concat([xp.cos(half), axis_angle * scale], axis=-1)


@_float64_for_numpy
def quaternion_to_axis_angle(quaternion):
    """(..., 4) quaternions -> (..., 3) rotation vectors with angle in [0, pi]."""
    xp = array_namespace(quaternion)
    q = quaternion / _norm(xp, quaternion)
    q = xp.where(q[..., :1] < 0, -q, q)  # w >= 0 picks the shorter rotation
    sin_half = _norm(xp, q[..., 1:])
    half = xp.atan2(sin_half, q[..., :1])
    angle = 2 * half
    small = sin_half < 1e-6
    safe_sin = xp.where(small, xp.ones_like(sin_half), sin_half)
    scale = xp.where(small, 2.0 + angle * angle / 12, angle / safe_sin)
    return q[..., 1:] * scale


@_float64_for_numpy
def quaternion_to_matrix(quaternion):
    """(..., 4) quaternions (normalised here) -> (..., 3, 3) rotation matrices."""
    xp = array_namespace(quaternion)
    q = quaternion / _norm(xp, quaternion)
    w, x, y, z = (q[..., i] for i in range(4))
    rows = [
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    ]  # fmt: skip
    return xp.reshape(xp.stack(rows, axis=-1), tuple(q.shape[:-1]) + (3, 3))


@_float64_for_numpy
def matrix_to_quaternion(matrix):
    """(..., 3, 3) rotation matrices -> (..., 4) unit quaternions with w >= 0.

    Computes all four candidate solutions and keeps, per matrix, the one built from the largest
    component: the usual trick that stays accurate for every angle, including 180 degrees.
    """
    xp = array_namespace(matrix)
    m = matrix
    m00, m01, m02 = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    m10, m11, m12 = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    four_sq = xp.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22], axis=-1)
    abs2 = _sqrt_positive(xp, four_sq)  # 2 * |w|, 2 * |x|, 2 * |y|, 2 * |z|
    candidates = xp.stack(
        [
            xp.stack([abs2[..., 0] ** 2, m21 - m12, m02 - m20, m10 - m01], axis=-1),
            xp.stack([m21 - m12, abs2[..., 1] ** 2, m10 + m01, m02 + m20], axis=-1),
            xp.stack([m02 - m20, m10 + m01, abs2[..., 2] ** 2, m12 + m21], axis=-1),
            xp.stack([m10 - m01, m20 + m02, m21 + m12, abs2[..., 3] ** 2], axis=-1),
        ],
        axis=-2,
    )
    candidates = candidates / (2.0 * xp.clip(abs2, min=0.1)[..., None])
    best = xp.argmax(abs2, axis=-1)
    q = xp.take_along_axis(candidates, best[..., None, None], axis=-2)[..., 0, :]
    q = q / _norm(xp, q)
    return xp.where(q[..., :1] < 0, -q, q)


@_float64_for_numpy
def axis_angle_to_matrix(axis_angle):
    """(..., 3) rotation vectors -> (..., 3, 3) matrices."""
    return quaternion_to_matrix(axis_angle_to_quaternion(axis_angle))


@_float64_for_numpy
def matrix_to_axis_angle(matrix):
    """(..., 3, 3) matrices -> (..., 3) rotation vectors."""
    return quaternion_to_axis_angle(matrix_to_quaternion(matrix))


@_float64_for_numpy
def matrix_to_rot6d(matrix):
    """(..., 3, 3) -> (..., 6): the first two rows, flattened row by row."""
    xp = array_namespace(matrix)
    return xp.reshape(matrix[..., :2, :], tuple(matrix.shape[:-2]) + (6,))


@_float64_for_numpy
def rot6d_to_matrix(rot6d):
    """(..., 6) -> (..., 3, 3) by Gram-Schmidt; any 6 numbers give a valid rotation.

    This is what makes 6D a good network output: it is continuous and never needs a projection
    step that can fail.
    """
    xp = array_namespace(rot6d)
    a1, a2 = rot6d[..., :3], rot6d[..., 3:]
    b1 = a1 / xp.clip(_norm(xp, a1), min=1e-12)
    a2 = a2 - xp.sum(b1 * a2, axis=-1, keepdims=True) * b1
    b2 = a2 / xp.clip(_norm(xp, a2), min=1e-12)
    b3 = xp.linalg.cross(b1, b2, axis=-1)
    return xp.stack([b1, b2, b3], axis=-2)


@_float64_for_numpy
def quaternion_multiply(a, b):
    """Hamilton product a * b (apply b, then a), broadcasting over leading dims."""
    xp = array_namespace(a, b)
    aw, ax, ay, az = (a[..., i] for i in range(4))
    bw, bx, by, bz = (b[..., i] for i in range(4))
    return xp.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


@_float64_for_numpy
def quaternion_conjugate(q):
    """Inverse of a unit quaternion."""
    xp = array_namespace(q)
    return xp.concat([q[..., :1], -q[..., 1:]], axis=-1)


@_float64_for_numpy
def quaternion_slerp(a, b, t):
    """Spherical interpolation from a (t=0) to b (t=1) along the shorter arc.

    ``t`` broadcasts against the quaternions' leading dims (shape (...,) or (..., 1)).
    """
    xp = array_namespace(a, b)
    t = xp.asarray(t, dtype=a.dtype)
    if t.ndim == a.ndim - 1:
        t = t[..., None]
    dot = xp.sum(a * b, axis=-1, keepdims=True)
    b = xp.where(dot < 0, -b, b)
    dot = xp.clip(xp.abs(dot), max=1.0)
    theta = xp.acos(dot)
    sin_theta = xp.sin(theta)
    near = sin_theta < 1e-6
    safe = xp.where(near, xp.ones_like(sin_theta), sin_theta)
    wa = xp.where(near, 1 - t, xp.sin((1 - t) * theta) / safe)
    wb = xp.where(near, t, xp.sin(t * theta) / safe)
    out = wa * a + wb * b
    return out / _norm(xp, out)


def _axis_matrix(axis: str, angle):
    xp = array_namespace(angle)
    c, s = xp.cos(angle), xp.sin(angle)
    one, zero = xp.ones_like(angle), xp.zeros_like(angle)
    rows = {
        "X": [one, zero, zero, zero, c, -s, zero, s, c],
        "Y": [c, zero, s, zero, one, zero, -s, zero, c],
        "Z": [c, -s, zero, s, c, zero, zero, zero, one],
    }[axis]
    return xp.reshape(xp.stack(rows, axis=-1), tuple(angle.shape) + (3, 3))


@_float64_for_numpy
def elementary_rotation(angle, axis: str):
    """(...,) angles in radians about one of the axes "X", "Y", "Z" -> (..., 3, 3)."""
    return _axis_matrix(axis.upper(), angle)


@_float64_for_numpy
def euler_to_matrix(angles, order: str = "ZXY"):
    """(..., 3) intrinsic Euler angles in radians -> (..., 3, 3).

    ``order`` names the axes as BVH lists its channels: for "ZXY" the matrix is Rz @ Rx @ Ry and
    ``angles[..., 0]`` is the Z angle. This is how BVH readers (Blender included) compose them.
    """
    order = order.upper()
    matrix = _axis_matrix(order[0], angles[..., 0])
    for i in (1, 2):
        matrix = matrix @ _axis_matrix(order[i], angles[..., i])
    return matrix


@_float64_for_numpy
def matrix_to_euler(matrix, order: str = "ZXY"):
    """Inverse of :func:`euler_to_matrix` for any of the six Tait-Bryan orders (radians)."""
    xp = array_namespace(matrix)
    order = order.upper()
    i, j, k = ("XYZ".index(a) for a in order)
    # Parity of the permutation decides the signs of the off-diagonal terms.
    sign = 1.0 if (j - i) % 3 == 1 else -1.0
    middle = xp.asin(xp.clip(sign * matrix[..., i, k], min=-1.0, max=1.0))
    first = xp.atan2(-sign * matrix[..., j, k], matrix[..., k, k])
    last = xp.atan2(-sign * matrix[..., i, j], matrix[..., i, i])
    # Gimbal lock (|middle| = 90 deg): put the whole remaining rotation into the first angle.
    locked = xp.abs(sign * matrix[..., i, k]) > 1 - 1e-9
    if bool(xp.any(locked)):
        alt_first = xp.atan2(sign * matrix[..., k, j], matrix[..., j, j])
        first = xp.where(locked, alt_first, first)
        last = xp.where(locked, xp.zeros_like(last), last)
    return xp.stack([first, middle, last], axis=-1)


def continuous_euler(angles: np.ndarray, previous: np.ndarray | None = None) -> np.ndarray:
    """(T, ..., 3) Tait-Bryan angles (radians, one frame per row) rewritten so each frame's triple is
    the equivalent one nearest the previous frame's: the same rotations, curves without jumps.

    Each frame's angles solved on their own wrap from +180 to -179 degrees as a joint turns past
    the back, and flip to the other solution near the middle axis's 90 degrees; a DCC tool that
    interpolates or resamples the curves then spins the joint the long way round. Every rotation
    has two triples, (a, b, c) and (a + pi, pi - b, c + pi), each up to whole turns; the one nearer
    the previous frame (after unwrapping by 2 pi) is kept, as an animator's Euler filter does.
    ``previous``: the frame before the first (a curve written in chunks); None keeps the first as solved."""
    angles = np.asarray(angles, dtype=np.float64)
    other = angles + [np.pi, 0.0, np.pi]
    other[..., 1] = np.pi - angles[..., 1]
    out = np.empty_like(angles)
    for t in range(len(angles)):
        if t == 0 and previous is None:
            out[0] = angles[0]
            continue
        reference = out[t - 1] if t else np.asarray(previous, dtype=np.float64)
        first, second = _nearest_turns(angles[t], reference), _nearest_turns(other[t], reference)
        closer = (np.abs(second - reference).sum(-1) < np.abs(first - reference).sum(-1))[..., None]
        out[t] = np.where(closer, second, first)
    return out


def _nearest_turns(angles: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``angles`` plus the whole turns that bring each nearest ``reference``."""
    return angles + 2 * np.pi * np.round((reference - angles) / (2 * np.pi))
