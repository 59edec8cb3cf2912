"""The pictured face drawn over the generated head: the photo's own pixels, moved as the fitted head moves.

A body generator at 256 px draws a head about 20 px tall from a network working on a body crop; whatever face the
photo shows does not survive it. So the face is taken from the photo itself and laid over each generated frame:

1. **Where it goes.** The face's landmarks have points on the body mesh's head (the face mesh's correspondence
   with Anny); the least-squares 2D affine map of those points from the reference mesh onto a target's posed mesh
   (:func:`head_affine`: in-plane turn, scale, translation, and the foreshortening of a small nod or turn) moves
   the face, and the face bends as the head's turn changes its shape (:class:`FaceBend`: the face's points lie at
   different depths, so a turned head's nose moves farther than its ears; each landmark's offset from its affine
   place is what the head's rest points show when seen the pictured way and the target's way).
2. **Whether it fits.** A face seen from far to the side is not an image of the pictured one. The head's turn
   out of the picture plane between the photo and the target (the angle between the directions the camera looks
   along in the head's own axes, :func:`view_direction`: in the photo from the face's landmarks, in the target from
   the posed head's vertices) and the share of the landmarks' surface points the target still shows (an arm in
   front, a turn) fade the face out (:func:`paste_weight`), leaving the generator's head: a wrong face is worse
   than no face.
3. **How it is laid over.** The face's matte (the convex hull of the face landmarks, feathered: :func:`face_matte`)
   is warped with the face and cut to the triangles of the face the target shows (:func:`shown_face`: a hand in
   front of the face stays in front of it); ``weight * matte`` (times the generated person's matte) blends the
   warped photo, sampled bicubically, over the frame (:func:`paste_head`). Outside the warped matte the frame is
   untouched.

Images are (H, W, 3) uint8; pixels x right, y down, the origin at the top-left corner of the top-left pixel (its
centre at (0.5, 0.5)); affine maps are (2, 3) float64 acting on (x, y, 1) in those coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from motion2video.generator.background import disc

# paste_weight: the face is laid over fully up to TURN_FULL_DEG of turn out of the picture plane, not at all from
# TURN_NONE_DEG on, linear between. Photos of people facing the camera, driven by a walk towards it, measured 18-20
# degrees (woman_blue_tracksuit.jpg, fashion_woman_shorts.png: the photo's camera looks down on the face a little
# more than the placement's); the three-quarter face of fashion_man_red_jacket.png 22-26 degrees; a profile 85. A
# sampled walk swings the shoulders, and the head with them, by up to 40 degrees every stride: bent to the turn
# (FaceBend), the pictured face is still a face there, where the generator's own head is a mosaic, and a ramp that
# ended at 45 degrees faded the face out and in again every half stride.
TURN_FULL_DEG = 35.0
TURN_NONE_DEG = 55.0
# paste_weight: the share of the face landmarks' surface points that the target shows (all three vertices of each):
# at or above SHOWN_FULL the face is laid over fully, at or below SHOWN_NONE not at all. On woman_blue_tracksuit.jpg
# driven by the demo walk: 0.97-0.98 of them facing the camera, 0.53 turned by 90 degrees (where the turn alone
# fades the face out), none turned by 180; a hand held in front of her face hides 0.40 of them. The part a target
# does not show is cut out of the face (shown_face), so the rest of it is laid over fully.
SHOWN_FULL = 0.5
SHOWN_NONE = 0.3
# face_matte: the hull is shrunk by this share of the face's size (its outline runs through hair and background at
# the temples and the chin's edge) and feathered by a Gaussian of this share.
MATTE_SHRINK = 0.03
MATTE_FEATHER = 0.04
MIN_POINTS = 8  # fewer face vertices than this fit no affine map
# face_triangles: a hull triangle whose height is under this share of its longest side is a sliver, left out
SLIVER = 0.1


def face_matte(points: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) float32 in [0, 1]: the face inside the convex hull of its landmarks ``points`` (L, 2) pixels,
    shrunk by :data:`MATTE_SHRINK` and feathered by :data:`MATTE_FEATHER` of the face's size (the long side of the
    landmarks' box), 1 deep inside and 0 outside the hull."""
    pts = np.asarray(points, np.float64)
    size = float(np.max(pts.max(axis=0) - pts.min(axis=0)))
    hull = cv2.convexHull(np.round((pts - 0.5) * 16).astype(np.int32))  # OpenCV's pixel centres, 4 fractional bits
    mask = np.zeros(shape, np.uint8)
    cv2.fillConvexPoly(mask, hull, 255, lineType=cv2.LINE_AA, shift=4)
    mask = cv2.erode(mask, disc(MATTE_SHRINK * size))
    matte = mask.astype(np.float32) / 255.0
    sigma = max(0.5, MATTE_FEATHER * size)
    return cv2.GaussianBlur(matte, (0, 0), sigmaX=sigma, borderType=cv2.BORDER_CONSTANT)


