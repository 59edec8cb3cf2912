"""2D structure renderers: OpenCV limb maps, per-limb channel maps and Gaussian joint heatmaps.

Everything here is deterministic (same input -> same pixels) so golden-frame tests stay stable.

Placement. 3D joints (world metres, z up) are projected with :mod:`motion2video.core.camera`: one camera is fitted
to the whole sequence (:func:`motion2video.core.camera.fit_camera`) unless one is passed, so there is no per-frame
zoom jitter. 2D joints (pixels, y down) are placed with one :func:`motion2video.core.camera.fit_image_framing` per
sequence unless a framing is passed.

Pixel convention. Continuous image coordinates put pixel centres at integer + 0.5 (see
:mod:`motion2video.core.camera`); OpenCV draws with pixel centres at integers, so every coordinate is shifted by
-0.5 before drawing, with 4 bits of sub-pixel precision (``shift=4``, 1/16 pixel) and anti-aliased
(``cv2.LINE_AA``) lines and circles. Heatmaps use the same convention: a joint at (10.5, 20.5) peaks at
exactly 1.0 in pixel row 20, column 10.

Palettes.

- ``"leftright"`` (default): left limbs green, right limbs orange-red, centre (spine, head) blue; joints in
  a lighter tint of their side's colour. With 3D input, limbs are drawn back to front (painter's order by
  the mean camera depth of their two joints) so near limbs cover far ones.
- ``"openpose"``: the OpenPose-18 / ControlNet-openpose drawing convention on a black background: 17 limbs
  (the two shoulder-ear limbs are not drawn, as in ControlNet), limb ``i`` in 60 % of the standard colour
  ``i``, then every keypoint ``k`` as a filled disc in full colour ``k``, always in the fixed OpenPose order.
  ControlNet's own maps at 512 px use ~8 px wide limbs and radius-4 keypoints; scale ``thickness`` and
  ``joint_radius`` with the image size to match. Joints are first converted to OpenPose-18 order by
  :func:`to_openpose18`.
"""

from __future__ import annotations

import functools

from dataclasses import dataclass

import cv2
import numpy as np

from motion2video.core.camera import ImageFraming, PinholeCamera, fit_camera, fit_image_framing, project
from motion2video.core.errors import InputError
from motion2video.core.motion import Motion
from motion2video.core.skeletons import H36M_17, OPENPOSE_18, Skeleton, get_skeleton
from renderers.base import RendererBase

SHIFT = 4  # sub-pixel bits for OpenCV drawing
_ONE = 1 << SHIFT
_MAX_COORD = 1.0e6  # pixels; clamps far-off points so the fixed-point coordinates stay in int32

PALETTES = ("leftright", "openpose")

# Left/right palette, RGB.
LEFT_COLOUR = (40, 210, 60)
RIGHT_COLOUR = (245, 90, 30)
CENTRE_COLOUR = (40, 110, 255)

# OpenPose-18 drawing convention (keypoint colour k, limb i drawn in colour i), RGB.
OPENPOSE_COLOURS: tuple[tuple[int, int, int], ...] = (
    (255, 0, 0), (255, 85, 0), (255, 170, 0), (255, 255, 0), (170, 255, 0), (85, 255, 0),
    (0, 255, 0), (0, 255, 85), (0, 255, 170), (0, 255, 255), (0, 170, 255), (0, 85, 255),
    (0, 0, 255), (85, 0, 255), (170, 0, 255), (255, 0, 255), (255, 0, 170), (255, 0, 85),
)
# The 17 drawn limbs as OpenPose-18 index pairs (0 nose, 1 neck, 2-4 right arm, 5-7 left arm, 8-10 right
# leg, 11-13 left leg, 14/15 right/left eye, 16/17 right/left ear).
OPENPOSE_LIMBS: tuple[tuple[int, int], ...] = (
    (1, 2), (1, 5), (2, 3), (3, 4), (5, 6), (6, 7), (1, 8), (8, 9), (9, 10),
    (1, 11), (11, 12), (12, 13), (1, 0), (0, 14), (14, 16), (0, 15), (15, 17),
)
OPENPOSE_LIMB_DIM = 0.6  # limbs are drawn at 60 % of their colour, keypoints at 100 %


