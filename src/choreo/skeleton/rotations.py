"""Rotation conversions: axis-angle, quaternion (w, x, y, z), matrix, 6D, Euler.

Written once in torch (training needs gradients through them) and usable from numpy: every public
function accepts a numpy array or a tensor and returns the same kind it was given. Conventions:
rotations act on column vectors (``v' = R @ v``); quaternions are unit, scalar first; the 6D form
is the first two *rows* of the matrix (Zhou et al. 2019, as in EDGE's 151-d frame vector).
"""

from __future__ import annotations

import functools

import numpy as np
import torch

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
]


def _numpy_in_numpy_out(fn):
    """Let a torch implementation take and return numpy arrays (computed in float64)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if not any(isinstance(a, np.ndarray) for a in args):
            return fn(*args, **kwargs)
        dtype = next(a.dtype for a in args if isinstance(a, np.ndarray))
        out_dtype = dtype if np.issubdtype(dtype, np.floating) else np.float64
        tensors = [torch.from_numpy(np.asarray(a, dtype=np.float64)) if isinstance(a, np.ndarray) else a for a in args]
        result = fn(*tensors, **kwargs)
        return result.numpy().astype(out_dtype, copy=False)

    return wrapper


def _sqrt_positive(x: torch.Tensor) -> torch.Tensor:
    """sqrt(max(x, 0)) with a zero gradient at 0 instead of inf."""
    out = torch.zeros_like(x)
    positive = x > 0
    out[positive] = torch.sqrt(x[positive])
    return out


@_numpy_in_numpy_out
def axis_angle_to_quaternion(axis_angle: torch.Tensor) -> torch.Tensor:
    """(..., 3) rotation vectors -> (..., 4) unit quaternions. Stable near zero angle."""
    angle = torch.linalg.norm(axis_angle, dim=-1, keepdim=True)
    half = angle / 2
    small = angle.abs() < 1e-6
    # sin(a/2)/a -> 1/2 - a^2/48 for small a (Taylor), avoiding 0/0.
    safe_angle = torch.where(small, torch.ones_like(angle), angle)
    scale = torch.where(small, 0.5 - angle * angle / 48, torch.sin(half) / safe_angle)
    return torch.cat([torch.cos(half), axis_angle * scale], dim=-1)


@_numpy_in_numpy_out
def quaternion_to_axis_angle(quaternion: torch.Tensor) -> torch.Tensor:
    """(..., 4) quaternions -> (..., 3) rotation vectors with angle in [0, pi]."""
    q = quaternion / torch.linalg.norm(quaternion, dim=-1, keepdim=True)
    q = torch.where(q[..., :1] < 0, -q, q)  # w >= 0 picks the shorter rotation
    sin_half = torch.linalg.norm(q[..., 1:], dim=-1, keepdim=True)
    half = torch.atan2(sin_half, q[..., :1])
    angle = 2 * half
    small = sin_half < 1e-6
    safe_sin = torch.where(small, torch.ones_like(sin_half), sin_half)
    scale = torch.where(small, 2.0 + angle * angle / 12, angle / safe_sin)
    return q[..., 1:] * scale


@_numpy_in_numpy_out
def quaternion_to_matrix(quaternion: torch.Tensor) -> torch.Tensor:
    """(..., 4) quaternions (normalised here) -> (..., 3, 3) rotation matrices."""
    q = quaternion / torch.linalg.norm(quaternion, dim=-1, keepdim=True)
    w, x, y, z = q.unbind(-1)
    rows = [
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    ]  # fmt: skip
    return torch.stack(rows, dim=-1).reshape(q.shape[:-1] + (3, 3))


@_numpy_in_numpy_out
def matrix_to_quaternion(matrix: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) rotation matrices -> (..., 4) unit quaternions with w >= 0.

    Computes all four candidate solutions and keeps, per matrix, the one built from the largest
    component: the usual trick that stays accurate for every angle, including 180 degrees.
    """
    m = matrix
    m00, m01, m02 = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    m10, m11, m12 = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    four_sq = torch.stack(
        [1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22], dim=-1
    )
    abs2 = _sqrt_positive(four_sq)  # 2 * |w|, 2 * |x|, 2 * |y|, 2 * |z|
    candidates = torch.stack(
        [
            torch.stack([abs2[..., 0] ** 2, m21 - m12, m02 - m20, m10 - m01], dim=-1),
            torch.stack([m21 - m12, abs2[..., 1] ** 2, m10 + m01, m02 + m20], dim=-1),
            torch.stack([m02 - m20, m10 + m01, abs2[..., 2] ** 2, m12 + m21], dim=-1),
            torch.stack([m10 - m01, m20 + m02, m21 + m12, abs2[..., 3] ** 2], dim=-1),
        ],
        dim=-2,
    )
    denom = 2.0 * abs2.clamp(min=0.1)[..., None]
    candidates = candidates / denom
    best = abs2.argmax(dim=-1)
    q = torch.gather(candidates, -2, best[..., None, None].expand(best.shape + (1, 4))).squeeze(-2)
    q = q / torch.linalg.norm(q, dim=-1, keepdim=True)
    return torch.where(q[..., :1] < 0, -q, q)


@_numpy_in_numpy_out
def axis_angle_to_matrix(axis_angle: torch.Tensor) -> torch.Tensor:
    """(..., 3) rotation vectors -> (..., 3, 3) matrices."""
    return quaternion_to_matrix(axis_angle_to_quaternion(axis_angle))


