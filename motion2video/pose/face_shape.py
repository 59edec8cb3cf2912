"""A person's face shape on Anny's head: MakeHuman's local face targets fitted to the tracked landmarks, as a 3D
morphable model's identity coefficients are fitted.

Anny carries MakeHuman's (MPFB2, CC0) local targets as blend shapes: where the eyes, brows, nose, mouth and chin
sit and how large they are, the cheeks. :data:`SHAPE_PAIRS` names the 27 pairs of opposite targets kept here
(``pose/data/face_shape_targets.npz``, built by ``scripts/make_face_correspondence.py --shapes``); the left and right
targets of an eye or a cheek are summed, so the fitted face is symmetric. Each target is a
coefficient in [0, 1] (1: MakeHuman's full change), fitted by bounded least squares with a ridge, the head's pose
and expression held (:func:`fit_shape`), alternating with their fit for a picture
(:func:`motion2video.pose.face_portrait.fit_portrait`); for a video, fitted to the tracker's person offsets
(:func:`fit_shape_to_offsets`). :func:`head_shape` turns the coefficients into the (V, 3) offsets the face renderer
adds to the posed head (:meth:`renderers.face.FaceRenderer.render_with_masks`, ``shape``).

Why targets and not the points' own residual: the residual spread over the head as a smooth offset field brought
the landmarks within 0.2-0.3% of the face size, but a cheek bulged as the head turned and the talking-head protocol
got worse (docs/experiments.md). The targets are whole, artist-made changes of a face: they cannot bulge, and they
give the depth the picture does not show as a face of that build has it. The head's own targets (its width, height,
fullness and place) are left out: they move the head's outline, which a real head's hair and ears do not follow, and
with them the talking-head protocol's face PSNR fell by 0.3 dB on ``face_talking_woman.mp4`` (24.69 -> 24.39).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from scipy.optimize import lsq_linear

from motion2video.pose.face_fit import PROJECTION, FrameFit
from motion2video.pose.facemesh import NUM_POINTS

SHAPE_FILE = Path(__file__).resolve().parent / "data" / "face_shape_targets.npz"

# (increase, decrease) MakeHuman target names; a leading "*" sums the "l-" and "r-" targets of that name
SHAPE_PAIRS: tuple[tuple[str, str], ...] = (
    ("eyebrows-trans-up", "eyebrows-trans-down"), ("eyebrows-angle-up", "eyebrows-angle-down"),
    ("*eye-trans-up", "*eye-trans-down"), ("*eye-trans-out", "*eye-trans-in"), ("*eye-scale-incr", "*eye-scale-decr"),
    ("*eye-height2-incr", "*eye-height2-decr"), ("*eye-corner1-up", "*eye-corner1-down"),
    ("*eye-corner2-up", "*eye-corner2-down"),
    ("nose-scale-horiz-incr", "nose-scale-horiz-decr"), ("nose-scale-vert-incr", "nose-scale-vert-decr"),
    ("nose-trans-up", "nose-trans-down"), ("nose-point-width-incr", "nose-point-width-decr"),
    ("nose-nostrils-width-incr", "nose-nostrils-width-decr"), ("nose-width1-incr", "nose-width1-decr"),
    ("mouth-scale-horiz-incr", "mouth-scale-horiz-decr"), ("mouth-scale-vert-incr", "mouth-scale-vert-decr"),
    ("mouth-trans-up", "mouth-trans-down"), ("mouth-upperlip-height-incr", "mouth-upperlip-height-decr"),
    ("mouth-lowerlip-height-incr", "mouth-lowerlip-height-decr"),
    ("mouth-upperlip-width-incr", "mouth-upperlip-width-decr"),
    ("mouth-lowerlip-width-incr", "mouth-lowerlip-width-decr"),
    ("mouth-cupidsbow-width-incr", "mouth-cupidsbow-width-decr"),
    ("chin-height-incr", "chin-height-decr"), ("chin-width-incr", "chin-width-decr"),
    ("*cheek-bones-incr", "*cheek-bones-decr"), ("*cheek-volume-incr", "*cheek-volume-decr"),
    ("*cheek-trans-up", "*cheek-trans-down"),
)
# The coefficients' ridge, in squared face-size fractions per point as :class:`.face_fit.FitConfig`'s ridge.
SHAPE_RIDGE = 1e-4


def target_names() -> tuple[str, ...]:
    """The K = 54 coefficients' names, in the order of :func:`shape_targets` (each pair's increase first)."""
    return tuple(name.lstrip("*") for pair in SHAPE_PAIRS for name in pair)


@dataclass(frozen=True)
class ShapeTargets:
    """The face targets on Anny's mesh and at the tracked points.

    Attributes:
        names: K target names (:func:`target_names`).
        shapes: (K, V, 3) float32 displacement of every Anny vertex at coefficient 1, metres, rest frame.
        points: (K, 470, 3) float64 the same at the tracked points (:mod:`motion2video.pose.face_anny`).
    """

    names: tuple[str, ...]
    shapes: np.ndarray
    points: np.ndarray


@lru_cache(maxsize=1)
def shape_targets(path: str | Path = SHAPE_FILE) -> ShapeTargets:
    """The shipped targets (see the module docstring)."""
    from motion2video.pose.face_anny import load_correspondence

    with np.load(path, allow_pickle=False) as data:
        names = tuple(str(n) for n in data["names"])
        shapes = data["shapes"].astype(np.float32)
    if names != target_names():
        raise ValueError(f"{path}: its targets are not SHAPE_PAIRS'; rebuild it")
    return ShapeTargets(names, shapes, load_correspondence().points(shapes.astype(np.float64)))


def head_shape(coefficients: np.ndarray | None) -> np.ndarray | None:
    """(V, 3) float32 offsets of Anny's vertices (rest frame, metres) for (K,) coefficients; None for None."""
    if coefficients is None:
        return None
    coefficients = np.asarray(coefficients, np.float64)
    return np.tensordot(coefficients, shape_targets().shapes, axes=1).astype(np.float32)


