"""A skirt, a dress or a long coat moved as one garment over the legs.

The body generators move a person's colours along a body (the Anny mesh, or the limbs of the keypoint warp), and a
body has two legs. Cloth that hangs from the hips across both legs does not follow either: in a generated frame a
knee-length dress split into two trouser legs as soon as the legs parted, with the background between them.

What this module does, in 2D over the generated frames:

1. :func:`find_skirt` looks in the reference picture for cloth that spans both legs. Along each leg (hip -> knee ->
   ankle, ``u`` = 0 at the hip, 1 at the knee, 2 at the ankle) it reads the colour of the person; the garment's
   colour is the one at the top of the thighs, and the hem is where both legs stop showing it. Cloth that reaches
   from the hips to at least :data:`MIN_HEM` and also covers the space between the legs (the segmented person, in
   the garment's colour, halfway between them) is a skirt. Trousers show their colour down to the shoes (no hem
   above the ankles), shorts end high on the thigh, and legs apart in trousers show the background between them,
   so none of them is taken for one.
2. :func:`lay_skirt` lays the reference's skirt panel, the quadrilateral between the hips and the hem on both
   legs, over each generated frame, moved with the target's hips and legs (two affine triangles): the cloth between
   the legs moves as one piece with them, and the legs come out below its hem. The arms stay in front of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from motion2video.core.skeletons import H36M_17

# Leg joints of H36M-17 (hip, knee, ankle) on the person's right and left.
RIGHT_LEG = tuple(H36M_17.joints.index(n) for n in ("right_hip", "right_knee", "right_ankle"))
LEFT_LEG = tuple(H36M_17.joints.index(n) for n in ("left_hip", "left_knee", "left_ankle"))
WRISTS = tuple(H36M_17.joints.index(n) for n in ("left_wrist", "right_wrist"))
ARMS = tuple(H36M_17.joints.index(n) for n in ("left_elbow", "right_elbow")) + WRISTS  # their bones: the arms
FEATHER_PX = 0.5  # the panel's edge is softened by a Gaussian of this many pixels at 256 px, scaled with the frame

GARMENT_TOP = (0.15, 0.45)  # where along the thighs the garment's colour is read (u, hip = 0, knee = 1)
MIN_HEM = 0.6  # a skirt reaches at least this far down the thighs (shorts and short jackets end above)
MAX_HEM = 1.9  # a hem is looked for down to here (ankle = 2); trousers show their colour down to the shoes
STEP = 0.05  # the spacing of the samples along the legs, in u
COLOUR_DISTANCE = 18.0  # colour_distance beyond which a sample is not the garment's colour
LIGHTNESS_WEIGHT = 0.5  # cloth between the legs is in shadow: lightness counts half as much as hue
BETWEEN_SHARE = 0.8  # of the samples halfway between the legs above the hem, the share that must be the garment


@dataclass(frozen=True, eq=False)
class Skirt:
    """Cloth that hangs from the hips across both legs in the reference, and the picture it is taken from.

    Attributes:
        hem: where the hem crosses the legs, in u (0 at the hips, 1 at the knees, 2 at the ankles).
        colour: (3,) the garment's CIE Lab colour (L in 0..100).
        quad: (4, 2) the reference's panel in its pixels: right hip, left hip, left leg's hem, right leg's hem.
        image: (H, W, 3) uint8 the reference picture, the panel's colours.
        cloth: (H, W) float32 the reference's segmented person: which of the panel is cloth, not background.
    """

    hem: float
    colour: np.ndarray
    quad: np.ndarray
    image: np.ndarray
    cloth: np.ndarray


def leg_points(points: np.ndarray, leg: tuple[int, int, int], u: np.ndarray) -> np.ndarray:
    """Points along a leg: points (..., 17, 2), u (U,) in [0, 2] -> (..., U, 2); hip -> knee for u in [0, 1],
    knee -> ankle for u in [1, 2]."""
    pts = np.asarray(points, np.float64)
    hip, knee, ankle = (pts[..., j, None, :] for j in leg)  # (..., 1, 2)
    u = np.asarray(u, np.float64)[:, None]
    upper = hip + np.clip(u, 0.0, 1.0) * (knee - hip)
    lower = knee + np.clip(u - 1.0, 0.0, 1.0) * (ankle - knee)
    return np.where(u <= 1.0, upper, lower)


def panel(points: np.ndarray, hem: float) -> np.ndarray:
    """The skirt panel of poses points (..., 17, 2): (..., 4, 2) right hip, left hip, left hem, right hem."""
    pts = np.asarray(points, np.float64)
    hem_r = leg_points(pts, RIGHT_LEG, np.array([hem]))[..., 0, :]
    hem_l = leg_points(pts, LEFT_LEG, np.array([hem]))[..., 0, :]
    return np.stack([pts[..., RIGHT_LEG[0], :], pts[..., LEFT_LEG[0], :], hem_l, hem_r], axis=-2)


def lab_image(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 RGB -> (H, W, 3) float32 CIE Lab (L in 0..100)."""
    return cv2.cvtColor(np.asarray(image, np.float32) / 255.0, cv2.COLOR_RGB2LAB)


