"""Rotations for compare.py: rotation vectors, matrices, quaternions and Euler angles (numpy),
written from their formulas for the PlaCo comparison (no code shared with Stance)."""

from __future__ import annotations

import math

import numpy as np

# --------------------------------------------------------------------------------------------
# Rotations
# --------------------------------------------------------------------------------------------


def skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotvec_to_matrix(r) -> np.ndarray:
    """exp(r): the rotation of angle |r| about r / |r| (Rodrigues)."""
    r = np.asarray(r, dtype=float)
    angle = float(np.linalg.norm(r))
    if angle < 1e-12:
        return np.eye(3) + skew(r)
    k = skew(r / angle)
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def axis_rotation(axis: int, angle: float) -> np.ndarray:
    r = np.zeros(3)
    r[axis] = angle
    return rotvec_to_matrix(r)


def rotation_angle(m: np.ndarray) -> float:
    """The angle of the rotation matrix m, in [0, pi] (the norm of its logarithm)."""
    # atan2 of the axis part and the trace part is accurate near 0 and pi alike.
    s = 0.5 * np.linalg.norm([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])
    c = 0.5 * (np.trace(m) - 1.0)
    return math.atan2(s, c)


def matrix_to_rotvec(m: np.ndarray) -> np.ndarray:
    """The rotation vector (angle in [0, pi]) of the rotation matrix m: log(m)."""
    angle = rotation_angle(m)
    vee = 0.5 * np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])
    if angle < 1e-12:
        return vee
    if angle < math.pi - 1e-6:
        return vee * (angle / math.sin(angle))
    # Near pi: the axis from the symmetric part (m + I) / 2 = k k^T, signed by vee.
    b = 0.5 * (m + np.eye(3))
    col = int(np.argmax(np.diag(b)))
    k = b[:, col] / math.sqrt(b[col, col])
    if np.dot(k, vee) < 0:
        k = -k
    return k * angle


def quaternion_to_rotvec(q) -> np.ndarray:
    """[qx, qy, qz, qw] to the rotation vector (angle in [0, pi])."""
    q = np.asarray(q, dtype=float) / np.linalg.norm(q)
    if q[3] < 0:
        q = -q
    s = float(np.linalg.norm(q[:3]))
    if s < 1e-12:
        return 2.0 * q[:3]
    return q[:3] / s * (2.0 * math.atan2(s, q[3]))


def quaternion_to_matrix(q) -> np.ndarray:
    """[qx, qy, qz, qw] (normalised here) to a rotation matrix."""
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def rotvec_to_quaternion(r) -> np.ndarray:
    """exp(r) as [qx, qy, qz, qw]."""
    r = np.asarray(r, dtype=float)
    angle = float(np.linalg.norm(r))
    if angle < 1e-12:
        return np.array([r[0] / 2, r[1] / 2, r[2] / 2, 1.0])
    return np.append(r / angle * math.sin(angle / 2), math.cos(angle / 2))


def is_cyclic(order) -> bool:
    return tuple(order) in ((0, 1, 2), (1, 2, 0), (2, 0, 1))


def euler_angles(m: np.ndarray, order) -> np.ndarray:
    """Angles (a, b, c) with m = R_i(a) R_j(b) R_k(c) for order = (i, j, k), b in [-pi/2, pi/2].

    Works on one matrix (3x3) or a stack of them (..., 3, 3).
    """
    i, j, k = order
    s = 1.0 if is_cyclic(order) else -1.0
    b = np.arcsin(np.clip(s * m[..., i, k], -1.0, 1.0))
    a = np.arctan2(-s * m[..., j, k], m[..., k, k])
    c = np.arctan2(-s * m[..., i, j], m[..., i, i])
    return np.stack([a, b, c], axis=-1)