@dataclass(frozen=True)
class SkeletonStyle:
    """How a skeleton map looks.

    Attributes:
        size: (width, height) in pixels.
        palette: ``"leftright"`` or ``"openpose"`` (see the module docstring).
        thickness: limb line width in pixels (integer, as OpenCV draws it).
        joint_radius: joint disc radius in pixels (sub-pixel precision); 0 draws no joints.
        background: RGB background colour (the OpenPose convention is black).
    """

    size: tuple[int, int] = (256, 256)
    palette: str = "leftright"
    thickness: int = 4
    joint_radius: float = 3.0
    background: tuple[int, int, int] = (0, 0, 0)

    def __post_init__(self) -> None:
        if len(self.size) != 2 or min(int(self.size[0]), int(self.size[1])) < 1:
            raise InputError(f"image size must be two positive integers (width, height), got {self.size}")
        if self.palette not in PALETTES:
            raise InputError(f"unknown skeleton palette {self.palette!r}; choose one of {', '.join(PALETTES)}")
        if int(self.thickness) < 1:
            raise InputError(f"limb thickness must be at least 1 pixel, got {self.thickness}")
        if not self.joint_radius >= 0:
            raise InputError(f"joint radius must be >= 0, got {self.joint_radius}")
        if len(self.background) != 3 or not all(0 <= int(c) <= 255 for c in self.background):
            raise InputError(f"background must be an RGB triple in 0..255, got {self.background}")

    @property
    def width(self) -> int:
        return int(self.size[0])

    @property
    def height(self) -> int:
        return int(self.size[1])


@dataclass(frozen=True)
class HeatmapStyle:
    """How joint heatmaps look.

    Attributes:
        size: (width, height) in pixels.
        sigma: Gaussian standard deviation in pixels.
    """

    size: tuple[int, int] = (256, 256)
    sigma: float = 4.0

    def __post_init__(self) -> None:
        if len(self.size) != 2 or min(int(self.size[0]), int(self.size[1])) < 1:
            raise InputError(f"image size must be two positive integers (width, height), got {self.size}")
        if not self.sigma > 0:
            raise InputError(f"heatmap sigma must be positive, got {self.sigma}")


@dataclass(frozen=True)
class PlacedJoints:
    """Joints placed in an image.

    Attributes:
        xy: (T, J, 2) float64 pixel coordinates (continuous frame, y down).
        depth: (T, J) float64 camera depth in metres for 3D input (<= 0 is behind the camera), else None.
        camera: the camera used for 3D input, else None.
        framing: the framing used for 2D input, else None.
    """

    xy: np.ndarray
    depth: np.ndarray | None
    camera: PinholeCamera | None
    framing: ImageFraming | None


# --- pure helpers -------------------------------------------------------------------------------------

def as_joints(motion_or_joints: Motion | np.ndarray, skeleton: Skeleton | str | None = None
              ) -> tuple[np.ndarray, Skeleton]:
    """Normalise renderer input.

    Args:
        motion_or_joints: a :class:`Motion`, or a (T, J, 2|3) array.
        skeleton: the skeleton of a raw array (default H36M-17); must be None or match a Motion's.
    Returns:
        (T, J, D) float64 joints and their :class:`Skeleton`.
    """
    if isinstance(motion_or_joints, Motion):
        skel = get_skeleton(motion_or_joints.skeleton)
        if skeleton is not None and _skeleton(skeleton).name != skel.name:
            raise ValueError(f"skeleton {_skeleton(skeleton).name} given for a {skel.name} motion")
        return np.asarray(motion_or_joints.joints, np.float64), skel
    joints = np.asarray(motion_or_joints, dtype=np.float64)
    skel = H36M_17 if skeleton is None else _skeleton(skeleton)
    if joints.ndim != 3 or joints.shape[-1] not in (2, 3) or joints.shape[0] < 1:
        raise ValueError(f"joints must have shape (T, J, 2|3) with T >= 1, got {joints.shape}")
    if joints.shape[1] != skel.num_joints:
        raise ValueError(f"skeleton {skel.name} has {skel.num_joints} joints but the array has {joints.shape[1]}")
    return joints, skel