def colours_at(lab: np.ndarray, person: np.ndarray, centres: np.ndarray, radius: float) -> np.ndarray:
    """The median Lab colour of the person's pixels within ``radius`` of each centre: (K, 2) -> (K, 3); NaN where
    fewer than a third of the disc is the person (``person`` (H, W) bool)."""
    h, w = person.shape
    r = max(1, int(round(radius)))
    dy, dx = np.mgrid[-r:r + 1, -r:r + 1]
    disc = dx ** 2 + dy ** 2 <= r * r
    out = np.full((len(centres), 3), np.nan)
    for k, (x, y) in enumerate(np.rint(np.asarray(centres)).astype(int)):
        ys, xs = y + dy[disc], x + dx[disc]
        inside = (ys >= 0) & (ys < h) & (xs >= 0) & (xs < w)
        ys, xs = ys[inside], xs[inside]
        on = person[ys, xs]
        if on.sum() * 3 >= disc.sum():
            out[k] = np.median(lab[ys[on], xs[on]], axis=0)
    return out


def colour_distance(lab: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """Distance of Lab colours (..., 3) from one Lab colour (3,), lightness weighted by :data:`LIGHTNESS_WEIGHT`
    (a fold or the shade between the legs darkens cloth without changing its hue); NaN stays NaN."""
    d = np.asarray(lab, np.float64) - np.asarray(colour, np.float64)
    return np.sqrt((LIGHTNESS_WEIGHT * d[..., 0]) ** 2 + d[..., 1] ** 2 + d[..., 2] ** 2)


def find_skirt(image: np.ndarray, person: np.ndarray, points: np.ndarray) -> Skirt | None:
    """The skirt the reference shows, or None (module docstring, step 1).

    Args:
        image: (H, W, 3) uint8 the reference picture.
        person: (H, W) the segmented person (probability or bool; > 0.5 is the person).
        points: (17, 2) the reference pose in the picture's pixels.
    """
    pts = np.asarray(points, np.float64)
    seg = np.asarray(person, np.float64) > 0.5
    lab = lab_image(image)
    length = np.mean([np.linalg.norm(pts[hip] - pts[knee]) + np.linalg.norm(pts[knee] - pts[ankle])
                      for hip, knee, ankle in (RIGHT_LEG, LEFT_LEG)])  # hip to ankle, pixels
    radius = max(1.5, 0.03 * length)
    us = np.arange(GARMENT_TOP[0], MAX_HEM + 1e-9, STEP)
    legs = [colours_at(lab, seg, leg_points(pts, leg, us), radius) for leg in (RIGHT_LEG, LEFT_LEG)]  # (U, 3) each
    top = (us >= GARMENT_TOP[0]) & (us <= GARMENT_TOP[1])
    samples = np.concatenate([leg[top] for leg in legs])
    samples = samples[~np.isnan(samples[:, 0])]
    if len(samples) < 4:
        return None
    colour = np.median(samples, axis=0)
    far = [colour_distance(leg, colour) > COLOUR_DISTANCE for leg in legs]  # NaN compares False
    off = far[0] & far[1]  # both legs off the garment's colour
    hem_at = next((i for i in range(len(us) - 1) if us[i] > GARMENT_TOP[1] and off[i] and off[i + 1]), None)
    if hem_at is None or us[hem_at] < MIN_HEM:
        return None
    hem = float(us[hem_at])
    above = us[(us >= GARMENT_TOP[0]) & (us < hem - STEP)]
    right, left = leg_points(pts, RIGHT_LEG, above), leg_points(pts, LEFT_LEG, above)
    apart = np.linalg.norm(right - left, axis=1) > 2.0 * radius  # where the legs are apart enough to tell
    if apart.sum() < 3:
        return None
    middle = colours_at(lab, seg, 0.5 * (right + left)[apart], radius)
    between = colour_distance(middle, colour) <= COLOUR_DISTANCE  # NaN (not the person) compares False
    if between.mean() < BETWEEN_SHARE:
        return None
    return Skirt(hem=hem, colour=colour, quad=panel(pts, hem), image=np.asarray(image),
                 cloth=np.asarray(person, np.float32))


def twice_area(tri: np.ndarray) -> float:
    """Twice the signed area of a triangle (3, 2) (the 2D cross product of two of its sides)."""
    (ax, ay), (bx, by) = tri[1] - tri[0], tri[2] - tri[0]
    return float(ax * by - ay * bx)


def arms_region(points: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) float32 1 on the arms of the pose points (17, 2): upper arms and forearms as
    :func:`motion2video.generator.warp.limb_region` draws limbs, and a disc of that width for each hand."""
    from motion2video.generator.warp import limb_region, limb_thickness

    thickness = limb_thickness(points)
    out = limb_region(points, width=shape[1], height=shape[0], limbs=ARMS).astype(np.uint8)
    for wrist in WRISTS:
        c = np.rint(np.asarray(points, np.float64)[wrist]).astype(int)
        cv2.circle(out, (int(c[0]), int(c[1])), thickness, 1, -1)
    return out.astype(np.float32)


def lay_skirt(frame: np.ndarray, skirt: Skirt, points: np.ndarray, *, feather_px: float | None = None) -> np.ndarray:
    """The reference's skirt panel laid over a generated frame of the reference's scale (module docstring, step 2).

    Args:
        frame: (H, W, 3) uint8 a generated frame, the size of ``skirt.image``.
        skirt: from :func:`find_skirt` on that reference.
        points: (17, 2) the frame's pose in its pixels.
        feather_px: the Gaussian's standard deviation that softens the panel's edge (None: :data:`FEATHER_PX` at
            256 px, scaled with the frame).
    Returns:
        (H, W, 3) uint8.
    """
    h, w = frame.shape[:2]
    if feather_px is None:
        feather_px = FEATHER_PX * h / 256
    target = panel(points, skirt.hem)
    image, cloth = skirt.image, skirt.cloth
    colour = np.zeros((h, w, 3), np.float32)
    alpha = np.zeros((h, w), np.float32)
    for tri in ((0, 1, 2), (0, 2, 3)):
        src, dst = skirt.quad[list(tri)].astype(np.float32), target[list(tri)].astype(np.float32)
        if min(abs(twice_area(dst)), abs(twice_area(src))) < 1.0:
            continue  # a triangle with no area (legs one behind the other)
        move = cv2.getAffineTransform(src, dst)
        inside = np.zeros((h, w), np.uint8)
        cv2.fillConvexPoly(inside, np.rint(dst).astype(np.int32), 1)
        take = (inside > 0) & (alpha == 0)
        colour[take] = cv2.warpAffine(image, move, (w, h), flags=cv2.INTER_LINEAR,
                                      borderMode=cv2.BORDER_REPLICATE).astype(np.float32)[take]
        alpha[take] = cv2.warpAffine(cloth, move, (w, h), flags=cv2.INTER_LINEAR)[take]
    alpha *= 1.0 - arms_region(points, (h, w))
    if feather_px > 0:
        alpha = cv2.GaussianBlur(alpha, (0, 0), feather_px)
    alpha = np.clip(alpha, 0.0, 1.0)[..., None]
    return np.rint(frame * (1.0 - alpha) + colour * alpha).clip(0, 255).astype(np.uint8)


def lay_skirts(frames: np.ndarray, skirt: Skirt, points: np.ndarray) -> np.ndarray:
    """(R, H, W, 3) uint8 ``frames`` with the skirt laid over each (:func:`lay_skirt`), moved with its pose of
    ``points`` (R, 17, 2) in the frames' pixels."""
    return np.stack([lay_skirt(frame, skirt, pts) for frame, pts in zip(frames, points)])