@_numpy_in_numpy_out
def matrix_to_axis_angle(matrix: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) matrices -> (..., 3) rotation vectors."""
    return quaternion_to_axis_angle(matrix_to_quaternion(matrix))


@_numpy_in_numpy_out
def matrix_to_rot6d(matrix: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) -> (..., 6): the first two rows, flattened row by row."""
    return matrix[..., :2, :].reshape(matrix.shape[:-2] + (6,))


@_numpy_in_numpy_out
def rot6d_to_matrix(rot6d: torch.Tensor) -> torch.Tensor:
    """(..., 6) -> (..., 3, 3) by Gram-Schmidt; any 6 numbers give a valid rotation.

    This is what makes 6D a good network output: it is continuous and never needs a projection
    step that can fail.
    """
    a1, a2 = rot6d[..., :3], rot6d[..., 3:]
    b1 = torch.nn.functional.normalize(a1, dim=-1)
    b2 = torch.nn.functional.normalize(a2 - (b1 * a2).sum(-1, keepdim=True) * b1, dim=-1)
    b3 = torch.cross(b1, b2, dim=-1)
    return torch.stack([b1, b2, b3], dim=-2)


@_numpy_in_numpy_out
def quaternion_multiply(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product a * b (apply b, then a), broadcasting over leading dims."""
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        dim=-1,
    )


@_numpy_in_numpy_out
def quaternion_conjugate(q: torch.Tensor) -> torch.Tensor:
    """Inverse of a unit quaternion."""
    return torch.cat([q[..., :1], -q[..., 1:]], dim=-1)


@_numpy_in_numpy_out
def quaternion_slerp(a: torch.Tensor, b: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
    """Spherical interpolation from a (t=0) to b (t=1) along the shorter arc.

    ``t`` broadcasts against the quaternions' leading dims (shape (...,) or (..., 1)).
    """
    t = torch.as_tensor(t, dtype=a.dtype)
    if t.ndim == a.ndim - 1:
        t = t[..., None]
    dot = (a * b).sum(-1, keepdim=True)
    b = torch.where(dot < 0, -b, b)
    dot = dot.abs().clamp(max=1.0)
    theta = torch.acos(dot)
    sin_theta = torch.sin(theta)
    near = sin_theta < 1e-6
    safe = torch.where(near, torch.ones_like(sin_theta), sin_theta)
    wa = torch.where(near, 1 - t, torch.sin((1 - t) * theta) / safe)
    wb = torch.where(near, t, torch.sin(t * theta) / safe)
    out = wa * a + wb * b
    return out / torch.linalg.norm(out, dim=-1, keepdim=True)


def _axis_matrix(axis: str, angle: torch.Tensor) -> torch.Tensor:
    c, s = torch.cos(angle), torch.sin(angle)
    one, zero = torch.ones_like(angle), torch.zeros_like(angle)
    rows = {
        "X": [one, zero, zero, zero, c, -s, zero, s, c],
        "Y": [c, zero, s, zero, one, zero, -s, zero, c],
        "Z": [c, -s, zero, s, c, zero, zero, zero, one],
    }[axis]
    return torch.stack(rows, dim=-1).reshape(angle.shape + (3, 3))


@_numpy_in_numpy_out
def elementary_rotation(angle: torch.Tensor, axis: str) -> torch.Tensor:
    """(...,) angles in radians about one of the axes "X", "Y", "Z" -> (..., 3, 3)."""
    return _axis_matrix(axis.upper(), angle)


@_numpy_in_numpy_out
def euler_to_matrix(angles: torch.Tensor, order: str = "ZXY") -> torch.Tensor:
    """(..., 3) intrinsic Euler angles in radians -> (..., 3, 3).

    ``order`` names the axes as BVH lists its channels: for "ZXY" the matrix is Rz @ Rx @ Ry and
    ``angles[..., 0]`` is the Z angle. This is how BVH readers (Blender included) compose them.
    """
    order = order.upper()
    matrix = _axis_matrix(order[0], angles[..., 0])
    for i in (1, 2):
        matrix = matrix @ _axis_matrix(order[i], angles[..., i])
    return matrix


@_numpy_in_numpy_out
def matrix_to_euler(matrix: torch.Tensor, order: str = "ZXY") -> torch.Tensor:
    """Inverse of :func:`euler_to_matrix` for any of the six Tait-Bryan orders (radians)."""
    order = order.upper()
    i, j, k = ("XYZ".index(a) for a in order)
    # Parity of the permutation decides the signs of the off-diagonal terms.
    sign = 1.0 if (j - i) % 3 == 1 else -1.0
    middle = torch.asin((sign * matrix[..., i, k]).clamp(-1.0, 1.0))
    first = torch.atan2(-sign * matrix[..., j, k], matrix[..., k, k])
    last = torch.atan2(-sign * matrix[..., i, j], matrix[..., i, i])
    # Gimbal lock (|middle| = 90 deg): put the whole remaining rotation into the first angle.
    locked = (sign * matrix[..., i, k]).abs() > 1 - 1e-9
    if locked.any():
        alt_first = torch.atan2(sign * matrix[..., k, j], matrix[..., j, j])
        first = torch.where(locked, alt_first, first)
        last = torch.where(locked, torch.zeros_like(last), last)
    return torch.stack([first, middle, last], dim=-1)
