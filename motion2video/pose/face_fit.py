"""Fitting the Anny head to tracked face landmarks: pure functions on arrays.

The model of one frame, for L landmark points of the head (their rest positions ``neutral`` and the 52
expression blendshapes ``basis`` at them, :mod:`motion2video.pose.face_anny`):

    points = R @ (neutral + basis . e)              (L, 3) world metres (z up, the face looks along -y)
    pixels = s * A @ points + t                     (L, 2), A = [[1, 0, 0], [0, 0, -1]]

a weak-perspective camera looking along +y (world x -> image x, world z -> image -y), ``R`` the head
rotation, ``s`` pixels per metre, ``t`` (2,) pixels, ``e`` (52,) ARKit coefficients in [0, 1]. The fit
solves for the pose (rotation, scale, shift) and the coefficients together by Gauss-Newton, each step a
bounded linear least squares with a small ridge on the coefficients, starting from the previous frame's
values.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from motion2video.core.motion import ARKIT_NAMES
from motion2video.core.rotations import axis_angle_to_matrix, matrix_to_axis_angle
from motion2video.pose.facemesh import EYE_CONTOUR_IN_MESH, NUM_LANDMARKS, NUM_POINTS

PROJECTION = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # world (x, y, z) -> image (x, y) directions


@dataclass(frozen=True)
class FitConfig:
    """Settings of the per-frame fit.

    Attributes:
        iterations: Gauss-Newton steps per frame started from the previous frame's fit (one is enough at video
            rates: a second changed the median re-projection error by under 0.01% of the face size).
        first_iterations: Gauss-Newton steps when nothing starts the fit.
        ridge: weight of the squared coefficients, in squared face-size fractions (keeps the shapes the
            landmarks hardly see, e.g. tongueOut or cheekPuff, near 0).
        unfitted: coefficients held at 0: by default tongueOut, which no tracked point lies on (fitted, it took
            up to 0.56 on a broad smile of face_talking_man_glasses, through the lips it also moves).
        eyelid_weight: weight of the 32 eyelid landmarks (the others weigh 1): the eyelids carry the blinks,
            and the tracked lids close by less than the model's on a blink (on face_talking_woman frames 36-58 the
            fitted eyeBlink peaks rose from 0.24 / 0.19 to 0.33 / 0.36, the median error from 0.33% to 0.37%).
        eye_halo_weight: weight of the 64 landmarks in the two rings around each eye, whose skin folds move less
            in the video than in Anny's eyeBlink.
        iris_weight: weight of the two iris centres, which alone carry the gaze (eyeLook*) against 468 others.
    """

    def weights(self) -> np.ndarray:
        """(470,) per-point weights of the tracked points (the mesh's 468, then the two iris centres)."""
        w = np.ones(NUM_POINTS)
        for contour in EYE_CONTOUR_IN_MESH:
            w[list(contour[:16])] = self.eyelid_weight
            w[list(contour[16:48])] = self.eye_halo_weight
        w[NUM_LANDMARKS:] = self.iris_weight
        return w

    def active(self) -> np.ndarray:
        """(52,) bool: the coefficients the fit solves for."""
        return np.array([name not in self.unfitted for name in ARKIT_NAMES])

    iterations: int = 1
    first_iterations: int = 4
    ridge: float = 1e-6
    unfitted: tuple[str, ...] = ("tongueOut",)
    eyelid_weight: float = 4.0
    eye_halo_weight: float = 0.25
    iris_weight: float = 4.0


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


def _pose_jacobian(X: np.ndarray, scale: float) -> np.ndarray:
    """(L, 2, 6) derivative of the pixels of rotated points X (L, 3) by a small world rotation (3), the log
    scale (1) and the shift (2): ``d(s A exp([w]) X + t)``."""
    j_rot = -scale * np.einsum("ij,ljk->lik", PROJECTION, _skew(X))  # (L, 2, 3)
    j_scale = (scale * X @ PROJECTION.T)[:, :, None]  # (L, 2, 1)
    j_shift = np.broadcast_to(np.eye(2), (len(X), 2, 2))
    return np.concatenate([j_rot, j_scale, j_shift], axis=2)


def fit_frame(neutral: np.ndarray, basis: np.ndarray, xy: np.ndarray, config: FitConfig = FitConfig(),
              start: FrameFit | None = None, weights: np.ndarray | None = None) -> FrameFit:
    """Fit head pose and expression to one frame's landmarks.

    Gauss-Newton on the pose and the coefficients together: each step solves the linearised problem by
    bounded least squares (the coefficients kept in [0, 1], the pose free), with a ridge on the coefficients.

    Args:
        neutral: (L, 3) rest positions of the landmark points, metres.
        basis: (52, L, 3) expression deltas.
        xy: (L, 2) tracked landmarks, pixels.
        config: the fit's settings.
        start: the previous frame's fit (its pose and coefficients start this one), or None (the closed-form
            pose of the neutral head, no expression).
        weights: (L,) per-landmark weights (None: ones).
    """
    size = float(np.max(xy.max(axis=0) - xy.min(axis=0)))
    active = config.active()
    n = int(active.sum())
    sw = np.sqrt(np.repeat(np.ones(len(xy)) if weights is None else np.asarray(weights, np.float64), 2))
    lam = np.sqrt(config.ridge * len(xy)) * size
    if start is None:
        e = np.zeros(len(basis))
        rotation, scale, shift = initial_pose(neutral, xy)
    else:
        e, rotation, scale, shift = start.expressions.copy(), start.rotation, start.scale, np.array(start.shift)
    R = axis_angle_to_matrix(np.asarray(rotation, np.float64))
    for _ in range(config.iterations if start is not None else config.first_iterations):
        X = (neutral + np.tensordot(e, basis, axes=1)) @ R.T  # (L, 3)
        r = (xy - scale * X @ PROJECTION.T - shift).reshape(-1)  # (2L,)
        j_expr = np.einsum("ij,klj->lik", scale * PROJECTION @ R, basis[active]).reshape(len(r), n)  # (2L, n)
        J = np.concatenate([_pose_jacobian(X, scale).reshape(-1, 6), j_expr], axis=1)  # (2L, 6 + n)
        ridge_rows = np.concatenate([np.zeros((n, 6)), lam * np.eye(n)], axis=1)
        A = np.concatenate([J * sw[:, None], ridge_rows])
        b = np.concatenate([r * sw, -lam * e[active]])
        lower = np.concatenate([np.full(6, -np.inf), -e[active]])
        upper = np.concatenate([np.full(6, np.inf), 1.0 - e[active]])
        delta = lsq_linear(A, b, bounds=(lower, upper), method="bvls").x if n else \
            np.linalg.lstsq(A, b, rcond=None)[0]
        R = axis_angle_to_matrix(delta[:3]) @ R
        scale *= float(np.exp(delta[3]))
        shift = shift + delta[4:6]
        e[active] = np.clip(e[active] + delta[6:], 0.0, 1.0)
    rotation = matrix_to_axis_angle(R)
    model = neutral + np.tensordot(e, basis, axes=1)
    residual = np.linalg.norm(project(model, rotation, scale, shift) - xy, axis=1)
    return FrameFit(rotation, float(scale), np.asarray(shift, np.float64), e, residual)


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