def head_affine(ref_uv: np.ndarray, tgt_uv: np.ndarray) -> np.ndarray | None:
    """(2, 3) the least-squares affine map taking (P, 2) reference points onto (P, 2) target points; None with
    fewer than :data:`MIN_POINTS` points or a degenerate (collinear) set."""
    ref, tgt = np.asarray(ref_uv, np.float64), np.asarray(tgt_uv, np.float64)
    if len(ref) < MIN_POINTS:
        return None
    design = np.concatenate([ref, np.ones((len(ref), 1))], axis=1)  # (P, 3)
    solution, _, rank, _ = np.linalg.lstsq(design, tgt, rcond=None)
    if rank < 3:
        return None
    return solution.T  # (2, 3)


def affine_camera(points3d: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(2, 3) the affine camera taking ``points3d`` (P, 3) (a rigid head at rest) to their pictured pixels ``uv``
    (P, 2), both about their means, fitted by least squares."""
    p = np.asarray(points3d, np.float64)
    q = np.asarray(uv, np.float64)
    return np.linalg.lstsq(p - p.mean(axis=0), q - q.mean(axis=0), rcond=None)[0].T


def view_direction(points3d: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(3,) unit vector: the direction the camera looks along, in the axes of ``points3d`` (P, 3) (a rigid head at
    rest), from their pictured pixels ``uv`` (P, 2): :func:`camera_direction` of their :func:`affine_camera`."""
    return camera_direction(affine_camera(points3d, uv))


def camera_direction(camera: np.ndarray) -> np.ndarray:
    """(3,) unit vector: the direction an affine ``camera`` (2, 3) looks along, its two rows made orthonormal, their
    cross product (image y down, so it points from the camera into the scene)."""
    u, _, vt = np.linalg.svd(camera, full_matrices=False)
    rows = u @ vt  # nearest orthonormal rows
    d = np.cross(rows[0], rows[1])
    return d / np.linalg.norm(d)


def paste_weight(turn_deg: float, shown: float) -> float:
    """How much of the pictured face to lay over, in [0, 1]: 1 for a turn up to :data:`TURN_FULL_DEG` with at
    least :data:`SHOWN_FULL` of the face still shown, falling linearly to 0 at :data:`TURN_NONE_DEG` or
    :data:`SHOWN_NONE` (the product of the two ramps)."""
    by_turn = np.clip((TURN_NONE_DEG - turn_deg) / (TURN_NONE_DEG - TURN_FULL_DEG), 0.0, 1.0)
    by_shown = np.clip((shown - SHOWN_NONE) / (SHOWN_FULL - SHOWN_NONE), 0.0, 1.0)
    return float(by_turn * by_shown)


def compose_affine(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """(2, 3) the affine map ``outer(inner(x))``."""
    o = np.vstack([np.asarray(outer, np.float64), [0.0, 0.0, 1.0]])
    i = np.vstack([np.asarray(inner, np.float64), [0.0, 0.0, 1.0]])
    return (o @ i)[:2]


def pixel_index_affine(affine: np.ndarray) -> np.ndarray:
    """(2, 3) the map ``affine`` (continuous pixel coordinates, centres at +0.5) in OpenCV's pixel indices (centres
    at integers): ``y + 0.5 = M (x + 0.5) + t``."""
    a = np.array(affine, np.float64)
    a[:, 2] += a[:, :2] @ np.array([0.5, 0.5]) - 0.5
    return a


def paste_head(frame: np.ndarray, source: np.ndarray, matte: np.ndarray, affine: np.ndarray,
               weight: float, *, within: np.ndarray | None = None, bend: FaceBend | None = None) -> np.ndarray:
    """The frame with the source face laid over it.

    The source is first shrunk by area averaging to the map's scale when the map shrinks it (a photo at several
    times the output's resolution would otherwise alias), then warped bicubically by the rest of the map: laid back
    where it was, woman_blue_tracksuit.jpg's face is 35.8 dB from the reference picture over its core, against 33.2
    dB warped bilinearly (moved by a quarter pixel, 26-28 dB).

    Args:
        frame: (H, W, 3) uint8 a generated frame.
        source: (h, w, 3) uint8 the picture the face comes from; matte: (h, w) float in [0, 1] the face in it
            (:func:`face_matte`).
        affine: (2, 3) source pixels -> frame pixels.
        weight: in [0, 1] (:func:`paste_weight`); 0 returns the frame unchanged.
        within: (H, W) float in [0, 1] where the face may be laid, or None: the generated person's matte (a face from
            a three-quarter view, spread over a frontal head, reaches past its outline) times the part of the face
            the target shows (:func:`shown_face`).
        bend: the face's own shape change on top of ``affine`` (:class:`FaceBend`: a turned head's near cheek
            widens and its far cheek narrows, its nose moves farther than its ears), or None: ``affine`` alone.
    Returns:
        (H, W, 3) uint8, equal to ``frame`` wherever the warped matte times ``weight`` is 0.
    """
    frame = np.asarray(frame, np.uint8)
    if weight <= 0.0:
        return frame.copy()
    affine = pixel_index_affine(affine)
    scale = float(np.sqrt(abs(np.linalg.det(affine[:, :2]))))
    matte = np.asarray(matte, np.float32)
    ys, xs = np.nonzero(matte > 0)
    if len(xs) == 0:
        return frame.copy()
    # the matte's box only, 2 pixels grown: the rest of the picture is never laid over
    h, w = matte.shape
    sx0, sy0 = max(0, xs.min() - 2), max(0, ys.min() - 2)
    sx1, sy1 = min(w, xs.max() + 3), min(h, ys.max() + 3)
    source = np.asarray(source)[sy0:sy1, sx0:sx1]
    matte = matte[sy0:sy1, sx0:sx1]
    affine = compose_affine(affine, np.array([[1.0, 0.0, sx0], [0.0, 1.0, sy0]]))
    if scale < 1.0:  # shrink by area first, then warp the shrunk picture by affine o (shrunk -> source)
        h, w = matte.shape
        sw, sh = max(1, int(round(w * scale))), max(1, int(round(h * scale)))
        source = cv2.resize(source, (sw, sh), interpolation=cv2.INTER_AREA)
        matte = cv2.resize(matte, (sw, sh), interpolation=cv2.INTER_AREA)
        unshrink = np.array([[w / sw, 0.0, 0.0], [0.0, h / sh, 0.0]])
        # a pixel centre c of the shrunk image is (c + 0.5) * w / sw - 0.5 in the source
        unshrink[:, 2] = 0.5 * np.array([w / sw, h / sh]) - 0.5
        affine = compose_affine(affine, unshrink)
    # only the box the warped matte covers is warped and blended (a face is about 1% of a frame)
    height, width = frame.shape[:2]
    out = frame.copy()
    mh, mw = matte.shape
    corners = np.array([[-1, -1], [mw, -1], [-1, mh], [mw, mh]], np.float64) @ affine[:, :2].T + affine[:, 2]
    x0, y0 = np.maximum(np.floor(corners.min(axis=0)).astype(int) - 1, 0)
    x1, y1 = np.minimum(np.ceil(corners.max(axis=0)).astype(int) + 2, [width, height])
    if x1 <= x0 or y1 <= y0:
        return out
    box = affine.copy()
    box[:, 2] -= [x0, y0]
    size = (int(x1 - x0), int(y1 - y0))
    if bend is None:
        face = cv2.warpAffine(source, box, size, flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
        alpha = cv2.warpAffine(matte, box, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                               borderValue=0.0)
    else:  # each box pixel looks up the source where the affine map's inverse takes it, less the bend there
        grid = np.stack(np.meshgrid(np.arange(size[0], dtype=np.float64), np.arange(size[1], dtype=np.float64)), -1)
        moved = grid - bend_field(bend, (int(x0), int(y0), int(x1), int(y1)))
        back = cv2.invertAffineTransform(box)
        maps = (moved @ back[:, :2].T + back[:, 2]).astype(np.float32)
        face = cv2.remap(source, maps[..., 0], maps[..., 1], cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
        alpha = cv2.remap(matte, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                          borderValue=0.0)
    if within is not None:
        alpha = alpha * np.asarray(within, np.float32)[y0:y1, x0:x1]
    alpha = np.clip(alpha * float(weight), 0.0, 1.0)[..., None]
    under = frame[y0:y1, x0:x1].astype(np.float32)
    mixed = alpha * face.astype(np.float32) + (1.0 - alpha) * under
    out[y0:y1, x0:x1] = np.clip(np.rint(mixed), 0, 255).astype(np.uint8)
    return out


@dataclass(frozen=True)
class FaceBend:
    """How a moved face departs from its affine move: each landmark's offset from where the affine map puts it.

    The head's affine move (:func:`head_affine`) is its turn, scale and place; a head turned out of the picture plane
    also changes the face's shape, as its points lie at different depths: the nose moves farther than the ears, the
    near cheek widens and the far one narrows. The offsets, spread between the landmarks, bend the pasted face to
    that shape (a piecewise-affine warp over the landmarks, :func:`bend_field`).

    Attributes:
        points: (L, 2) the landmarks where the target has them, frame pixels (the affine map's place plus
            ``offsets``).
        offsets: (L, 2) each landmark's offset from the affine map's place, pixels.
    """

    points: np.ndarray
    offsets: np.ndarray


def bend_field(bend: FaceBend, box: tuple[int, int, int, int]) -> np.ndarray:
    """(y1 - y0, x1 - x0, 2) float64: the bend at each pixel centre of the frame's box (x0, y0, x1, y1).

    Inside the landmarks' hull it is the offsets interpolated linearly over the Delaunay triangles of the landmarks'
    places (SciPy's ``LinearNDInterpolator``: the triangles never overlap, even where a turned face folds its far
    cheek over, and each pixel's centre is found in the triangle that holds it); outside the hull it is the bend of
    the nearest pixel inside (the matte's feather reaches a little past it), and zero when the hull misses the box.
    """
    from scipy.interpolate import LinearNDInterpolator

    x0, y0, x1, y1 = box
    h, w = y1 - y0, x1 - x0
    centres = np.stack(np.meshgrid(np.arange(x0, x1) + 0.5, np.arange(y0, y1) + 0.5), axis=-1).reshape(-1, 2)
    field = LinearNDInterpolator(np.asarray(bend.points, np.float64),
                                 np.asarray(bend.offsets, np.float64))(centres).reshape(h, w, 2)
    inside = np.isfinite(field[..., 0])
    if not inside.any():
        return np.zeros((h, w, 2))
    if not inside.all():  # each pixel outside takes the bend of the nearest pixel inside
        _, nearest = cv2.distanceTransformWithLabels((~inside).astype(np.uint8), cv2.DIST_L2, 5,
                                                     labelType=cv2.DIST_LABEL_PIXEL)
        ys, xs = np.nonzero(inside)
        by_label = np.zeros((nearest.max() + 1, 2))
        by_label[nearest[ys, xs]] = field[ys, xs]
        field = by_label[nearest]
    return field


def lay_moved_face(frame: np.ndarray, source: np.ndarray, matte: np.ndarray, affine: np.ndarray, moved: np.ndarray,
                   offsets: np.ndarray, triangles: np.ndarray, shown: np.ndarray, weight: float, *,
                   within: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 3) uint8 ``frame`` with a face laid over the part of it the target shows: ``source`` (h, w, 3) and its
    ``matte`` moved by ``affine`` (2, 3) (source pixels -> frame pixels) and bent by ``offsets`` (L, 2)
    (:class:`FaceBend`), cut to the triangles (:func:`shown_face`, ``triangles`` (T, 3), ``shown`` (L,) bool) of its
    landmarks, ``moved`` (L, 2) where ``affine`` puts them in the frame, bent, and to ``within`` (H, W) float in
    [0, 1] (the generated person's matte) or None (:func:`paste_head` with ``weight``). The one way ``synthesize``
    and the reconstruction protocol lay the pictured face."""
    where = np.asarray(moved, np.float64) + offsets
    cover = shown_face(where, triangles, shown, frame.shape[:2])
    within = cover if within is None else cover * np.asarray(within, np.float32)
    return paste_head(frame, source, matte, affine, weight, within=within, bend=FaceBend(where, offsets))


def head_squares(points: np.ndarray, size: int, *, scale: float, min_side: float) -> np.ndarray:
    """(N, S, S) bool: the head of each of (N, 17, 2) canonical joints (pixels), a square centred between the neck
    and head joints, its side ``scale`` times the thorax-to-head distance and at least ``min_side`` pixels, clipped
    to the (S, S) frame."""
    from motion2video.core.skeletons import HEAD, NECK, THORAX

    pts = np.asarray(points, np.float64)
    centre = 0.5 * (pts[:, NECK] + pts[:, HEAD])  # (N, 2)
    side = np.maximum(scale * np.linalg.norm(pts[:, HEAD] - pts[:, THORAX], axis=-1), min_side)
    grid = np.arange(size) + 0.5  # pixel centres
    lo, hi = centre - side[:, None] / 2, centre + side[:, None] / 2  # (N, 2)
    inside_x = (grid[None] >= lo[:, :1]) & (grid[None] < hi[:, :1])  # (N, S)
    inside_y = (grid[None] >= lo[:, 1:]) & (grid[None] < hi[:, 1:])
    return inside_y[:, :, None] & inside_x[:, None, :]


def joint_head_axes(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The head's axes and origin from canonical H36M-17 joints: up from the thorax joint to the head joint, left the
    mean of the directions from the right shoulder to the left one and from the right hip to the left one (made
    square to up), and their cross product; the origin at the head joint. The joints do not say where the head
    looks. The thorax, not the neck joint: the neck-to-head segment is some 10 cm long, and in a sampled walk it
    tilted by up to 36 degrees and swung around the vertical, so the face faded out every stride. Shoulders and hips:
    they swing against each other in a walk, while a walker's head keeps its course.

    Args:
        joints: (..., 17, 3) world joints, metres.
    Returns:
        axes (..., 3, 3) whose columns are left, up x left, up; origins (..., 3).
    """
    from motion2video.core.skeletons import HEAD, L_HIP, L_SHOULDER, R_HIP, R_SHOULDER, THORAX

    j = np.asarray(joints, np.float64)
    up = j[..., HEAD, :] - j[..., THORAX, :]
    up = up / np.linalg.norm(up, axis=-1, keepdims=True)

    def unit(v: np.ndarray) -> np.ndarray:
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    left = unit(j[..., L_SHOULDER, :] - j[..., R_SHOULDER, :]) + unit(j[..., L_HIP, :] - j[..., R_HIP, :])
    left = left - np.sum(left * up, axis=-1, keepdims=True) * up
    left = left / np.linalg.norm(left, axis=-1, keepdims=True)
    return np.stack([left, np.cross(up, left), up], axis=-1), j[..., HEAD, :]


def rigid_head(points: np.ndarray, normals: np.ndarray, rest_joints: np.ndarray, joints: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """A head at rest carried rigidly by the head's axes of each pose (:func:`joint_head_axes`): where a body posed
    by 2D-lifted or 3D joints alone puts it, without a mesh.

    Args:
        points: (P, 3) the head's points at rest; normals: (P, 3) their surface normals at rest.
        rest_joints: (17, 3) the rest pose's joints; joints: (N, 17, 3) the poses.
    Returns:
        points (N, P, 3) and normals (N, P, 3) in each pose.
    """
    rest_axes, rest_origin = joint_head_axes(rest_joints)
    axes, origins = joint_head_axes(joints)  # (N, 3, 3), (N, 3)
    turn = axes @ rest_axes.T  # (N, 3, 3) rest -> pose
    moved = np.einsum("nij,pj->npi", turn, np.asarray(points, np.float64) - rest_origin) + origins[:, None]
    return moved, np.einsum("nij,pj->npi", turn, np.asarray(normals, np.float64))


@dataclass(frozen=True)
class HeadMoves:
    """Where the pictured face goes in N targets (:func:`head_moves`).

    Attributes:
        affines: (N, 2, 3) reference pixels -> target pixels, the head's move (the identity where none fits).
        weights: (N,) in [0, 1] how much of the face each target takes (0 where no map fits).
        shown: (N, L) bool: the target shows the surface point of each of the face's L landmarks.
        offsets: (N, L, 2) each landmark's offset in the target from where the affine map puts it, pixels: the
            face's shape change (:class:`FaceBend`); zero where no map fits.
    """

    affines: np.ndarray
    weights: np.ndarray
    shown: np.ndarray
    offsets: np.ndarray


def face_triangles(points: np.ndarray) -> np.ndarray:
    """(T, 3) int triangles over a face's landmarks: the Delaunay triangulation of their points at rest ``points``
    (L, 3) seen from the front (projected onto the plane of their two largest principal axes), each listed
    counter-clockwise in that plane, without the hull's slivers (a triangle whose height is under :data:`SLIVER` of
    its longest side)."""
    from scipy.spatial import Delaunay

    p = np.asarray(points, np.float64)
    p = p - p.mean(axis=0)
    flat = p @ np.linalg.svd(p, full_matrices=False)[2][:2].T  # (L, 2)
    triangles = Delaunay(flat).simplices.astype(np.int64)
    area = signed_areas(flat, triangles)
    triangles[area < 0] = triangles[area < 0][:, ::-1]
    longest = np.max([np.linalg.norm(flat[triangles[:, a]] - flat[triangles[:, b]], axis=-1)
                      for a, b in ((0, 1), (1, 2), (2, 0))], axis=0)
    return triangles[2 * np.abs(area) / longest >= SLIVER * longest]


def signed_areas(xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(T,) signed areas of ``triangles`` (T, 3) over points ``xy`` (L, 2); positive counter-clockwise in (x, y)."""
    a, b, c = (np.asarray(xy, np.float64)[triangles[:, k]] for k in range(3))
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def lone_hidden(shown: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(L,) bool: the landmarks ``shown`` (L,) bool says are hidden whose every neighbour in ``triangles`` (T, 3) is
    shown. What hides part of a face (a hand, the far cheek of a turn) hides landmarks side by side; one hidden among
    shown ones is the render's depth test, steep across a pixel on a small head (1-5 of a face's 468 in each frame
    of a sampled walk), and cutting its triangles out punched a hole in the face."""
    shown = np.asarray(shown, bool)
    tri = np.asarray(triangles, np.int64)
    hidden_beside = np.zeros(len(shown), bool)  # a landmark with a hidden neighbour in one of its triangles
    for a, b in ((0, 1), (1, 2), (2, 0)):
        np.logical_or.at(hidden_beside, tri[:, a], ~shown[tri[:, b]])
        np.logical_or.at(hidden_beside, tri[:, b], ~shown[tri[:, a]])
    in_triangles = np.zeros(len(shown), bool)
    in_triangles[tri.ravel()] = True
    return ~shown & ~hidden_beside & in_triangles


def shown_face(points: np.ndarray, triangles: np.ndarray, shown: np.ndarray, shape: tuple[int, int]
               ) -> np.ndarray:
    """(H, W) float32 in [0, 1]: the part of a moved face a target shows. The face's triangles (:func:`face_triangles`)
    at its landmarks ``points`` (L, 2) in the target's pixels are drawn where the target shows their three landmarks
    (``shown`` (L,) bool: not behind a hand or an arm, not on the far side of a turned head; a lone hidden landmark
    counts as shown, :func:`lone_hidden`) and they face the way most of them face (a triangle folded over in the
    picture is the far cheek of a three-quarter face); the rest is left to the generator. The edges the hidden
    triangles leave are feathered by :data:`MATTE_FEATHER` of the face's size."""
    pts = np.asarray(points, np.float64)
    triangles = np.asarray(triangles, np.int64)
    area = signed_areas(pts, triangles)
    front = 1.0 if np.sum(area > 0) >= np.sum(area < 0) else -1.0
    shown = np.asarray(shown, bool) | lone_hidden(shown, triangles)
    drawn = shown[triangles].all(axis=1) & (area * front > 1e-6)
    if drawn.all():
        return np.ones(shape, np.float32)  # nothing hidden: the matte alone outlines the face
    cover = np.zeros(shape, np.float32)
    corners = np.round((pts - 0.5) * 16).astype(np.int32)  # OpenCV's pixel centres, 4 fractional bits
    for tri in triangles[drawn]:
        cv2.fillConvexPoly(cover, corners[tri], 1.0, lineType=cv2.LINE_8, shift=4)
    sigma = max(0.5, MATTE_FEATHER * float(np.ptp(pts, axis=0).max()))
    return cover * cv2.GaussianBlur(cover, (0, 0), sigmaX=sigma, borderType=cv2.BORDER_CONSTANT)


def head_moves(face_xy: np.ndarray, face_points: np.ndarray, face_vertices: np.ndarray, face_weights: np.ndarray,
               ref_uv: np.ndarray, tgt_uv: np.ndarray, tgt_visible: np.ndarray, *, head_points: np.ndarray,
               head_vertices: np.ndarray) -> HeadMoves:
    """Where the pictured face goes in every target, and how much of it to lay over.

    The face's landmarks have their points on the body mesh's head (the face mesh's correspondence with Anny,
    :mod:`motion2video.pose.face_anny`): the affine map of those points from the reference mesh onto each target mesh
    (:func:`head_affine`) moves the face. The map is the head's move, not a fit of the pictured face onto the
    mesh's: a fitted head is seldom the pictured one's size and place (on ``dancer.avi`` at 128 px, mapping her
    landmarks onto the mesh's stretched her 10 px face to 15 and raised its brow 5 px). How far the target's head is
    turned from the pictured face (:func:`view_direction`, both against the same head at rest) and how many of the
    landmarks' surface points the target shows give the weight (:func:`paste_weight`); which of them it shows says
    where the face may be laid (:func:`shown_face`). The face's bend (:class:`FaceBend`) is what no affine map takes
    of the change from the pictured view to the target's: the face's points at rest seen through the affine camera
    of the pictured landmarks and through that of the target's head (:func:`affine_camera`), so it is the turn's
    alone, whatever the fitted head's own place in the reference.

    Args:
        face_xy: (L, 2) the face's landmarks in the reference picture's pixels (the pictured view of the head).
        face_points: (L, 3) their points on the head at rest, metres; face_vertices: (L, 3) int the mesh vertices
            each point lies between; face_weights: (L, 3) its barycentric weights.
        ref_uv: (V, 2) the body mesh's vertices in the reference, its pixels (where the reference samples them).
        tgt_uv: (N, V, 2) the body mesh's vertices in each target, pixels; tgt_visible: (N, V) bool shown there.
        head_points: (P, 3) the head's vertices at rest, metres; head_vertices: (P,) int their indices.
    Returns:
        the :class:`HeadMoves` of the N targets.
    """
    face_xy = np.asarray(face_xy, np.float64)
    face_vertices = np.asarray(face_vertices, np.int64)
    face_weights = np.asarray(face_weights, np.float64)
    pictured_camera = affine_camera(face_points, face_xy)
    pictured = camera_direction(pictured_camera)
    on_ref = np.einsum("lkd,lk->ld", np.asarray(ref_uv, np.float64)[face_vertices], face_weights)  # (L, 2)
    face_at_rest = np.asarray(face_points, np.float64) - np.mean(face_points, axis=0)
    as_pictured = face_at_rest @ pictured_camera.T  # (L, 2) the face's points seen as pictured
    n = len(tgt_uv)
    affines = np.repeat(np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]), n, axis=0)
    offsets = np.zeros((n, len(face_xy), 2))
    weights = np.zeros(n)
    landmark_shown = np.zeros((n, len(face_xy)), bool)
    for i in range(n):
        uv = np.asarray(tgt_uv[i], np.float64)
        landmarks = np.einsum("lkd,lk->ld", uv[face_vertices], face_weights)  # (L, 2)
        affine = head_affine(on_ref, landmarks)
        if affine is None:
            continue
        affines[i] = affine
        camera = affine_camera(head_points, uv[head_vertices])
        as_seen = face_at_rest @ camera.T  # ... and seen as the target sees them
        shape = head_affine(as_pictured, as_seen)
        if shape is not None:
            offsets[i] = as_seen - (as_pictured @ shape[:, :2].T + shape[:, 2])
        turn = float(np.degrees(np.arccos(np.clip(pictured @ camera_direction(camera), -1.0, 1.0))))
        landmark_shown[i] = np.asarray(tgt_visible[i], bool)[face_vertices].all(axis=1)
        weights[i] = paste_weight(turn, float(np.mean(landmark_shown[i])))
    return HeadMoves(affines, weights, landmark_shown, offsets)
