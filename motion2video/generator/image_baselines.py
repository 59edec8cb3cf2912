"""Frame baselines evaluated on the same pairs as the generator.

- ``copy-reference``: the reference frame unchanged.
- ``limb-warp``: a piecewise-affine warp of the reference frame taking its 2D control points (body joints, or
  projected face-mesh vertices for faces) to the target's, with fixed anchors around the image border so the
  triangulation covers every pixel. It is the map scikit-image's PiecewiseAffineTransform and ``warp`` make
  (a Delaunay triangulation of the target's points, each triangle's affine map, bilinear sampling with the
  border's pixels beyond it), computed for all pixels at once from SciPy's barycentric transforms. scikit-image
  fits each triangle's map by a least-squares solve of its own: 23 ms per 128-px body pair and 51 ms per face
  pair, against 5 and 6 ms here, for the same pixels (64 held-out pairs of each).

Points are image pixels (x right, y down, pixel centres at integer + 0.5), as the shared camera projects them.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import map_coordinates
from scipy.spatial import Delaunay

BASELINES = ("copy-reference", "limb-warp")


def copy_reference(ref_image: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 -> the same frame (a copy)."""
    return np.array(ref_image, copy=True)


def border_anchors(width: int, height: int, *, per_side: int = 4) -> np.ndarray:
    """(4 * per_side, 2) points just outside the image border (pixel coordinates), evenly spaced."""
    t = np.linspace(0.0, 1.0, per_side, endpoint=False)
    x0, y0, x1, y1 = -1.0, -1.0, width + 1.0, height + 1.0
    top = np.stack([x0 + t * (x1 - x0), np.full_like(t, y0)], axis=1)
    right = np.stack([np.full_like(t, x1), y0 + t * (y1 - y0)], axis=1)
    bottom = np.stack([x1 - t * (x1 - x0), np.full_like(t, y1)], axis=1)
    left = np.stack([np.full_like(t, x0), y1 - t * (y1 - y0)], axis=1)
    return np.concatenate([top, right, bottom, left])


def _select_points(ref_points: np.ndarray, tgt_points: np.ndarray, anchors: np.ndarray,
                   *, width: int, height: int, min_dist: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Keep control points that lie inside the anchor frame in both images and are at least ``min_dist``
    pixels from every kept point in both images (coincident points make degenerate triangles)."""
    keep_ref, keep_tgt = [a for a in anchors], [a for a in anchors]
    for p, q in zip(ref_points, tgt_points):
        inside = all(-1.0 < v[0] < width + 1.0 and -1.0 < v[1] < height + 1.0 for v in (p, q))
        if not inside or not (np.all(np.isfinite(p)) and np.all(np.isfinite(q))):
            continue
        if np.min(np.linalg.norm(np.asarray(keep_ref) - p, axis=1)) < min_dist:
            continue
        if np.min(np.linalg.norm(np.asarray(keep_tgt) - q, axis=1)) < min_dist:
            continue
        keep_ref.append(p)
        keep_tgt.append(q)
    return np.asarray(keep_ref, np.float64), np.asarray(keep_tgt, np.float64)


def limb_warp(ref_image: np.ndarray, ref_points: np.ndarray, tgt_points: np.ndarray) -> np.ndarray:
    """Piecewise-affine warp of the reference so its control points land on the target's.

    Args:
        ref_image: (H, W, 3) uint8 reference frame.
        ref_points: (K, 2) control points in the reference frame, pixels.
        tgt_points: (K, 2) the same points in the target frame, pixels.
    Returns:
        (H, W, 3) uint8 warped frame.
    """
    height, width = ref_image.shape[:2]
    anchors = border_anchors(width, height)
    src_ref, src_tgt = _select_points(np.asarray(ref_points, np.float64), np.asarray(tgt_points, np.float64),
                                      anchors, width=width, height=height)
    source = piecewise_affine_source(src_tgt, src_ref, width=width, height=height)  # (H, W, 2) x, y
    rows, cols = source[..., 1], source[..., 0]
    image = np.asarray(ref_image, np.float64)
    out = np.stack([map_coordinates(image[..., c], [rows, cols], order=1, mode="nearest")
                    for c in range(image.shape[2])], axis=-1)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def piecewise_affine_source(tgt_points: np.ndarray, ref_points: np.ndarray, *, width: int,
                            height: int) -> np.ndarray:
    """Where each pixel of the target frame comes from in the reference: the Delaunay triangulation of the
    target's points, each triangle mapped affinely onto the same triangle of the reference's points.

    Args:
        tgt_points, ref_points: (K, 2) pixels (centres at integer + 0.5), the same K points in the two frames.
        width, height: the target frame's size.
    Returns:
        (height, width, 2) float64 reference x, y of every target pixel in array coordinates (pixel centres at
        integers, as ``scipy.ndimage.map_coordinates`` reads them); -1 for a pixel no triangle covers.
    """
    tgt = np.asarray(tgt_points, np.float64) - 0.5
    ref = np.asarray(ref_points, np.float64) - 0.5
    tri = Delaunay(tgt)
    ys, xs = np.mgrid[:height, :width]
    pixels = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)  # (P, 2)
    simplex = tri.find_simplex(pixels)
    covered = simplex >= 0
    inside = simplex[covered]  # (C,) the triangle of each covered pixel
    affine = tri.transform[inside]  # (C, 3, 2): inverse of the triangle's edge matrix, its last corner
    first = np.einsum("cij,cj->ci", affine[:, :2], pixels[covered] - affine[:, 2])  # (C, 2) barycentric
    weights = np.concatenate([first, 1.0 - first.sum(axis=1, keepdims=True)], axis=1)  # (C, 3)
    source = np.full((len(pixels), 2), -1.0)
    source[covered] = np.einsum("ck,ckd->cd", weights, ref[tri.simplices[inside]])
    return source.reshape(height, width, 2)


def run_baseline(name: str, ref_images: np.ndarray, ref_points: np.ndarray, tgt_points: np.ndarray) -> np.ndarray:
    """A baseline over a batch.

    Args:
        name: one of :data:`BASELINES`.
        ref_images: (N, H, W, 3) uint8.
        ref_points, tgt_points: (N, K, 2) pixels.
    Returns:
        (N, H, W, 3) uint8 predicted target frames.
    """
    if name == "copy-reference":
        return np.array(ref_images, copy=True)
    if name == "limb-warp":
        return np.stack([limb_warp(img, p, q) for img, p, q in zip(ref_images, ref_points, tgt_points)])
    raise ValueError(f"unknown baseline {name!r}; known: {', '.join(BASELINES)}")
