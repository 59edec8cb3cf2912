"""Fitting the Anny head to tracked face landmarks: pure functions on arrays.

The model of one frame, for L landmark points of the head (their rest positions ``neutral`` and the 52
expression blendshapes ``basis`` at them, :mod:`motion2video.pose.face_anny`):

    points = R @ (neutral + basis . e)              (L, 3) world metres (z up, the face looks along -y)
    pixels = s * A @ points + t                     (L, 2), A = [[1, 0, 0], [0, 0, -1]]

a weak-perspective camera looking along +y (world x -> image x, world z -> image -y), ``R`` the head
rotation, ``s`` pixels per metre, ``t`` (2,) pixels, ``e`` (52,) ARKit coefficients in [0, 1]. The fit
alternates the pose (Gauss-Newton on rotation, scale and shift) and the coefficients (bounded linear least
squares with a small ridge), starting from the previous frame's values.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from motion2video.core.motion import ARKIT_NAMES
from motion2video.core.rotations import axis_angle_to_matrix, matrix_to_axis_angle

GAZE_NAMES = tuple(name for name in ARKIT_NAMES if name.startswith("eyeLook"))
PROJECTION = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # world (x, y, z) -> image (x, y) directions


@dataclass(frozen=True)
class FitConfig:
    """Settings of the per-frame fit.

    Attributes:
        iterations: pose / expression alternations per frame.
        pose_steps: Gauss-Newton steps of the pose per alternation.
        ridge: weight of the squared coefficients, in squared face-size fractions (keeps the shapes the
            landmarks hardly see, e.g. tongueOut or cheekPuff, near 0).
        unfitted: coefficients held at 0: by default the gaze (the 468 landmarks have no iris).
    """

    def active(self) -> np.ndarray:
        """(52,) bool: the coefficients the fit solves for."""
        return np.array([name not in self.unfitted for name in ARKIT_NAMES])

    iterations: int = 2
    pose_steps: int = 2
    ridge: float = 1e-6
    unfitted: tuple[str, ...] = GAZE_NAMES


@dataclass(frozen=True)
class FrameFit:
    """One frame's fit.

    Attributes:
        rotation: (3,) head axis-angle, world axes, radians.
        scale: pixels per metre.
        shift: (2,) pixels.
        expressions: (52,) in [0, 1].
        residual: (L,) distance in pixels of each re-projected landmark from the tracked one.
    """

    rotation: np.ndarray
    scale: float
    shift: np.ndarray
    expressions: np.ndarray
    residual: np.ndarray


def project(points: np.ndarray, rotation: np.ndarray, scale: float, shift: np.ndarray) -> np.ndarray:
    """(..., L, 2) pixels of (..., L, 3) head points under a (3,) axis-angle rotation and the weak-perspective
    camera (``scale`` pixels per metre, (2,) ``shift``)."""
    R = axis_angle_to_matrix(np.asarray(rotation, np.float64))
    return scale * (np.asarray(points) @ R.T) @ PROJECTION.T + shift


def initial_pose(model: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """A closed-form pose: the affine camera fitted by least squares, its rows made orthonormal.

    Args:
        model: (L, 3) head points, metres.
        xy: (L, 2) pixels.
    Returns:
        (3,) axis-angle, scale, (2,) shift.
    """
    pm, qm = model.mean(axis=0), xy.mean(axis=0)
    P, Q = model - pm, xy - qm
    K = np.linalg.lstsq(P, Q, rcond=None)[0].T  # (2, 3) affine camera
    K = np.linalg.inv(PROJECTION[:, [0, 2]]) @ K  # rows: world x and z directions, scaled
    scale = 0.5 * (np.linalg.norm(K[0]) + np.linalg.norm(K[1]))
    u, _, vt = np.linalg.svd(K, full_matrices=False)
    rows = u @ vt  # (2, 3) nearest orthonormal rows
    R = np.stack([rows[0], np.cross(rows[1], rows[0]), rows[1]])  # x, y = z cross x, z
    if np.linalg.det(R) < 0:
        R[1] *= -1
    rotation = matrix_to_axis_angle(R)
    shift = qm - scale * (PROJECTION @ (R @ pm))
    return rotation, float(scale), shift


def _skew(v: np.ndarray) -> np.ndarray:
    """(L, 3, 3) cross-product matrices of (L, 3) vectors."""
    z = np.zeros(len(v))
    return np.stack([np.stack([z, -v[:, 2], v[:, 1]], -1), np.stack([v[:, 2], z, -v[:, 0]], -1),
                     np.stack([-v[:, 1], v[:, 0], z], -1)], axis=1)


def refine_pose(model: np.ndarray, xy: np.ndarray, rotation: np.ndarray, scale: float, shift: np.ndarray,
                steps: int = 3, weights: np.ndarray | None = None) -> tuple[np.ndarray, float, np.ndarray]:
    """Gauss-Newton steps on the 2D re-projection error over (rotation increment, log scale, shift).

    Args:
        model: (L, 3) head points; xy: (L, 2) pixels; weights: (L,) per-landmark weights (None: ones).
    Returns:
        (3,) axis-angle, scale, (2,) shift.
    """
    w = np.ones(len(xy)) if weights is None else np.asarray(weights, np.float64)
    sw = np.sqrt(np.repeat(w, 2))
    R = axis_angle_to_matrix(np.asarray(rotation, np.float64))
    for _ in range(steps):
        X = model @ R.T  # (L, 3) rotated points
        pred = scale * X @ PROJECTION.T + shift
        r = (xy - pred).reshape(-1)  # (2L,)
        # d pred / d omega (a small world rotation exp([omega]) R): -s A [X]x
        j_rot = -scale * np.einsum("ij,ljk->lik", PROJECTION, _skew(X))  # (L, 2, 3)
        j_scale = (scale * X @ PROJECTION.T)[:, :, None]  # (L, 2, 1), d / d log s
        j_shift = np.broadcast_to(np.eye(2), (len(xy), 2, 2))
        J = np.concatenate([j_rot, j_scale, j_shift], axis=2).reshape(-1, 6)  # (2L, 6)
        delta = np.linalg.lstsq(J * sw[:, None], r * sw, rcond=None)[0]
        R = axis_angle_to_matrix(delta[:3]) @ R
        scale *= float(np.exp(delta[3]))
        shift = shift + delta[4:]
    return matrix_to_axis_angle(R), float(scale), np.asarray(shift, np.float64)


def fit_expressions(neutral: np.ndarray, basis: np.ndarray, xy: np.ndarray, rotation: np.ndarray, scale: float,
                    shift: np.ndarray, ridge: float, size: float, weights: np.ndarray | None = None,
                    active: np.ndarray | None = None) -> np.ndarray:
    """The 52 coefficients in [0, 1] that best explain the landmarks under a fixed pose.

    Args:
        neutral: (L, 3); basis: (52, L, 3) deltas at weight 1; xy: (L, 2) pixels.
        ridge: squared-coefficient weight relative to a residual of one face size (``size`` pixels).
        weights: (L,) per-landmark weights (None: ones).
        active: (52,) bool, the coefficients solved for (the others stay 0); None: all.
    Returns:
        (52,) coefficients.
    """
    active = np.ones(len(basis), bool) if active is None else np.asarray(active, bool)
    out = np.zeros(len(basis))
    if not active.any():
        return out
    basis = basis[active]
    w = np.ones(len(xy)) if weights is None else np.asarray(weights, np.float64)
    sw = np.sqrt(np.repeat(w, 2))[:, None]
    R = axis_angle_to_matrix(np.asarray(rotation, np.float64))
    M = scale * PROJECTION @ R  # (2, 3)
    A = np.einsum("ij,klj->lik", M, basis).reshape(-1, len(basis))  # (2L, 52)
    b = (xy - neutral @ M.T - shift).reshape(-1)  # (2L,)
    lam = np.sqrt(ridge * len(xy)) * size
    A = np.concatenate([A * sw, lam * np.eye(len(basis))])
    b = np.concatenate([b * sw[:, 0], np.zeros(len(basis))])
    out[active] = lsq_linear(A, b, bounds=(0.0, 1.0), method="bvls").x
    return out


def fit_frame(neutral: np.ndarray, basis: np.ndarray, xy: np.ndarray, config: FitConfig = FitConfig(),
              start: FrameFit | None = None, weights: np.ndarray | None = None) -> FrameFit:
    """Fit head pose and expression to one frame's landmarks.

    Args:
        neutral: (L, 3) rest positions of the landmark points, metres.
        basis: (52, L, 3) expression deltas.
        xy: (L, 2) tracked landmarks, pixels.
        start: the previous frame's fit (its pose and coefficients start this one), or None.
        weights: (L,) per-landmark weights.
    """
    size = float(np.max(xy.max(axis=0) - xy.min(axis=0)))
    active = config.active()
    if start is None:
        e = np.zeros(len(basis))
        rotation, scale, shift = initial_pose(neutral, xy)
    else:
        e, rotation, scale, shift = start.expressions, start.rotation, start.scale, start.shift
    for _ in range(config.iterations):
        model = neutral + np.tensordot(e, basis, axes=1)  # (L, 3)
        rotation, scale, shift = refine_pose(model, xy, rotation, scale, shift, config.pose_steps, weights)
        e = fit_expressions(neutral, basis, xy, rotation, scale, shift, config.ridge, size, weights, active)
    model = neutral + np.tensordot(e, basis, axes=1)
    residual = np.linalg.norm(project(model, rotation, scale, shift) - xy, axis=1)
    return FrameFit(rotation, scale, shift, e, residual)


def person_neutral_offsets(neutral: np.ndarray, xy: np.ndarray, fits: list[FrameFit]) -> np.ndarray:
    """The person's own face as offsets from the model's landmark points: each frame's residual of a pose-only
    fit taken back into the head's frame (the least-norm 3D offset that projects onto it), and the median over
    the frames, so that the coefficients then fitted describe expressions, not the person's face shape.

    Args:
        neutral: (L, 3) the model's points; xy: (T, L, 2) tracked landmarks; fits: T pose-only fits.
    Returns:
        (L, 3) offsets in the head's rest frame, metres.
    """
    offsets = []
    for frame, fit in zip(xy, fits):
        M = fit.scale * PROJECTION @ axis_angle_to_matrix(fit.rotation)  # (2, 3)
        residual = frame - project(neutral, fit.rotation, fit.scale, fit.shift)  # (L, 2)
        offsets.append(residual @ np.linalg.pinv(M).T)  # (L, 3)
    return np.median(np.stack(offsets), axis=0)