def _skeleton(skeleton: Skeleton | str) -> Skeleton:
    return skeleton if isinstance(skeleton, Skeleton) else get_skeleton(skeleton)


def place_joints(
    joints: np.ndarray,
    size: tuple[int, int],
    *,
    camera: PinholeCamera | None = None,
    framing: ImageFraming | None = None,
    fit_points: np.ndarray | None = None,
) -> PlacedJoints:
    """Put a whole sequence of joints into image pixels with ONE camera or framing.

    Args:
        joints: (T, J, 3) world metres or (T, J, 2) pixels.
        size: (width, height) of the target image.
        camera: camera for 3D input; fitted to ``fit_points`` (default: all joints) when None. Its size
            must equal ``size``.
        framing: framing for 2D input; fitted to ``fit_points`` (default: all joints) when None.
        fit_points: (..., D) points the camera / framing is fitted to, when it is not given.
    Returns:
        The placed joints, with the camera or framing that was used.
    """
    width, height = int(size[0]), int(size[1])
    joints = np.asarray(joints, dtype=np.float64)
    fit = joints if fit_points is None else np.asarray(fit_points, dtype=np.float64)
    if joints.shape[-1] == 3:
        if framing is not None:
            raise ValueError("a 2D framing was given for 3D joints; pass a camera instead")
        if camera is None:
            camera = fit_camera(fit, width, height)
        elif (camera.width, camera.height) != (width, height):
            raise ValueError(f"camera is {camera.width}x{camera.height} but the image is {width}x{height}")
        uvd = project(joints, camera)  # (T, J, 3)
        return PlacedJoints(uvd[..., :2], uvd[..., 2], camera, None)
    if joints.shape[-1] == 2:
        if camera is not None:
            raise ValueError("a camera was given for 2D joints; pass a framing instead")
        if framing is None:
            framing = fit_image_framing(fit, width, height)
        return PlacedJoints(framing.apply(joints), None, None, framing)
    raise ValueError(f"joints must end in 2 or 3 coordinates, got shape {joints.shape}")


def to_openpose18(joints: np.ndarray, skeleton: Skeleton | str) -> np.ndarray:
    """Convert joints to the OpenPose-18 order.

    H36M-17 has no eyes or ears; they are derived approximately (works on 2D or 3D coordinates alike):
    nose = H36M joint 9 (neck/nose), neck = midpoint of the shoulders (OpenPose's definition), and with
    ``up = head - nose`` and ``lateral = left_shoulder - right_shoulder`` (so the face turns and
    foreshortens with the shoulders): eyes = ``nose + 0.35 up +/- 0.09 lateral``, ears =
    ``nose + 0.20 up +/- 0.21 lateral`` (about 6.5 cm between the eyes and 15 cm between the ears for a
    37 cm shoulder width). Other skeletons (COCO-17, BODY-25) are mapped by joint name, with a missing
    neck taken as the shoulders' midpoint.

    Args:
        joints: (..., J, D) joints in ``skeleton`` order.
        skeleton: their skeleton.
    Returns:
        (..., 18, D) joints in :data:`~motion2video.core.skeletons.OPENPOSE_18` order.
    """
    skel = _skeleton(skeleton)
    joints = np.asarray(joints, dtype=np.float64)
    if skel.name == OPENPOSE_18.name:
        return joints.copy()
    if skel.name == H36M_17.name:
        j = {name: joints[..., i, :] for i, name in enumerate(H36M_17.joints)}
        nose, up = j["neck"], j["head"] - j["neck"]
        lateral = j["left_shoulder"] - j["right_shoulder"]
        derived = {
            "nose": nose,
            "neck": 0.5 * (j["left_shoulder"] + j["right_shoulder"]),
            "right_eye": nose + 0.35 * up - 0.09 * lateral,
            "left_eye": nose + 0.35 * up + 0.09 * lateral,
            "right_ear": nose + 0.20 * up - 0.21 * lateral,
            "left_ear": nose + 0.20 * up + 0.21 * lateral,
        }
        return np.stack([derived[n] if n in derived else j[n] for n in OPENPOSE_18.joints], axis=-2)
    out = []
    for name in OPENPOSE_18.joints:
        if name in skel.joints:
            out.append(joints[..., skel.index(name), :])
        elif name == "neck" and {"left_shoulder", "right_shoulder"} <= set(skel.joints):
            out.append(0.5 * (joints[..., skel.index("left_shoulder"), :]
                              + joints[..., skel.index("right_shoulder"), :]))
        else:
            raise InputError(f"cannot convert skeleton {skel.name} to openpose-18: it has no {name} joint")
    return np.stack(out, axis=-2)


