"""The background behind the reference person, and the generated person composited over it.

A frame of the body generators is two layers (Photo Wake-Up, Liquid Warping GAN): the reference picture with
its person removed and filled in (:func:`inpaint_background`), and the generated person laid over it through a
soft matte (:func:`soft_matte`, :func:`composite`). The background is made once per reference, at the output's
resolution, over the whole picture: where the person stood shows the background in every frame (no ghost), and
inside the generated person's matte no background colour is mixed in.

Images are (H, W, 3) uint8 or float in [0, 1]; masks (H, W) bool or float in [0, 1]; pixels x right, y down.
"""

from __future__ import annotations

import numpy as np

# The person region removed before inpainting is the person mask grown by this many pixels at 128 px (scaled with
# the picture's width): a segmentation's outline runs through pixels mixed with the person (hair, a blurred edge),
# which the inpainting would otherwise spread inward as a halo of the person's colour.
BACKGROUND_GROW_PX = 3.0
# The matte's Gaussian feather (standard deviation), pixels of the matte: it smooths the stair of pixels along the
# outline. The generator's alpha is already soft over a few pixels (its network works at a quarter of the
# resolution); a feather of 1.5 px at 256 on top of it drew a blurred halo of the person around her outline on
# fashion_woman_shorts.png (the frames' Laplacian variance 2,578 without the feather, 1,824 with it).
MATTE_FEATHER_PX = 0.5
# The mesh generator's alpha is a sigmoid around its silhouette's logit of +-4: 0.018 outside the person and 0.982
# inside. The matte maps these levels to 0 and 1 (linear between), so no background is mixed into the person and no
# faint person colour spreads over the background.
MATTE_LEVELS = (0.05, 0.95)
# Thin things the person holds (a barbell's bar, ski poles) are not the person to BlazePose's segmentation, yet
# stayed behind in every frame where they were pictured. :func:`attached_objects` looks for them within this many
# person heights of a wrist ...
ATTACHED_REACH = 0.8
# ... keeps what touches the person within this many heights of a wrist (a pole held in a glove) ...
ATTACHED_CONTACT = 0.12
# ... across a gap of at most this many pixels at 256 px (a pole seen passing behind the hand) ...
ATTACHED_GAP_PX = 4.0
# ... when it is narrower than a disc of this radius in pixels at 256 px ...
ATTACHED_HALF_WIDTH_PX = 3.0
# ... and differs from what is beside it by at least this much (of 255, in one channel) ...
ATTACHED_CONTRAST = 40
# ... and is a line: at least this many person heights long (its box's diagonal), on average no wider than twice
# ATTACHED_HALF_WIDTH_PX (its area over that length). Texture beside a hand (rubble, gravel) is thin too, but in
# patches: without this test, 38% of a man's area in rubble beside his hands on one photo; with it, 0.6%.
ATTACHED_LENGTH = 0.1
# ... and straight: its pixels spread at most this many pixels at 256 px (one standard deviation) across its
# direction. What is held is a pole, a bar, a stick; a curved line that touches a hand is the edge of something the
# hand rests on: the bonnet of a truck a man leans on was 5.1% of his area without this test, 0.3% with it.
ATTACHED_BEND_PX = 3.0


def person_hole(person: np.ndarray, *, grow_px: float | None = None) -> np.ndarray:
    """(H, W) bool: the pixels to fill, ``person`` (H, W) bool / probability (> 0.5 is the person) grown by
    ``grow_px`` pixels (default :data:`BACKGROUND_GROW_PX` scaled from 128 px to the width)."""
    import cv2

    mask = np.asarray(person) > 0.5
    grow = BACKGROUND_GROW_PX * mask.shape[1] / 128 if grow_px is None else grow_px
    return cv2.dilate(mask.astype(np.uint8), disc(grow)) > 0


def disc(radius: float) -> np.ndarray:
    """OpenCV's elliptic structuring element of ``radius`` pixels (rounded, at least 1): (2r + 1, 2r + 1) uint8."""
    import cv2

    r = max(1, round(radius))
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))


