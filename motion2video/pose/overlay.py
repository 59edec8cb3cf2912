"""Draw estimated keypoints on the input, so the user can check them (``motion2video pose --overlay``)."""

from __future__ import annotations

import numpy as np

from renderers.skeleton import SkeletonStyle, draw_skeleton


def overlay_style(width: int, height: int) -> SkeletonStyle:
    """Left/right palette, lines and joints scaled with the image (about 1/200 of its larger side)."""
    side = max(width, height)
    return SkeletonStyle(size=(width, height), thickness=max(2, round(side / 200)),
                         joint_radius=max(2.0, side / 160))


def draw_pose(image: np.ndarray, points2d: np.ndarray, confidence: np.ndarray | None = None, *,
              min_confidence: float = 0.0, style: SkeletonStyle | None = None) -> np.ndarray:
    """The H36M-17 joints drawn on a copy of an image.

    Args:
        image: (H, W, 3) uint8 RGB.
        points2d: (17, 2) canonical joints in the image's pixels.
        confidence: (17,) per-joint confidence; joints below ``min_confidence`` (and their limbs) are not
            drawn.
    Returns:
        (H, W, 3) uint8 RGB.
    """
    pts = np.asarray(points2d, np.float64).copy()
    if confidence is not None:
        pts[np.asarray(confidence) < min_confidence] = np.nan
    style = style or overlay_style(image.shape[1], image.shape[0])
    return draw_skeleton(image, pts, "h36m-17", style)