def _fixed(points: np.ndarray) -> np.ndarray:
    """(..., 2) continuous pixel coordinates -> (..., 2) int32 OpenCV fixed-point coordinates (non-finite
    values become 0; callers skip those joints)."""
    p = np.asarray(points, np.float64)
    p = np.clip(np.where(np.isfinite(p), p, 0.5) - 0.5, -_MAX_COORD, _MAX_COORD)
    return np.round(p * _ONE).astype(np.int32)


def _visible(joints_2d: np.ndarray, depth: np.ndarray | None) -> np.ndarray:
    """(J,) bool: the joint can be drawn (finite, and in front of the camera when depth is known)."""
    ok = np.all(np.isfinite(joints_2d), axis=-1)
    if depth is not None:
        ok &= np.isfinite(depth) & (depth > 0)
    return ok


def _tint(colour: tuple[int, int, int], amount: float) -> tuple[int, int, int]:
    """Mix a colour with white (amount > 0) or black (amount < 0)."""
    c = np.asarray(colour, np.float64)
    c = c + (255.0 - c) * amount if amount >= 0 else c * (1.0 + amount)
    return tuple(int(round(v)) for v in c)


def side_colour(skeleton: Skeleton, joint: int) -> tuple[int, int, int]:
    """The left/right palette colour of a joint (RGB)."""
    return {"left": LEFT_COLOUR, "right": RIGHT_COLOUR}.get(skeleton.side(joint), CENTRE_COLOUR)


@functools.lru_cache(maxsize=None)
def _palette(skeleton_name: str, palette: str) -> tuple[tuple, tuple, tuple]:
    """(limbs, limb colours, joint colours) of a skeleton in a palette; cached, since drawing a frame is far
    cheaper than recomputing the tints."""
    if palette == "openpose":
        limbs = OPENPOSE_LIMBS
        limb_colours = tuple(_tint(OPENPOSE_COLOURS[i], OPENPOSE_LIMB_DIM - 1.0) for i in range(len(limbs)))
        return limbs, limb_colours, tuple(OPENPOSE_COLOURS)
    skel = _skeleton(skeleton_name)
    limbs = tuple(skel.bones)
    limb_colours = tuple(side_colour(skel, child) for _, child in limbs)
    joint_colours = tuple(_tint(side_colour(skel, j), 0.45) for j in range(skel.num_joints))
    return limbs, limb_colours, joint_colours