def shape_points(coefficients: np.ndarray | None) -> np.ndarray:
    """(470, 3) the offsets of the tracked points for (K,) coefficients (zeros for None)."""
    if coefficients is None:
        return np.zeros((NUM_POINTS, 3))
    return np.tensordot(np.asarray(coefficients, np.float64), shape_targets().points, axes=1)


def _solve(J: np.ndarray, r: np.ndarray, lam: float) -> np.ndarray:
    """Bounded ridge least squares: argmin |J c - r|^2 + lam^2 |c|^2 over c in [0, 1]^K, J (N, K), r (N,)."""
    k = J.shape[1]
    A = np.concatenate([J, lam * np.eye(k)])
    b = np.concatenate([r, np.zeros(k)])
    return lsq_linear(A, b, bounds=(0.0, 1.0), method="bvls").x


def fit_shape(points: np.ndarray, xy: np.ndarray, fit: FrameFit, weights: np.ndarray | None = None, *,
              ridge: float = SHAPE_RIDGE) -> np.ndarray:
    """(K,) coefficients in [0, 1] that take the head's points nearest the picture's, its pose held.

    Args:
        points: (470, 3) the head's points without a shape, with the fitted expression, rest frame.
        xy: (470, 2) the picture's points, pixels; fit: the weak-perspective pose of the head in it.
        weights: (470,) per-point weights (None: ones).
        ridge: the coefficients' ridge, in squared face-size fractions per point.
    """
    from motion2video.core.rotations import axis_angle_to_matrix

    xy = np.asarray(xy, np.float64)
    M = fit.scale * PROJECTION @ axis_angle_to_matrix(np.asarray(fit.rotation, np.float64))  # (2, 3)
    residual = xy - (np.asarray(points, np.float64) @ M.T + fit.shift)  # (L, 2)
    J = np.einsum("ij,klj->lik", M, shape_targets().points).reshape(2 * len(xy), -1)  # (2L, K)
    sw = np.sqrt(np.repeat(np.ones(len(xy)) if weights is None else np.asarray(weights, np.float64), 2))
    size = float(np.max(xy.max(axis=0) - xy.min(axis=0)))
    return _solve(J * sw[:, None], residual.reshape(-1) * sw, np.sqrt(ridge * len(xy)) * size)


def fit_shape_to_offsets(offsets: np.ndarray, weights: np.ndarray | None = None, *,
                         ridge: float = SHAPE_RIDGE) -> np.ndarray:
    """(K,) coefficients in [0, 1] nearest a video's person offsets (:func:`.face_fit.person_neutral_offsets`,
    (470, 3) metres, rest frame), in the face's plane (x and z: the offsets carry no depth)."""
    plane = [0, 2]
    targets = shape_targets().points[:, :, plane]  # (K, L, 2)
    offsets = np.asarray(offsets, np.float64)[:, plane]
    sw = np.sqrt(np.repeat(np.ones(len(offsets)) if weights is None else np.asarray(weights, np.float64), 2))
    J = targets.transpose(1, 2, 0).reshape(-1, targets.shape[0])  # (2L, K)
    size = float(np.max(np.ptp(_neutral_points()[:, plane], axis=0)))  # the face's size, metres
    return _solve(J * sw[:, None], offsets.reshape(-1) * sw, np.sqrt(ridge * len(offsets)) * size)


def _neutral_points() -> np.ndarray:
    """(470, 3) Anny's default head at the tracked points, metres."""
    from motion2video.pose.face_anny import head_basis

    return head_basis().neutral
