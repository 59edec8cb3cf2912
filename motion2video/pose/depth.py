"""The body's distance from the camera from its apparent size, and its 3D root path through a video.

A bone of 3D length ``L`` metres, seen ``Z`` metres away by a pinhole camera of focal length ``f`` pixels, spans
``f L' / Z`` pixels, where ``L'`` is its length across the image plane (the part of it not along the line of
sight). BlazePose's world landmarks are metric and image-aligned (x right, y down, z away), so ``L'`` is the
length of their x, y difference, and each frame's distance is ``Z = f * sum(L') / sum(pixels)`` over the
torso and leg bones (weighted by visibility; turning the body shortens both sums alike). The root then sits at
``((u - cx) Z / f, (v - cy) Z / f, Z)`` in the camera's axes for the pelvis's pixel ``(u, v)``: a person who walks
towards the camera travels towards it, and sideways steps are in the same metres.

The camera's focal length is not in a video file: :func:`default_focal` takes a 60 degree field of view across
the frame's longer side (a phone's main camera is 65-70 degrees, a webcam 60-78, a lab camera often narrower);
distances scale with it.
"""

from __future__ import annotations

import numpy as np

# BlazePose landmark pairs whose lengths measure the body's size: shoulders, hips, torso sides, thighs, shins
SIZE_BONES = np.array([(11, 12), (23, 24), (11, 23), (12, 24), (23, 25), (24, 26), (25, 27), (26, 28)])
FIELD_OF_VIEW_DEG = 60.0  # assumed across the longer side of a video frame


def default_focal(width: int, height: int, fov_deg: float = FIELD_OF_VIEW_DEG) -> float:
    """Focal length in pixels of a camera with ``fov_deg`` across the longer side of a width x height frame."""
    return 0.5 * max(width, height) / np.tan(0.5 * np.deg2rad(fov_deg))


def pixels_per_metre(xy: np.ndarray, world: np.ndarray, visibility: np.ndarray) -> np.ndarray:
    """(T,) the body's apparent scale, pixels per metre across the image plane (= focal / distance).

    Args:
        xy: (T, 33, 2) image landmarks, pixels.
        world: (T, 33, 3) world landmarks, metres, x right, y down (image-aligned).
        visibility: (T, 33) in [0, 1].
    """
    a, b = SIZE_BONES[:, 0], SIZE_BONES[:, 1]
    pixels = np.linalg.norm(xy[:, a] - xy[:, b], axis=-1)  # (T, B)
    metres = np.linalg.norm(world[:, a, :2] - world[:, b, :2], axis=-1)  # (T, B)
    weight = np.minimum(visibility[:, a], visibility[:, b]) + 1e-3  # (T, B)
    return (weight * pixels).sum(axis=1) / np.maximum((weight * metres).sum(axis=1), 1e-6)


# The apparent size's running window: on the dancer video (a person dancing in place, 2.2 m away) the distance
# jitters by 0.18 m (5th to 95th percentile) and adds 4.1 m of path in 63 s with a 0.4 s window, 0.14 m and 2.4 m
# with 1 s; a walk changes its distance steadily, which a centred window keeps.
DEPTH_WINDOW_S = 1.0


def smooth_in_time(values: np.ndarray, fps: float, seconds: float = DEPTH_WINDOW_S) -> np.ndarray:
    """(T,) a per-frame series through a running median of ``seconds`` (drops single-frame outliers), then a
    running mean of the same window. Near the ends the window narrows to stay centred, so that a steady trend
    (a walk towards the camera) keeps its full extent instead of bending towards its middle."""
    values = np.asarray(values, np.float64)
    half = max(1, int(round(0.5 * seconds * fps)))
    n = len(values)
    reach = [min(half, i, n - 1 - i) for i in range(n)]
    median = np.array([np.median(values[i - r:i + r + 1]) for i, r in enumerate(reach)])
    return np.array([median[i - r:i + r + 1].mean() for i, r in enumerate(reach)])


def root_path(pelvis: np.ndarray, scale: np.ndarray, *, focal: float, centre: np.ndarray, fps: float
              ) -> np.ndarray:
    """(T, 3) the pelvis in metres, project axes (x right, y away from the camera, z up), camera at the origin.

    Args:
        pelvis: (T, 2) the pelvis's pixels.
        scale: (T,) :func:`pixels_per_metre` of each frame (smoothed here in log space over :data:`DEPTH_WINDOW_S`,
            ``fps`` frames a second).
        focal: focal length, pixels; centre: (2,) principal point, pixels.
    """
    scale = np.exp(smooth_in_time(np.log(np.maximum(scale, 1e-6)), fps))
    depth = focal / scale  # (T,) metres
    offset = (np.asarray(pelvis, np.float64) - np.asarray(centre, np.float64)) / focal  # (T, 2)
    return np.stack([offset[:, 0] * depth, depth, -offset[:, 1] * depth], axis=1)