def draw_skeleton(
    image: np.ndarray,
    joints_2d: np.ndarray,
    skeleton: Skeleton | str,
    style: SkeletonStyle,
    *,
    depth: np.ndarray | None = None,
) -> np.ndarray:
    """Draw one skeleton onto a copy of ``image``.

    Joints that are not finite, or behind the camera (``depth <= 0``), are not drawn, nor are their limbs
    (the usual convention for undetected keypoints).

    Args:
        image: (H, W, 3) uint8 RGB image (not modified).
        joints_2d: (J, 2) pixel coordinates in ``skeleton`` order (continuous frame, y down).
        skeleton: the joints' skeleton. With the ``"openpose"`` palette it must be OpenPose-18 or
            convertible by :func:`to_openpose18`.
        style: colours and sizes.
        depth: (J,) camera depths; with the left/right palette the limbs are then drawn back to front.
    Returns:
        (H, W, 3) uint8 new image.
    """
    skel = _skeleton(skeleton)
    out = np.ascontiguousarray(image, dtype=np.uint8).copy()
    joints_2d = np.asarray(joints_2d, np.float64)
    if joints_2d.shape != (skel.num_joints, 2):
        raise ValueError(f"joints_2d must be ({skel.num_joints}, 2) for {skel.name}, got {joints_2d.shape}")
    if style.palette == "openpose" and skel.name != OPENPOSE_18.name:
        joints_2d = to_openpose18(joints_2d, skel)
        depth = None if depth is None else to_openpose18(depth[:, None], skel)[:, 0]
    limbs, limb_colours, joint_colours = _palette(skel.name, style.palette)
    order = range(len(limbs))
    if style.palette != "openpose":
        if depth is not None:
            d = np.asarray(depth, np.float64)
            mean_depth = np.array([d[a] + d[b] for a, b in limbs])
            order = np.argsort(-mean_depth, kind="stable")  # far first
    ok = _visible(joints_2d, depth).tolist()
    pts = [tuple(p) for p in _fixed(joints_2d).tolist()]  # J (x, y) fixed-point int pairs, as OpenCV wants
    thickness = int(style.thickness)
    for i in order:
        a, b = limbs[i]
        if ok[a] and ok[b]:
            cv2.line(out, pts[a], pts[b], limb_colours[i], thickness, cv2.LINE_AA, SHIFT)
    radius = int(round(style.joint_radius * _ONE))
    if radius > 0:
        joint_order = range(len(pts))
        if depth is not None and style.palette != "openpose":
            joint_order = np.argsort(-np.asarray(depth, np.float64), kind="stable").tolist()
        for j in joint_order:
            if ok[j]:
                cv2.circle(out, pts[j], radius, joint_colours[j], -1, cv2.LINE_AA, SHIFT)
    return out


def gaussian_heatmaps(joints_2d: np.ndarray, size: tuple[int, int], sigma: float) -> np.ndarray:
    """One unnormalised Gaussian per joint, built separably (outer product of two 1-D Gaussians).

    ``h[j, y, x] = exp(-((x + 0.5 - u_j)^2 + (y + 0.5 - v_j)^2) / (2 sigma^2))``: the peak value 1 sits at
    the joint (a joint at a pixel centre gives exactly 1 there). Non-finite joints give an all-zero map.

    Args:
        joints_2d: (J, 2) pixel coordinates (continuous frame, y down).
        size: (width, height).
        sigma: standard deviation in pixels.
    Returns:
        (J, H, W) float32 in [0, 1].
    """
    gx, gy = gaussian_profiles(joints_2d, size, sigma)
    return (gy.astype(np.float32)[:, :, None] * gx.astype(np.float32)[:, None, :])  # (J, H, W)


