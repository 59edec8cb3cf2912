"""Where a body fitted to a picture lends its colours: the pure rules that decide, for the mesh generator's
reference, which fitted vertices count as shown and which pixel each samples.

A fitted body lies a little off the pictured person: a vertex outside the person would lend the background
(:func:`on_person`), one seen edge-on beside another body part lends that part (:func:`grazing_where_touching`,
by :func:`facing`), the fitted face is not on the pictured face (:func:`align_face`, :func:`crown_offset`), a
fitted hand beside the pictured hand samples the clothes (:func:`hand_colour_sources`), and clothes and hair reach
past the body (:func:`clothes_margin`). :func:`reference_sampling` applies the first three.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_erosion, distance_transform_edt
from scipy.spatial import cKDTree

from motion2video.generator.mesh_flow import pixel_indices, touching_other_part
from renderers import anny_model

# clothes_margin: the quantile, over the fitted silhouette's outline, of how far the person reaches past each outline
# pixel that the grown silhouettes cover, and the smallest margin (pixels at 128) that counts: BlazePose's mask has a
# fringe of about a pixel.
MARGIN_QUANTILE = 0.9
MIN_MARGIN_PX = 2.0


def clothes_margin(person: np.ndarray, silhouette: np.ndarray) -> int:
    """How far a real person reaches past the Anny body fitted to them, in pixels of the masks' size.

    A fitted Anny body has a body model's build, not the person's clothes and hair: the dancer of
    ``../shared/data/video/dancer.avi`` in her loose suit covers 369 pixels outside the fitted silhouette at 128 (of
    1,730). The mesh generator paints the person inside the target silhouette and the background outside it, so
    without a margin it drew her thin, with the backdrop inside her outline (person PSNR 15.3 dB, limb-warp 21.5).
    Growing every silhouette by the margin found here carries her width to every frame (docs/results.md).

    The margin is measured along the outline, not over the pixels: each outline pixel of the silhouette gets the
    distance of the farthest person pixel outside whose nearest silhouette pixel it is (0 where none), and the
    margin is :data:`MARGIN_QUANTILE` of those. So one blob beyond the body (a shoe's reflection on a shiny floor,
    a bag) does not widen the whole person: counted over the pixels, 171 pixels of reflection under one shoe in
    ``three_walking.jpg`` made the margin 11 px at 256 instead of 3, and every frame showed a hood of the head's
    fringe colour around his head (2026-11-26).

    Args:
        person: (S, S) bool the segmented person in the reference; silhouette: (S, S) bool the fitted mesh's.
    Returns:
        The margin in pixels, rounded up; 0 when it is under :data:`MIN_MARGIN_PX` (scaled from 128) or nothing
        lies outside.
    """
    person, silhouette = np.asarray(person, bool), np.asarray(silhouette, bool)
    outside = person & ~silhouette
    if not outside.any() or not silhouette.any():
        return 0
    distance, (near_y, near_x) = distance_transform_edt(~silhouette, return_indices=True)
    reach = np.zeros(silhouette.shape)  # per silhouette pixel: how far the person reaches past it
    ys, xs = np.nonzero(outside)
    np.maximum.at(reach, (near_y[ys, xs], near_x[ys, xs]), distance[ys, xs])
    outline = silhouette & ~binary_erosion(silhouette)
    margin = float(np.quantile(reach[outline], MARGIN_QUANTILE))
    if margin < MIN_MARGIN_PX * silhouette.shape[1] / 128:
        return 0
    return int(np.ceil(margin))


# on_person: the person's mask is eroded by this many pixels at 128. 0: a 1-2 px erosion hid 40% of the shown
# vertices (a limb's sides crowd into its silhouette's edge) and cost 1.6 dB of person PSNR on pictures of Anny
# people fitted as synthesize fits them (docs/results.md, "Turned legs, touching hands and jumps").
PERSON_EDGE_PX = 0


def on_person(uv: np.ndarray, person_mask: np.ndarray, *, edge_px: float = PERSON_EDGE_PX) -> np.ndarray:
    """(V,) bool: which of the (V, 2) vertex pixels of a body *fitted* to a picture land on the pictured person
    (``person_mask`` (S, S) bool, eroded by ``edge_px`` pixels at 128, scaled to S). A fitted body is a little off
    the person in places; a vertex it shows outside the person would lend the background's colour to every target
    pixel that samples it (white streaks on a turned leg), so it is treated as not shown: the surface completion
    then takes the nearest vertex that lands on the person."""
    size = person_mask.shape[1]
    rings = round(edge_px * size / 128)
    inner = binary_erosion(person_mask, iterations=rings) if rings > 0 else np.asarray(person_mask, bool)
    h, w = inner.shape
    x = np.floor(uv[:, 0]).astype(np.int64)
    y = np.floor(uv[:, 1]).astype(np.int64)
    inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    out = np.zeros(len(uv), bool)
    out[inside] = inner[y[inside], x[inside]]
    return out


# align_face: the fitted head is moved onto the pictured eyes when BlazePose sees both eyes at least this surely,
# the fitted mesh shows at least MIN_IRIS_SHOWN iris vertices of each, and the move is at most MAX_FACE_SHIFT times
# the distance between the pictured eyes (a face is about 3.6 of them high: a longer move is a wrong detection).
EYE_VISIBILITY = 0.5
MIN_IRIS_SHOWN = 3
MAX_FACE_SHIFT = 3.0


def head_weights(rest) -> np.ndarray:
    """(V,) float in [0, 1]: how much each vertex follows a move of the face in the picture (:func:`align_face`):
    1 on the head (:func:`renderers.anny_model.head_vertices`), falling linearly to 0 down the neck, from the head
    bone to the lowest neck bone (``neck01``), by height in the rest pose; 0 below. (Weights by how far in front
    of the skull base a point lies, as a turn of the head would move it, gave up to 0.4 dB less head PSNR with
    references fitted to held-out real-mocap pairs.)"""
    head = anny_model.head_vertices()
    top = rest.bone_heads[anny_model.bone_index("head"), 2]
    bottom = rest.bone_heads[anny_model.bone_index("neck01"), 2]
    ramp = np.clip((rest.vertices[:, 2] - bottom) / max(top - bottom, 1e-6), 0.0, 1.0)
    return np.where(head, 1.0, ramp)


FACE_HAIRLINE_M = 0.05  # face_weights: the hairline's height above the eyes in the rest pose (Anny's regions use 5 cm)


def face_weights(rest) -> np.ndarray:
    """(V,) float in [0, 1]: which head vertices are the face (1 at and below the eyes' height in the rest pose)
    and which the crown (0 from :data:`FACE_HAIRLINE_M` above the eyes up), linear between; 0 off the head."""
    iris = anny_model.vertex_regions(rest) == anny_model.IRIS
    eyes = float(np.mean(rest.vertices[iris, 2]))
    face = np.clip((eyes + FACE_HAIRLINE_M - rest.vertices[:, 2]) / FACE_HAIRLINE_M, 0.0, 1.0)
    return np.where(anny_model.head_vertices(), face, 0.0)


def crown_offset(uv: np.ndarray, silhouette: np.ndarray, person: np.ndarray, *, dx: float = 0.0) -> float | None:
    """How far (pixels, + down) the pictured person's head top lies below the fitted head's: the median over the
    middle half of the fitted head's columns of the difference between the first person row ``dx`` pixels to the
    right (where those columns sample once the face is moved sideways onto the eyes, :func:`eye_shift`) and the first
    silhouette row; None when a column has no person or the head is under 4 columns wide.

    Without ``dx``, a fitted head an eye distance beside the pictured one measured the person's shoulder and hair
    in half its columns: on the Mona Lisa the crown was moved 51 px down at 256 where the face moved 6, and the
    crown and forehead sampled her forehead and eyes (a skin crown, a second pair of eyes above the pasted face)."""
    head = np.asarray(uv)[anny_model.head_vertices()]
    w = silhouette.shape[1]
    lo, hi = np.quantile(head[:, 0], [0.25, 0.75])
    columns = np.arange(max(0, int(np.floor(lo))), min(w, int(np.ceil(hi)) + 1))
    moved = columns + int(round(dx))
    keep = (moved >= 0) & (moved < w)
    columns, moved = columns[keep], moved[keep]
    if len(columns) < 4:
        return None
    sil, per = np.asarray(silhouette, bool)[:, columns], np.asarray(person, bool)[:, moved]
    if not sil.any(axis=0).all() or not per.any(axis=0).all():
        return None
    return float(np.median(per.argmax(axis=0) - sil.argmax(axis=0)))


def eye_shift(uv: np.ndarray, visible: np.ndarray, eyes: np.ndarray, eye_visibility: np.ndarray, *,
              rest) -> np.ndarray | None:
    """(2,) pixels: the mean offset from the centres of the irises the fitted mesh shows to BlazePose's eyes, the
    move :func:`align_face` gives the face; None when an eye is not seen surely (:data:`EYE_VISIBILITY`), the mesh
    shows fewer than :data:`MIN_IRIS_SHOWN` vertices of an iris, or the offset is longer than
    :data:`MAX_FACE_SHIFT` times the distance between the pictured eyes. Arguments as :func:`align_face`."""
    eyes = np.asarray(eyes, np.float64)
    if np.any(np.asarray(eye_visibility) < EYE_VISIBILITY):
        return None
    iris = (anny_model.vertex_regions(rest) == anny_model.IRIS) & np.asarray(visible, bool)
    offsets = []
    for eye, side in zip(eyes, (rest.vertices[:, 0] > 0, rest.vertices[:, 0] < 0)):  # Anny's left is +x
        shown = iris & side
        if shown.sum() < MIN_IRIS_SHOWN:
            return None
        offsets.append(eye - np.asarray(uv, np.float64)[shown].mean(axis=0))
    shift = np.mean(offsets, axis=0)
    if np.linalg.norm(shift) > MAX_FACE_SHIFT * np.linalg.norm(eyes[0] - eyes[1]):
        return None
    return shift


def align_face(uv: np.ndarray, visible: np.ndarray, eyes: np.ndarray, eye_visibility: np.ndarray, *,
               rest, crown_dy: float | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """The reference vertices' pixels with the fitted face moved onto the pictured eyes.

    A body fitted to a picture puts its joints on the picture's joints, but not its face on the pictured face: the
    head joints are built from the ears and body lengths, and which way the head nods or looks they do not fix. On
    ``skier.jpg`` the fitted irises lay 7 px above and 6 px beside hers at 256, and her face sampled the stripes of
    her hat; on the demo's reference the fitted face lay 5 px too high while the fitted crown matched the picture's.
    So the face is shifted by the mean offset between BlazePose's eyes and the centres of the irises the fitted
    mesh shows, and the crown by the offset of the pictured head top (``crown_dy``, :func:`crown_offset`; the eyes'
    sideways offset), blended over the forehead (:func:`face_weights`); the neck follows the face part of the way
    (:func:`head_weights`). Without ``crown_dy`` the whole head takes the eyes' shift. Only where the colours are
    sampled changes: not the fitted body, nor the targets. Measured on held-out identities fitted as ``synthesize``
    fits them: head PSNR +2.6 to +3.3 dB where it applies (docs/results.md, "The fitted face on the pictured eyes").

    Args:
        uv: (V, 2) the fitted reference vertices' pixels; visible: (V,) bool which of them the mesh shows.
        eyes: (2, 2) BlazePose's left and right eye in the same pixels; eye_visibility: (2,) their visibility.
        rest: the fitted body's :class:`renderers.anny_model.AnnyRest` (its phenotype's rest pose).
        crown_dy: pixels (+ down) by which the pictured head top lies below the fitted one, or None.
    Returns:
        (the moved (V, 2) pixels, the (2,) shift of the face), or (``uv`` unchanged, None) when an eye is not seen
        surely (:data:`EYE_VISIBILITY`), the mesh shows fewer than :data:`MIN_IRIS_SHOWN` vertices of an iris, or
        the shift is longer than :data:`MAX_FACE_SHIFT` times the distance between the pictured eyes.
    """
    shift = eye_shift(uv, visible, eyes, eye_visibility, rest=rest)
    if shift is None:
        return uv, None
    return move_face(uv, shift, rest=rest, crown_dy=crown_dy), shift


def move_face(uv: np.ndarray, shift: np.ndarray, *, rest, crown_dy: float | None = None) -> np.ndarray:
    """(V, 2) ``uv`` with the face moved by ``shift`` (2,) (:func:`eye_shift`), the crown by ``crown_dy`` (with the
    shift's sideways part) blended over the forehead, the neck following part of the way: :func:`align_face`'s
    move, for a caller that has the shift already."""
    per_vertex = head_weights(rest)[:, None] * shift[None]  # (V, 2)
    if crown_dy is not None:  # the crown moves down by the pictured crown's offset, the face by the eyes'
        face = face_weights(rest)[:, None]
        crown = np.array([shift[0], crown_dy])
        head = anny_model.head_vertices()[:, None]
        per_vertex = np.where(head, face * shift[None] + (1.0 - face) * crown[None], per_vertex)
    moved = np.asarray(uv, np.float64) + per_vertex
    return moved.astype(np.asarray(uv).dtype)


# grazing_where_touching: a fitted vertex whose surface the picture shows at a grazing angle (facing() below this)
# and that lies within GRAZING_TOUCH_PX (at 128) of another body part does not lend its pixel.
GRAZING_FACING = 0.3
GRAZING_TOUCH_PX = 1.5
FACING_QUANTILE = 0.95  # facing() is relative to this quantile of the shown vertices' area ratio (a square view)


def facing(uv: np.ndarray, shown: np.ndarray, vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(V,) how squarely a picture shows each vertex's surface, about |cos| of the angle between the surface and the
    view: the summed pixel area of the vertex's triangles over their summed area on the body (``vertices``, metres),
    divided by :data:`FACING_QUANTILE` of that ratio over the ``shown`` vertices (which face the camera squarely
    somewhere on a body). Scale-free, so no camera is needed; 0 for a vertex without area.

    Args:
        uv: (V, 2) the vertices' pixels; shown: (V,) bool; vertices: (V, 3) the same mesh in 3D (Anny at rest:
            skinning changes areas little); triangles: (F, 3) int.
    """
    tri = np.asarray(triangles, np.int64)
    p = np.asarray(uv, np.float64)[tri]  # (F, 3, 2)
    d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    pixel_area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    q = np.asarray(vertices, np.float64)[tri]
    body_area = 0.5 * np.linalg.norm(np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]), axis=1)
    n = len(uv)
    ratio = np.bincount(tri.ravel(), np.repeat(pixel_area, 3), n) / np.maximum(
        np.bincount(tri.ravel(), np.repeat(body_area, 3), n), 1e-12)
    shown = np.asarray(shown, bool)
    square = float(np.quantile(ratio[shown], FACING_QUANTILE)) if shown.any() else 0.0
    return ratio / square if square > 0 else np.zeros(n)


