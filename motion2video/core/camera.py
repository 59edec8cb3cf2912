"""One pinhole camera shared by every renderer, so projected joints and rendered meshes line up.

World frame: metres, right-handed, z up. Image frame: pixels, x right, y down, origin at the top-left
corner of the top-left pixel (pixel centres at integer + 0.5 in this continuous frame; OpenCV drawing uses
the same convention to within its sub-pixel shift).

A camera is ``position`` looking at ``target`` with world ``up`` = +z and a vertical field of view. The
default viewpoint looks at the body's front: Anny and the canonical skeleton face -y, so the camera sits
on the -y side looking towards +y, and the body's left (+x) appears on the image's right.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PinholeCamera:
    """A pinhole camera.

    Attributes:
        position: (3,) camera centre in world metres.
        target: (3,) the world point at the image centre.
        yfov: vertical field of view, radians.
        width, height: image size in pixels.
    """

    position: tuple[float, float, float]
    target: tuple[float, float, float]
    yfov: float
    width: int
    height: int

    @property
    def focal(self) -> float:
        """Focal length in pixels (square pixels)."""
        return 0.5 * self.height / np.tan(0.5 * self.yfov)

    def axes(self) -> np.ndarray:
        """(3, 3) rows = camera right, up, forward unit vectors in world coordinates."""
        return camera_axes(np.asarray(self.position, float), np.asarray(self.target, float))

    def gl_pose(self) -> np.ndarray:
        """(4, 4) camera-to-world matrix in OpenGL convention (looks down -z, y up), as pyrender wants."""
        right, up, forward = self.axes()
        pose = np.eye(4)
        pose[:3, 0], pose[:3, 1], pose[:3, 2] = right, up, -forward
        pose[:3, 3] = self.position
        return pose

    def project(self, points: np.ndarray) -> np.ndarray:
        """Project world points to pixels. See :func:`project`."""
        return project(points, self)

    def with_size(self, width: int, height: int) -> "PinholeCamera":
        return PinholeCamera(self.position, self.target, self.yfov, int(width), int(height))


def affine_matrix(a: float, b: np.ndarray) -> np.ndarray:
    """(2, 3) OpenCV matrix of ``x' = a x + b`` in this project's pixel convention (centres at integer + 0.5)
    for ``cv2.warpAffine``, which works on pixel indices."""
    off = a * 0.5 + np.asarray(b, np.float64) - 0.5
    return np.array([[a, 0.0, off[0]], [0.0, a, off[1]]])


def camera_axes(position: np.ndarray, target: np.ndarray, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Right, up and forward unit vectors (rows of a (3, 3) array) of a camera at ``position`` looking
    at ``target`` with the world's ``up`` direction."""
    forward = target - position
    forward = forward / np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(up, float))
    if np.linalg.norm(right) < 1e-8:  # looking straight up or down: pick +x as right
        right = np.array([1.0, 0.0, 0.0])
    right = right / np.linalg.norm(right)
    true_up = np.cross(right, forward)
    return np.stack([right, true_up, forward])


def project(points: np.ndarray, camera: PinholeCamera) -> np.ndarray:
    """Pinhole projection.

    Args:
        points: (..., 3) world points, metres.
        camera: the camera.
    Returns:
        (..., 3): pixel x, pixel y, and depth along the viewing direction in metres (<= 0 means behind).
    """
    axes = camera.axes()  # (3, 3)
    rel = np.asarray(points, dtype=np.float64) - np.asarray(camera.position, float)  # (..., 3)
    cam = rel @ axes.T  # (..., 3) right, up, forward components
    depth = cam[..., 2]
    safe = np.where(np.abs(depth) < 1e-9, 1e-9, depth)
    f = camera.focal
    x = 0.5 * camera.width + f * cam[..., 0] / safe
    y = 0.5 * camera.height - f * cam[..., 1] / safe
    return np.stack([x, y, depth], axis=-1)


def fit_camera(
    points: np.ndarray,
    width: int,
    height: int,
    *,
    azimuth_deg: float = 0.0,
    elevation_deg: float = 8.0,
    yfov_deg: float = 35.0,
    margin: float = 0.12,
) -> PinholeCamera:
    """A camera that keeps every point of a whole sequence in view (computed once: no per-frame zoom).

    Args:
        points: (..., 3) world points (e.g. all joints of all frames), metres.
        width, height: image size in pixels.
        azimuth_deg: rotation of the viewpoint about +z; 0 looks at the body's front (from -y).
        elevation_deg: how far above the target the camera looks down from.
        yfov_deg: vertical field of view.
        margin: fraction of the image left free on each side.
    Returns:
        The fitted camera.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    target = 0.5 * (lo + hi)
    az, el = np.deg2rad(azimuth_deg), np.deg2rad(elevation_deg)
    direction = np.array([np.sin(az) * np.cos(el), -np.cos(az) * np.cos(el), np.sin(el)])  # target->camera
    yfov = np.deg2rad(yfov_deg)
    xfov = 2 * np.arctan(np.tan(yfov / 2) * width / height)
    # Radius of the bounding sphere, then the distance at which it fits in both fields of view.
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.05)
    half = min(yfov, xfov) / 2
    distance = radius / np.sin(half) * (1.0 - 2 * margin) ** -1 * 0.75
    # Tighten with the actual projected extent (the sphere bound is loose for a thin standing body).
    cam = _camera(target + distance * direction, target, yfov, width, height)
    for _ in range(3):
        uv = project(pts, cam)
        if np.any(uv[:, 2] <= 0.05):
            break
        extent_x = np.abs(uv[:, 0] - width / 2).max() / (width / 2)
        extent_y = np.abs(uv[:, 1] - height / 2).max() / (height / 2)
        scale = max(extent_x, extent_y) / (1.0 - 2 * margin)
        distance = max(distance * scale, radius * 1.05)
        cam = _camera(target + distance * direction, target, yfov, width, height)
    return cam


def _camera(position: np.ndarray, target: np.ndarray, yfov: float, width: int, height: int) -> PinholeCamera:
    return PinholeCamera(tuple(float(v) for v in position), tuple(float(v) for v in target), float(yfov),
                         int(width), int(height))


@dataclass(frozen=True)
class ImageFraming:
    """A similarity map from input 2D coordinates to output pixels: ``out = in * scale + offset``."""

    scale: float
    offset: tuple[float, float]

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(..., 2) input coordinates -> (..., 2) output pixels."""
        return np.asarray(points, np.float64) * self.scale + np.asarray(self.offset)


def fit_image_framing(points: np.ndarray, width: int, height: int, *, margin: float = 0.1) -> ImageFraming:
    """Fit the bounding box of all 2D points of a sequence (pixels, y down) into a width x height image,
    keeping the aspect ratio, centred."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = np.maximum(hi - lo, 1e-6)
    scale = min(width * (1 - 2 * margin) / size[0], height * (1 - 2 * margin) / size[1])
    centre = 0.5 * (lo + hi)
    offset = np.array([width / 2, height / 2]) - centre * scale
    return ImageFraming(float(scale), (float(offset[0]), float(offset[1])))