def gaussian_profiles(joints_2d: np.ndarray, size: tuple[int, int], sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """The 1-D factors of :func:`gaussian_heatmaps`: ``gx`` (..., J, W) over the pixel centres of a row and ``gy``
    (..., J, H) over those of a column, float64, ``gy`` zero for a joint that is not finite. ``joints_2d`` (..., J, 2)
    pixels; ``size`` (width, height)."""
    width, height = int(size[0]), int(size[1])
    pts = np.asarray(joints_2d, np.float64)
    ok = np.all(np.isfinite(pts), axis=-1)  # (..., J)
    pts = np.where(ok[..., None], pts, 0.0)
    xs = np.arange(width, dtype=np.float64) + 0.5  # (W,) pixel centres
    ys = np.arange(height, dtype=np.float64) + 0.5  # (H,)
    gx = np.exp(-((xs - pts[..., :1]) ** 2) / (2.0 * sigma**2))  # (..., J, W)
    gy = np.exp(-((ys - pts[..., 1:]) ** 2) / (2.0 * sigma**2))  # (..., J, H)
    return gx, gy * ok[..., None]


def colourise_heatmaps(heatmaps: np.ndarray) -> np.ndarray:
    """Visualise heatmaps: the maximum over joints, scaled to 0..255 (1.0 -> 255) and mapped through
    OpenCV's INFERNO colour map (0 black, through purple and orange, to pale yellow at 1).

    Args:
        heatmaps: (T, J, H, W) or (J, H, W) float values in [0, 1].
    Returns:
        (T, H, W, 3) or (H, W, 3) uint8 RGB.
    """
    h = np.asarray(heatmaps)
    single = h.ndim == 3
    if single:
        h = h[None]
    peak = h.max(axis=1)  # (T, H, W)
    grey = np.round(np.clip(peak, 0.0, 1.0) * 255.0).astype(np.uint8)  # (T, H, W)
    bgr = cv2.applyColorMap(grey.reshape(-1, grey.shape[-1]), cv2.COLORMAP_INFERNO)  # (T*H, W, 3)
    rgb = bgr[..., ::-1].reshape(*grey.shape, 3)  # (T, H, W, 3)
    rgb = np.ascontiguousarray(rgb)
    return rgb[0] if single else rgb


def render_limb_maps(
    joints_2d: np.ndarray,
    skeleton: Skeleton | str,
    size: tuple[int, int],
    *,
    thickness: int = 4,
    as_uint8: bool = False,
) -> np.ndarray:
    """One channel per limb: each bone drawn alone (anti-aliased, value 1 on the line) in its own map.

    Args:
        joints_2d: (T, J, 2) pixel coordinates.
        skeleton: their skeleton; channels follow ``skeleton.bones`` order.
        size: (width, height).
        thickness: line width in pixels.
        as_uint8: the maps as drawn, 0..255, not divided into floats.
    Returns:
        (T, L, H, W) float32 in [0, 1] (uint8 in 0..255 with ``as_uint8``), L = number of bones.
    """
    skel = _skeleton(skeleton)
    width, height = int(size[0]), int(size[1])
    pts2 = np.asarray(joints_2d, np.float64)
    if pts2.ndim != 3 or pts2.shape[1:] != (skel.num_joints, 2):
        raise ValueError(f"joints_2d must be (T, {skel.num_joints}, 2), got {pts2.shape}")
    bones = skel.bones
    maps = np.zeros((pts2.shape[0], len(bones), height, width), np.uint8)  # (T, L, H, W)
    for t in range(pts2.shape[0]):
        ok = _visible(pts2[t], None)
        pts = _fixed(pts2[t])
        for i, (a, b) in enumerate(bones):
            if ok[a] and ok[b]:
                cv2.line(maps[t, i], tuple(int(v) for v in pts[a]), tuple(int(v) for v in pts[b]), 255,
                         int(thickness), cv2.LINE_AA, SHIFT)
    return maps if as_uint8 else maps.astype(np.float32) / 255.0


# --- renderers ----------------------------------------------------------------------------------------

class SkeletonRenderer(RendererBase):
    """Coloured skeleton (limb) maps, (T, H, W, 3) uint8.

    Example::

        with SkeletonRenderer(style=SkeletonStyle(size=(256, 256), palette="openpose")) as r:
            frames = r.render(motion)
    """

    def __init__(self, *, style: SkeletonStyle = SkeletonStyle()) -> None:
        self.style = style

    def place(self, motion_or_joints: Motion | np.ndarray, *, camera: PinholeCamera | None = None,
              framing: ImageFraming | None = None, skeleton: Skeleton | str | None = None
              ) -> tuple[PlacedJoints, Skeleton]:
        """Joints in this renderer's pixels (after OpenPose conversion when that palette is chosen).

        The camera / framing is fitted to the ORIGINAL joints, so both palettes frame a motion identically.
        """
        joints, skel = as_joints(motion_or_joints, skeleton)
        drawn, drawn_skel = joints, skel
        if self.style.palette == "openpose":
            drawn, drawn_skel = to_openpose18(joints, skel), OPENPOSE_18
        placed = place_joints(drawn, self.style.size, camera=camera, framing=framing, fit_points=joints)
        return placed, drawn_skel

    def render(self, motion_or_joints: Motion | np.ndarray, *, camera: PinholeCamera | None = None,
               framing: ImageFraming | None = None, skeleton: Skeleton | str | None = None) -> np.ndarray:
        """Draw every frame.

        Args:
            motion_or_joints: a Motion or a (T, J, 3) world / (T, J, 2) pixel array.
            camera: for 3D input; fitted once to the whole sequence when None.
            framing: for 2D input; fitted once to the whole sequence when None.
            skeleton: skeleton of a raw array (default H36M-17).
        Returns:
            (T, H, W, 3) uint8 RGB.
        """
        placed, skel = self.place(motion_or_joints, camera=camera, framing=framing, skeleton=skeleton)
        canvas = np.empty((self.style.height, self.style.width, 3), np.uint8)
        canvas[:] = np.asarray(self.style.background, np.uint8)
        frames = np.empty((placed.xy.shape[0], *canvas.shape), np.uint8)  # (T, H, W, 3)
        for t in range(placed.xy.shape[0]):
            depth = None if placed.depth is None else placed.depth[t]
            frames[t] = draw_skeleton(canvas, placed.xy[t], skel, self.style, depth=depth)
        return frames


class HeatmapRenderer(RendererBase):
    """Gaussian joint heatmaps: :meth:`heatmaps` gives (T, J, H, W) float32 (for a frame generator),
    :meth:`render` the (T, H, W, 3) uint8 visualisation of :func:`colourise_heatmaps`."""

    def __init__(self, *, style: HeatmapStyle = HeatmapStyle()) -> None:
        self.style = style

    def heatmaps(self, motion_or_joints: Motion | np.ndarray, *, camera: PinholeCamera | None = None,
                 framing: ImageFraming | None = None, skeleton: Skeleton | str | None = None) -> np.ndarray:
        """(T, J, H, W) float32 heatmaps, joints placed as in :class:`SkeletonRenderer`. Joints behind the
        camera give all-zero maps."""
        joints, _ = as_joints(motion_or_joints, skeleton)
        placed = place_joints(joints, self.style.size, camera=camera, framing=framing)
        xy = placed.xy.copy()
        if placed.depth is not None:
            xy[placed.depth <= 0] = np.nan
        width, height = int(self.style.size[0]), int(self.style.size[1])
        out = np.empty((xy.shape[0], xy.shape[1], height, width), np.float32)  # (T, J, H, W)
        for t in range(xy.shape[0]):
            out[t] = gaussian_heatmaps(xy[t], self.style.size, self.style.sigma)
        return out

    def render(self, motion_or_joints: Motion | np.ndarray, *, camera: PinholeCamera | None = None,
               framing: ImageFraming | None = None, skeleton: Skeleton | str | None = None) -> np.ndarray:
        """(T, H, W, 3) uint8 colourised heatmaps."""
        return colourise_heatmaps(self.heatmaps(motion_or_joints, camera=camera, framing=framing,
                                                skeleton=skeleton))