def attached_objects(image: np.ndarray, person: np.ndarray, anchors: np.ndarray, *,
                     picture: np.ndarray | None = None) -> np.ndarray:
    """(H, W) bool: the thin things the person holds (a pole, a bar, a racket's handle), outside the segmented
    person.

    A thin thing is what a morphological opening or closing with a disc of radius :data:`ATTACHED_HALF_WIDTH_PX`
    removes (a line narrower than the disc) where it differs from what is beside it by at least
    :data:`ATTACHED_CONTRAST` (OpenCV's top-hat and black-hat, the larger over the three channels). Of those pixels
    within :data:`ATTACHED_REACH` person heights of a wrist (``anchors``), each connected part that touches the
    person within :data:`ATTACHED_CONTACT` heights of one (across a gap of :data:`ATTACHED_GAP_PX`) and is a straight
    line (:data:`ATTACHED_LENGTH`, :data:`ATTACHED_BEND_PX`) is kept.

    Why thin lines only: where nothing was held, a thin line filled in comes back as its surroundings continue,
    while a broad region beside a hand was background as often as an object on the photos tried (docs/results.md,
    "Things the person holds"). Why not a learned segmentation: the MediaPipe models the project ships segment
    people, not what they hold.

    Args:
        image: (H, W, 3) uint8 RGB. person: (H, W) bool or probability (> 0.5 is the person).
        anchors: (A, 2) pixels, the wrists.
        picture: (H, W) bool, False where the pixels do not come from the picture (a replicated border): never an
            object.
    Returns:
        (H, W) bool, False everywhere when no person is segmented.
    """
    import cv2

    mask = np.asarray(person) > 0.5
    rows = np.flatnonzero(mask.any(axis=1))
    if len(rows) == 0 or len(anchors) == 0:
        return np.zeros(mask.shape, bool)
    h, w = mask.shape
    height = float(rows[-1] - rows[0] + 1)
    scale = w / 256
    anchors = np.asarray(anchors, np.float64).reshape(-1, 2)
    yy, xx = np.mgrid[:h, :w]
    near = np.min([(xx - x) ** 2 + (yy - y) ** 2 for x, y in anchors], axis=0)  # squared distance to an anchor
    image = np.ascontiguousarray(image, np.uint8)
    width = disc(ATTACHED_HALF_WIDTH_PX * scale)
    contrast = np.maximum(cv2.morphologyEx(image, cv2.MORPH_TOPHAT, width),
                          cv2.morphologyEx(image, cv2.MORPH_BLACKHAT, width)).max(axis=2)
    grown = person_hole(mask, grow_px=2 * scale)
    thin = (contrast >= ATTACHED_CONTRAST) & (near < (ATTACHED_REACH * height) ** 2) & ~grown
    if picture is not None:
        thin &= np.asarray(picture, bool)
    contact = grown & (near < (ATTACHED_CONTACT * height) ** 2)
    reach = cv2.dilate(contact.astype(np.uint8), disc(ATTACHED_GAP_PX * scale)) > 0
    _, parts, boxes, _ = cv2.connectedComponentsWithStats(thin.astype(np.uint8))
    touching = np.unique(parts[reach & thin])
    touching = touching[touching > 0]
    length = np.hypot(boxes[touching, cv2.CC_STAT_WIDTH], boxes[touching, cv2.CC_STAT_HEIGHT])
    mean_width = boxes[touching, cv2.CC_STAT_AREA] / length
    line = (length >= ATTACHED_LENGTH * height) & (mean_width <= 2 * ATTACHED_HALF_WIDTH_PX * scale)
    straight = [part for part in touching[line]
                if off_line_spread(np.argwhere(parts == part)) <= ATTACHED_BEND_PX * scale]
    return np.isin(parts, straight)