def grazing_where_touching(uv: np.ndarray, shown: np.ndarray, *, rest, size: int,
                           fitted: np.ndarray | None = None) -> np.ndarray:
    """(V,) bool: shown vertices of a body *fitted* to a picture that the picture shows at a grazing angle
    (:func:`facing` under :data:`GRAZING_FACING`) where another body part lies beside them (within
    :data:`GRAZING_TOUCH_PX` at 128 of a shown vertex 10 cm away on the body:
    :func:`motion2video.generator.mesh_flow.touching_other_part`); the head's are never flagged (its face is moved
    onto the pictured eyes).

    Such a vertex is squeezed into the last pixel of its part's outline, where the fit is a pixel off the picture
    as often as not: on the demo's reference the side of a thigh under the hanging hand read the hand, and the sides
    of the hand the trousers, and where a future turns them to the camera they came out as skin blobs on the
    trousers and dark fingers (`make demo`'s future 2 at +41 and +48). Counted as hidden, they take their colour
    by the surface completion from squarely seen vertices of their own region. A grazing vertex at the person's
    outer outline is left alone (the background there is filled from inside the person,
    :func:`motion2video.generator.mesh_warp.fill_outside_person`): made hidden everywhere, 14% of the demo
    reference's shown vertices, it cost 0.2-0.5 dB of person PSNR on fitted references (docs/results.md).

    Args:
        uv: (V, 2) the fitted vertices' pixels in an (size, size) image; shown: (V,) bool.
        rest: the fitted body's :class:`renderers.anny_model.AnnyRest`.
        fitted: (V, 2) the pixels the fit gave, when ``uv`` has the head moved onto the pictured eyes
            (:func:`align_face`): the facing is read from them (a moved head stretches the neck's triangles).
    """
    shown = np.asarray(shown, bool)
    if shown.sum() < 3:
        return np.zeros(len(shown), bool)
    fitted = uv if fitted is None else fitted
    grazing = shown & (facing(fitted, shown, rest.vertices, anny_model.triangles()) < GRAZING_FACING)
    grazing &= ~anny_model.head_vertices()
    return grazing & touching_other_part(uv, shown, radius_px=GRAZING_TOUCH_PX * size / 128)


