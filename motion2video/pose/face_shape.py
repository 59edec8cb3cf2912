"""A person's own face on Anny's head: offsets of the tracked points from the fitted head's, spread over the head's
vertices, fixed for every frame the person is drawn in.

- :func:`fit_offsets`: one picture's residual after the pose and expression fit (:func:`.face_fit.fit_frame`),
  each point's least-norm 3D offset that projects onto it (so no depth: the template's is kept), in the head's
  rest frame. A face video's counterpart is :func:`.face_fit.person_neutral_offsets` (the median residual of
  pose-only fits).
- :func:`spread_offsets`: the offsets of the 468 mesh points carried to every vertex by a Gaussian radial basis
  (:data:`SHAPE_SIGMA_M` wide, ridge :data:`SHAPE_RIDGE`): smooth over the face, fading to none a few centimetres
  beyond its outline (ears, skull, neck keep Anny's shape).
- :func:`head_shape`: both on Anny's rest mesh: the (V, 3) offsets the face renderer adds to the posed head
  (:meth:`renderers.face.FaceRenderer.render_with_masks`, ``shape``).
"""

from __future__ import annotations

import numpy as np

from motion2video.core.rotations import axis_angle_to_matrix
from motion2video.pose.face_fit import PROJECTION, FrameFit, project
from motion2video.pose.facemesh import NUM_LANDMARKS

SHAPE_SIGMA_M = 0.012  # the Gaussian's standard deviation, metres on the head at rest (the points are ~7 mm apart)
SHAPE_RIDGE = 0.05  # added to the kernel's diagonal: the offsets are smoothed, not matched point for point


def fit_offsets(points: np.ndarray, xy: np.ndarray, fit: FrameFit) -> np.ndarray:
    """(L, 3) offsets, metres in the head's rest frame, that take the fitted head's points onto the picture's.

    Args:
        points: (L, 3) the head's points with the fitted expression (neutral + basis . e, rest frame).
        xy: (L, 2) the picture's points, pixels; fit: the weak-perspective fit to them.
    """
    M = fit.scale * PROJECTION @ axis_angle_to_matrix(fit.rotation)  # (2, 3)
    residual = np.asarray(xy, np.float64) - project(points, fit.rotation, fit.scale, fit.shift)
    return residual @ np.linalg.pinv(M).T


def spread_offsets(points: np.ndarray, offsets: np.ndarray, vertices: np.ndarray, *,
                   sigma: float = SHAPE_SIGMA_M, ridge: float = SHAPE_RIDGE) -> np.ndarray:
    """(V, 3) offsets at ``vertices`` (V, 3) interpolating ``offsets`` (L, 3) given at ``points`` (L, 3): a sum of
    Gaussians exp(-d^2 / 2 sigma^2) centred on the points, weighted to match the offsets up to the ridge."""
    p = np.asarray(points, np.float64)

    def kernel(a: np.ndarray) -> np.ndarray:
        d2 = np.sum(a * a, axis=1)[:, None] + np.sum(p * p, axis=1)[None] - 2.0 * a @ p.T
        return np.exp(-np.maximum(d2, 0.0) / (2.0 * sigma * sigma))

    weights = np.linalg.solve(kernel(p) + ridge * np.eye(len(p)), np.asarray(offsets, np.float64))  # (L, 3)
    out = np.zeros((len(vertices), 3))
    for start in range(0, len(vertices), 4096):  # (4096, L) kernels at a time
        out[start:start + 4096] = kernel(np.asarray(vertices[start:start + 4096], np.float64)) @ weights
    return out


def head_shape(offsets: np.ndarray, phenotype: dict[str, float] | None = None) -> np.ndarray:
    """(V, 3) float32 offsets of all of Anny's vertices (rest frame, metres) from (470, 3) offsets at the tracked
    points (the two iris centres left out: the eyeballs follow the lids around them)."""
    from motion2video.pose.face_anny import load_correspondence
    from renderers import anny_model

    rest = anny_model.anny_rest(phenotype).vertices
    points = load_correspondence().points(rest)[:NUM_LANDMARKS]
    return spread_offsets(points, np.asarray(offsets)[:NUM_LANDMARKS], rest).astype(np.float32)