def off_line_spread(points: np.ndarray) -> float:
    """The standard deviation of (N, 2) points across their principal direction, in their units: about 0.3 of a
    straight line's width, and more the more the line bends."""
    centred = np.asarray(points, np.float64) - np.mean(points, axis=0)
    return float(np.sqrt(max(np.linalg.eigvalsh(centred.T @ centred / len(centred))[0], 0.0)))


def inpaint_background(image: np.ndarray, person: np.ndarray, *, grow_px: float | None = None) -> np.ndarray:
    """The picture with its person removed: :func:`person_hole` filled from the picture's own patches
    (:func:`motion2video.generator.inpaint.patch_inpaint`).

    Why patches: a diffusing inpainting (OpenCV's Navier-Stokes) continues the hole's border inward, which is right
    for a flat wall but, over a hole the size of a person, drew what touches it into a smear of the person's shape:
    the skier's ski bindings into a dark bell at her feet, a cast shadow into a dark blob, asphalt and grass into a
    grey blur where a man lunged. Patches carry the snow, the asphalt's grain and the shadow's edge into the hole
    (docs/results.md, "The background behind the person", with the measurements).

    Args:
        image: (H, W, 3) uint8 RGB; person: (H, W) bool or probability, the person (> 0.5).
        grow_px: how far the hole reaches past the person (:func:`person_hole`).
    Returns:
        (H, W, 3) uint8, equal to ``image`` outside the hole (an image with no person comes back unchanged).
    """
    from motion2video.generator.inpaint import patch_inpaint

    hole = person_hole(person, grow_px=grow_px)
    image = np.ascontiguousarray(image, np.uint8)
    if not hole.any():
        return image.copy()
    if hole.all():  # nothing to fill from: the image's mean colour
        return np.broadcast_to(image.reshape(-1, 3).mean(0).round().astype(np.uint8), image.shape).copy()
    return patch_inpaint(image, hole)


def soft_matte(alpha: np.ndarray, *, feather_px: float | None = None) -> np.ndarray:
    """The person's soft matte: ``alpha`` (N, H, W) (or (H, W)) in [0, 1], the generated person's coverage (its
    rendered silhouette, as the generator corrects it), its levels stretched (:data:`MATTE_LEVELS`) and feathered
    by a Gaussian of ``feather_px`` pixels (default :data:`MATTE_FEATHER_PX`) so that the cut between person and
    background is a ramp, not a stair of pixels. A pixel deep inside the person stays 1, one far outside 0.

    Returns:
        float32 in [0, 1], the shape of ``alpha``.
    """
    import cv2

    lo, hi = MATTE_LEVELS
    a = np.clip((np.asarray(alpha, np.float32) - lo) / (hi - lo), 0.0, 1.0)
    sigma = MATTE_FEATHER_PX if feather_px is None else float(feather_px)
    if sigma <= 0:
        return a
    flat = a.reshape(-1, *a.shape[-2:])
    out = np.stack([cv2.GaussianBlur(m, (0, 0), sigmaX=sigma, borderType=cv2.BORDER_REPLICATE) for m in flat])
    return np.clip(out, 0.0, 1.0).reshape(a.shape)


def composite(background: np.ndarray, person: np.ndarray, matte: np.ndarray) -> np.ndarray:
    """``matte * person + (1 - matte) * background`` as uint8.

    Args:
        background: (H, W, 3) uint8 or float in [0, 1]; person: (N, H, W, 3) float in [0, 1] (the generated
            person's colours; whatever lies outside its matte is not used); matte: (N, H, W) in [0, 1].
    Returns:
        (N, H, W, 3) uint8.
    """
    bg = np.asarray(background)
    bg = bg.astype(np.float32) / 255.0 if bg.dtype == np.uint8 else bg.astype(np.float32)
    m = np.asarray(matte, np.float32)[..., None]
    mixed = m * np.clip(np.asarray(person, np.float32), 0.0, 1.0) + (1.0 - m) * bg[None]
    return np.clip(np.rint(mixed * 255.0), 0, 255).astype(np.uint8)