def reference_sampling(uv: np.ndarray, visible: np.ndarray, silhouette: np.ndarray, person, *, rest,
                       edge_px: float | None = PERSON_EDGE_PX, align: bool = True,
                       grazing: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Where a body fitted to a picture lends its colours: its (V, 2) vertex pixels with the face moved onto the
    pictured eyes and the crown onto the pictured head top (:func:`align_face`, :func:`crown_offset`; not moved
    without a person or with ``align`` False), and which of its (V,) depth-tested ``visible`` vertices count as
    shown: those landing on the segmented person (:func:`on_person` with ``edge_px``; all of them without a person
    or with ``edge_px`` None), less those seen at a grazing angle beside another body part
    (:func:`grazing_where_touching`, with ``grazing``).

    Args:
        uv, visible: the fitted reference mesh's (V, 2) vertex pixels and (V,) depth test, at the model's size S.
        silhouette: the fitted body's (S, S) bool mask.
        person: what BlazePose found in the picture, in the same pixels
            (:class:`motion2video.stages.reference.ReferencePerson`), or None.
        rest: the fitted body's :class:`renderers.anny_model.AnnyRest`.
    """
    fitted = np.asarray(uv)
    mask = None if person is None else person.segmented()
    if person is not None and align:
        shift = eye_shift(uv, visible, person.eyes, person.eye_visibility, rest=rest)
        if shift is not None:  # align_face's move, with the crown measured where the face moves
            uv = move_face(uv, shift, rest=rest, crown_dy=crown_offset(uv, silhouette, mask, dx=float(shift[0])))
    shown = np.asarray(visible, bool)
    if mask is not None and mask.any() and edge_px is not None:
        shown = shown & on_person(uv, mask, edge_px=edge_px)
    if grazing:
        shown = shown & ~grazing_where_touching(uv, shown, rest=rest, size=silhouette.shape[0], fitted=fitted)
    return uv, shown


# hand_colour_sources: a hand vertex whose pixel's colour lies further than this from the pictured hand's colour
# (Euclidean, RGB 0-255) samples where its nearest hand vertex that does not samples; the pictured hand's colour is
# the median over 3x3 pixels at each of its landmarks BlazePose sees at least HAND_VISIBILITY surely (at least
# MIN_HAND_LANDMARKS of the four).
HAND_COLOUR_DISTANCE = 80.0
HAND_VISIBILITY = 0.5
MIN_HAND_LANDMARKS = 3
HAND_REACH = 1.5  # clothes beside the hand: within this times the hand points' largest distance from their centre


POCKET_COLOUR_DISTANCE = 40.0  # pocketed_hand_skin: a pictured hand this close to the clothes around it is in them
MIN_POCKET_VERTICES = 5  # and the clothes around it and the face show at least this many vertices each
POCKET_REACH_PX = 6.0  # the clothes around a hand: within this (at 128 px) of its points' centre, at least


def pocketed_hand_skin(hand_colour: np.ndarray, colours: np.ndarray, shown: np.ndarray, near: np.ndarray,
                       regions: np.ndarray, any_hand: np.ndarray) -> int | None:
    """The vertex whose pixel a hand hidden in the clothes samples instead of itself, or None for a hand in view.

    A hand in a pocket (``woman_blue_tracksuit.jpg``) has BlazePose's hand points on the pocket, so its colour read
    there is the clothes' colour, which the hand-colour rule kept as if it were a glove: the hands came out as blue
    blocks when a target swung them out. A hand whose colour lies within :data:`POCKET_COLOUR_DISTANCE` of the median
    colour of the shown clothes around it (``near``) and further than :data:`HAND_COLOUR_DISTANCE` from the face's skin
    counts as hidden, and takes the face's skin: the shown face-skin vertex nearest the face's median colour. A glove
    of another colour than the clothes around it is kept.

    Args:
        hand_colour: (3,) the colour read at the hand's points; colours: (V, 3) each vertex's pixel; shown: (V,) bool;
        near: (V,) bool vertices within reach of the hand; regions: (V,) int; any_hand: (V,) bool either hand.
    """
    clothes = shown & near & np.isin(regions, (anny_model.TOP, anny_model.TROUSERS)) & ~any_hand
    face = np.flatnonzero(shown & (regions == anny_model.SKIN) & anny_model.head_vertices())
    if clothes.sum() < MIN_POCKET_VERTICES or len(face) < MIN_POCKET_VERTICES:
        return None
    if np.linalg.norm(hand_colour - np.median(colours[clothes], axis=0)) > POCKET_COLOUR_DISTANCE:
        return None
    skin = np.median(colours[face], axis=0)
    if np.linalg.norm(hand_colour - skin) <= HAND_COLOUR_DISTANCE:
        return None
    return int(face[np.argmin(np.linalg.norm(colours[face] - skin, axis=1))])


def hand_colour_sources(uv: np.ndarray, shown: np.ndarray, image: np.ndarray, hands: np.ndarray,
                        hand_visibility: np.ndarray, *, rest) -> np.ndarray | None:
    """(V,) int64: for every vertex, the vertex whose reference pixel it samples: itself, except a shown hand vertex
    that lands on something other than the pictured hand, which samples where the nearest hand vertex (on the body
    at rest) that lands on it does, and a shown clothes vertex beside the pictured hand that shows the hand's colour,
    which samples where the nearest vertex of its clothes showing their colour does. None when no vertex changes.

    A 17-joint pose does not say which way a hand turns. On the demo's reference the pictured right hand hangs
    edge-on beside the thigh while the fitted one shows its palm: 929 of its vertices counted as shown and 57% of
    them landed on the dark trousers beside the hand, so the hand came out dark in many frames. The hand's colour
    is read at BlazePose's wrist, index, pinky and thumb points (:data:`motion2video.stages.reference.HAND_LANDMARKS`);
    a hand vertex whose pixel is far from it (:data:`HAND_COLOUR_DISTANCE`) takes a pixel on the hand. A gloved hand
    keeps its glove (its landmarks read the glove's colour). The other way round, thigh vertices under a hand that
    hangs beside the thigh pass the depth test and take the hand's colour, which a target that moves the hand away
    showed as skin specks on the trousers: a shown vertex of the clothes (:data:`renderers.anny_model.TOP`,
    :data:`~renderers.anny_model.TROUSERS`) within :data:`HAND_REACH` of the pictured hand whose pixel is nearer the
    hand's colour than :data:`HAND_COLOUR_DISTANCE` and further than that from the median colour of its clothes
    samples where the nearest vertex of its clothes showing their colour does (bare skin beside a hand cannot be
    told from the hand, and is left). Reaching along the forearm to the elbow as well was measured and not kept:
    on the demo 12 more trousers pixels, on the fitted held-out references 0.03-0.05 dB less person PSNR. A hand in a
    pocket, whose points read the clothes around it, takes the face's skin (:func:`pocketed_hand_skin`). Applied
    after the surface completion
    (:func:`motion2video.generator.mesh_flow.complete_reference_uv`), whose test of a thigh touching the hand must see
    the fitted hand where it lies.

    Args:
        uv: (V, 2) vertex pixels; shown: (V,) bool. image: (S, S, 3) uint8 in the same pixels.
        hands: (2, 4, 2) the left and right hand's landmarks in those pixels; hand_visibility: (2, 4).
        rest: the fitted body's :class:`renderers.anny_model.AnnyRest`.
    """

    shown = np.asarray(shown, bool)
    sources = np.arange(len(uv), dtype=np.int64)
    h, w = image.shape[:2]
    picture = np.asarray(image, np.float64)

    def take_nearest(off: np.ndarray, on: np.ndarray) -> bool:  # off vertices sample where their nearest on does
        if len(off) == 0 or len(on) == 0:
            return False
        _, nearest = cKDTree(rest.vertices[on]).query(rest.vertices[off])
        sources[off] = on[nearest]
        return True

    any_hand = anny_model.hand_vertices("L") | anny_model.hand_vertices("R")
    regions = anny_model.vertex_regions(rest)
    ys, xs = pixel_indices(uv, h, w)
    colours = picture[ys, xs]  # (V, 3) what each vertex's pixel shows
    changed = False
    for side, points, seen in zip(("L", "R"), np.asarray(hands), np.asarray(hand_visibility)):
        points = points[seen >= HAND_VISIBILITY]
        if len(points) < MIN_HAND_LANDMARKS:
            continue
        patch = points[:, None, :] + np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1]), -1).reshape(1, 9, 2)
        colour = np.median(picture[pixel_indices(patch.reshape(-1, 2), h, w)], axis=0)
        to_hand = np.linalg.norm(colours - colour, axis=1)
        centre = points.mean(axis=0)
        reach = HAND_REACH * max(np.linalg.norm(points - centre, axis=1).max(), 1.0)
        apart = np.linalg.norm(np.asarray(uv, np.float64) - centre, axis=1)
        near = apart <= reach
        cheek = pocketed_hand_skin(colour, colours, shown, apart <= max(reach, POCKET_REACH_PX * h / 128), regions,
                                   any_hand)
        if cheek is not None:  # the hand is inside a pocket or a sleeve: it takes the face's skin
            sources[anny_model.hand_vertices(side)] = cheek
            changed = True
            continue
        hand = np.flatnonzero(anny_model.hand_vertices(side) & shown)
        far = to_hand[hand] > HAND_COLOUR_DISTANCE
        changed |= take_nearest(hand[far], hand[~far])
        for region in (anny_model.TOP, anny_model.TROUSERS):
            clothes = shown & (regions == region) & ~any_hand
            if clothes.sum() < 2:
                continue
            own = np.linalg.norm(colours - np.median(colours[clothes], axis=0), axis=1)
            covered = clothes & near & (to_hand < HAND_COLOUR_DISTANCE) & (own > HAND_COLOUR_DISTANCE)
            changed |= take_nearest(np.flatnonzero(covered), np.flatnonzero(clothes & (own <= HAND_COLOUR_DISTANCE)))
    return sources if changed else None
