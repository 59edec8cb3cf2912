"""Rotations, the one place for them: pure numpy, batched over leading axes, float64.

Matrices act on column vectors (``R @ v``); quaternions are (w, x, y, z); axis-angle vectors are axis * angle in
radians. World frame: metres, right-handed, z up; the body faces -y at heading 0.
"""

from __future__ import annotations

import numpy as np

from motion2video.core.skeletons import L_HIP, R_HIP


def _normalize(v: np.ndarray, eps: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors along the last axis and a mask of which inputs were long enough."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    ok = n[..., 0] > eps
    return v / np.maximum(n, eps), ok


def swing_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotation taking direction ``a`` to direction ``b``.

    Args:
        a, b: (..., 3) directions (any length; a zero-length one gives the identity).
    Returns:
        (..., 3, 3) rotation matrices R with R @ a_hat = b_hat.
    """
    a_hat, ok_a = _normalize(np.asarray(a, np.float64))
    b_hat, ok_b = _normalize(np.asarray(b, np.float64))
    v = np.cross(a_hat, b_hat)  # (..., 3) axis * sin
    c = np.sum(a_hat * b_hat, axis=-1)  # (...,) cos
    shape = c.shape
    eye = np.broadcast_to(np.eye(3), shape + (3, 3))
    vx = np.zeros(shape + (3, 3))
    vx[..., 0, 1], vx[..., 0, 2] = -v[..., 2], v[..., 1]
    vx[..., 1, 0], vx[..., 1, 2] = v[..., 2], -v[..., 0]
    vx[..., 2, 0], vx[..., 2, 1] = -v[..., 1], v[..., 0]
    k = 1.0 / np.maximum(1.0 + c, 1e-12)
    rot = eye + vx + (vx @ vx) * k[..., None, None]
    # Opposite directions: half a turn about any axis perpendicular to a.
    opposite = c < -1.0 + 1e-9
    if np.any(opposite):
        helper = np.where(np.abs(a_hat[..., :1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
        axis, _ = _normalize(np.cross(a_hat, helper))
        half_turn = 2.0 * axis[..., :, None] * axis[..., None, :] - eye
        rot = np.where(opposite[..., None, None], half_turn, rot)
    return np.where((ok_a & ok_b)[..., None, None], rot, eye)


def frame_from_axes(x: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Right-handed orthonormal frame with first axis along ``x`` and third axis as close to ``up`` as
    possible (Gram-Schmidt).

    Args:
        x, up: (..., 3) vectors.
    Returns:
        (..., 3, 3) rotation whose columns are the frame's x, y = z cross x, z axes.
    """
    x_hat, _ = _normalize(np.asarray(x, np.float64))
    up = np.asarray(up, np.float64)
    z = up - np.sum(up * x_hat, axis=-1, keepdims=True) * x_hat
    z_hat, ok = _normalize(z)
    # Degenerate (up parallel to x): any z perpendicular to x.
    fallback, _ = _normalize(np.cross(x_hat, np.array([0.0, 1.0, 0.0])) + 1e-6 * np.array([0.0, 0.0, 1.0]))
    z_hat = np.where(ok[..., None], z_hat, fallback)
    y_hat = np.cross(z_hat, x_hat)
    return np.stack([x_hat, y_hat, z_hat], axis=-1)


def quaternion_from_matrix(rot: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations -> (..., 4) unit quaternions (w, x, y, z) with w >= 0."""
    m = np.asarray(rot, np.float64)
    trace = m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2]
    candidates = np.stack([
        np.stack([1.0 + trace, m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0],
                  m[..., 1, 0] - m[..., 0, 1]], -1),
        np.stack([m[..., 2, 1] - m[..., 1, 2], 1.0 + m[..., 0, 0] - m[..., 1, 1] - m[..., 2, 2],
                  m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0]], -1),
        np.stack([m[..., 0, 2] - m[..., 2, 0], m[..., 0, 1] + m[..., 1, 0],
                  1.0 - m[..., 0, 0] + m[..., 1, 1] - m[..., 2, 2], m[..., 1, 2] + m[..., 2, 1]], -1),
        np.stack([m[..., 1, 0] - m[..., 0, 1], m[..., 0, 2] + m[..., 2, 0], m[..., 1, 2] + m[..., 2, 1],
                  1.0 - m[..., 0, 0] - m[..., 1, 1] + m[..., 2, 2]], -1),
    ], axis=-2)  # (..., 4 candidates, 4); candidate i is 4 q_i q, best conditioned for the largest q_i
    diag = np.stack([trace, m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]], -1)  # (..., 4)
    best = np.argmax(diag, axis=-1)
    q = np.take_along_axis(candidates, best[..., None, None], axis=-2)[..., 0, :]  # (..., 4)
    q, _ = _normalize(q)
    return np.where(q[..., :1] < 0, -q, q)


def matrix_from_quaternion(q: np.ndarray) -> np.ndarray:
    """(..., 4) quaternions (w, x, y, z) -> (..., 3, 3) rotations."""
    q, _ = _normalize(np.asarray(q, np.float64))
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def slerp_rotations(a: np.ndarray, b: np.ndarray, weight: np.ndarray | float) -> np.ndarray:
    """Rotation a fraction ``weight`` of the way from ``a`` to ``b`` (along the shortest path).

    Args:
        a, b: (..., 3, 3) rotations.
        weight: (...) or scalar in [0, 1].
    Returns:
        (..., 3, 3) rotations: ``a`` at weight 0, ``b`` at weight 1.
    """
    rel = quaternion_from_matrix(b @ np.swapaxes(a, -1, -2))  # (..., 4), w >= 0
    half = np.arctan2(np.linalg.norm(rel[..., 1:], axis=-1), rel[..., 0])  # (...) half angle
    axis, _ = _normalize(rel[..., 1:])
    new_half = np.asarray(weight, np.float64) * half
    q = np.concatenate([np.cos(new_half)[..., None], np.sin(new_half)[..., None] * axis], axis=-1)
    return matrix_from_quaternion(q) @ a


def axis_angle_to_matrix(rotvec: np.ndarray) -> np.ndarray:
    """(..., 3) axis-angle vectors (radians) -> (..., 3, 3) rotations."""
    rotvec = np.asarray(rotvec, np.float64)
    angle = np.linalg.norm(rotvec, axis=-1)
    axis, _ = _normalize(rotvec)
    q = np.concatenate([np.cos(angle / 2)[..., None], np.sin(angle / 2)[..., None] * axis], axis=-1)
    return matrix_from_quaternion(q)


def head_euler_to_matrix(euler: np.ndarray) -> np.ndarray:
    """Head rotation matrices ``Rz(yaw) @ Rx(pitch) @ Ry(roll)``.

    Args:
        euler: (..., 3) yaw, pitch, roll in radians (yaw about +z, pitch about +x, roll about +y).
    Returns:
        (..., 3, 3) rotation matrices.
    """
    e = np.asarray(euler, dtype=np.float64)
    cy, sy = np.cos(e[..., 0]), np.sin(e[..., 0])
    cp, sp = np.cos(e[..., 1]), np.sin(e[..., 1])
    cr, sr = np.cos(e[..., 2]), np.sin(e[..., 2])
    zeros, ones = np.zeros_like(cy), np.ones_like(cy)
    rz = np.stack([cy, -sy, zeros, sy, cy, zeros, zeros, zeros, ones], axis=-1).reshape(e.shape[:-1] + (3, 3))
    rx = np.stack([ones, zeros, zeros, zeros, cp, -sp, zeros, sp, cp], axis=-1).reshape(e.shape[:-1] + (3, 3))
    ry = np.stack([cr, zeros, sr, zeros, ones, zeros, -sr, zeros, cr], axis=-1).reshape(e.shape[:-1] + (3, 3))
    return rz @ rx @ ry


def matrix_to_axis_angle(rot: np.ndarray) -> np.ndarray:
    """Axis-angle vectors (axis * angle, angle in [0, pi]) of rotation matrices.

    Args:
        rot: (..., 3, 3) rotation matrices.
    Returns:
        (..., 3) axis-angle vectors.
    """
    r = np.asarray(rot, dtype=np.float64)
    cos = np.clip((np.trace(r, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(cos)  # (...,)
    skew = np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]], axis=-1)
    sin = np.sin(angle)
    # Away from 0 and pi: axis = skew / (2 sin). Near 0: axis * angle ~ skew / 2.
    small = sin < 1e-6
    scale = np.where(small, 0.5, angle / np.where(small, 1.0, 2.0 * sin))
    out = skew * scale[..., None]
    # Near pi the skew part vanishes: take the axis from the diagonal of (R + I) / 2 = a a^T.
    near_pi = (angle > np.pi - 1e-3)
    if np.any(near_pi):
        rp = r[near_pi]
        aat = (rp + np.eye(3)) / 2.0
        col = np.argmax(np.diagonal(aat, axis1=-2, axis2=-1), axis=-1)
        axis = aat[np.arange(rp.shape[0]), :, col]
        axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
        out[near_pi] = axis * angle[near_pi][..., None]
    return out


def head_euler_to_axis_angle(euler: np.ndarray) -> np.ndarray:
    """(..., 3) yaw, pitch, roll -> (..., 3) axis-angle of ``Rz(yaw) @ Rx(pitch) @ Ry(roll)``."""
    return matrix_to_axis_angle(head_euler_to_matrix(euler))


def rotation_z(angle: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices about +z for angles (...,) in radians."""
    angle = np.asarray(angle, np.float64)
    c, s = np.cos(angle), np.sin(angle)
    zero, one = np.zeros_like(angle), np.ones_like(angle)
    return np.stack([np.stack([c, -s, zero], -1), np.stack([s, c, zero], -1), np.stack([zero, zero, one], -1)], -2)


def euler_to_matrix(euler: np.ndarray) -> np.ndarray:
    """Rotation matrices from (pitch, roll, yaw) Euler angles: ``Rz(yaw) @ Ry(roll) @ Rx(pitch)``.

    Args:
        euler: (..., 3) radians, rotations about x, y, z.
    Returns:
        (..., 3, 3) rotation matrices.
    """
    e = np.asarray(euler, dtype=np.float64)
    cx, cy, cz = np.cos(e[..., 0]), np.cos(e[..., 1]), np.cos(e[..., 2])
    sx, sy, sz = np.sin(e[..., 0]), np.sin(e[..., 1]), np.sin(e[..., 2])
    r = np.empty(e.shape[:-1] + (3, 3))
    r[..., 0, 0] = cz * cy
    r[..., 0, 1] = cz * sy * sx - sz * cx
    r[..., 0, 2] = cz * sy * cx + sz * sx
    r[..., 1, 0] = sz * cy
    r[..., 1, 1] = sz * sy * sx + cz * cx
    r[..., 1, 2] = sz * sy * cx - cz * sx
    r[..., 2, 0] = -sy
    r[..., 2, 1] = cy * sx
    r[..., 2, 2] = cy * cx
    return r


def heading_of(joints: np.ndarray) -> np.ndarray:
    """Facing angle about +z from the hip line: 0 when facing -y, positive when turned to the body's left.

    Args:
        joints: (..., 17, 3) H36M-17 joints.
    Returns:
        (...,) radians in (-pi, pi].
    """
    hips = joints[..., L_HIP, :2] - joints[..., R_HIP, :2]  # (..., 2) points to the body's left
    return np.arctan2(hips[..., 1], hips[..., 0])
