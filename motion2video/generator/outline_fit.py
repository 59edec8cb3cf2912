"""The fitted body's surface moved onto the pictured person's outline.

Anny posed by a picture's joints, with its weight fitted to the person's mask
(:func:`motion2video.generator.mesh_fit.fit_width`), has a body model's build, not the person's: loose clothes
and hair reach past it on one side, a slim arm lies inside it on the other. Photo Wake-Up (Weng et al., CVPR 2019)
fits its body mesh to the person's silhouette as well as to the skeleton; here the same is done on the mesh itself:

1. **Measured on the outline.** Each vertex the reference picture shows on the fitted silhouette's outline (within
   :data:`OUTLINE_PX`) is given the signed distance from it to the person's outline (:func:`outline_offsets`):
   positive where the person reaches past the body, negative where the body reaches past the person.
2. **Spread over the surface.** The measured distances are spread over the whole surface by averaging over the
   mesh's edges (:func:`spread_over_mesh`), so the back and the sides the picture does not show take the offsets of
   the outline beside them, and a few more rounds smooth them.
3. **Carried by the skinning.** In metres (:func:`pixels_per_metre`), clipped to [-:data:`MAX_IN_M`,
   :data:`MAX_OUT_M`], each vertex moves along its rest normal (:func:`surface_offsets`); posed by the skinning, the
   body keeps the person's outline in every frame. The head and the forearms keep their shape (:func:`kept_shape`).

Masks are (S, S) bool; vertex positions in pixels, x right, y down, the origin at the top-left corner of the top-left
pixel (its centre at (0.5, 0.5)).
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.ndimage import distance_transform_edt, map_coordinates
from scipy.spatial import cKDTree

# a vertex within this many pixels of the fitted silhouette's outline measures the person's outline beside it
OUTLINE_PX = 1.0
# a vertex farther than this from the person's outline (pixels at 128 px, scaled with the size) does not measure
# the body's surface: long hair over a shoulder, the gap between an arm and the waist that the segmentation fills,
# a bag, a limb the fit put beside the pictured one
MAX_MEASURED_PX = 4.0
# the bones whose vertices keep the body model's shape (kept_shape), besides the head's
KEPT_BONES = ("lowerarm", "wrist", "metacarpal", "finger")
# how far a vertex may move along its normal, outwards and inwards: loose clothes and hair reach some centimetres
# past a body model; a segmentation's edge is a pixel or two inside the person
MAX_OUT_M = 0.08
MAX_IN_M = 0.03
# a body fitted to the outline and posed by joints estimated in other frames of a video (the reconstruction
# protocol) is grown by this many pixels (at 128 px, scaled with the size): it lies a pixel or two beside the person
# there, and a pixel of the person's colour beside them costs less than a pixel of the background inside them
# (dancer.avi, evaluate-frames --video at 128: grown by 0 / 1 / 2 px, person PSNR 18.41 / 20.52 / 21.58 dB, L1 0.0156
# / 0.0162 / 0.0183; copy-reference's L1 0.0169)
GROW_PX = 1.0
# a body whose weight fit already covers the person this well (intersection over union of the silhouette and the
# mask) is left as it is: an Anny render's (make demo's reference, 0.957) differs from its segmentation by the
# segmentation's own blur, and moving its surface by a pixel changed which of a hand and the thigh it touches some
# vertices sample; the six photos of ../shared/data/photos measured 0.69-0.85 (docs/results.md), dancer.avi 0.77
FIT_IOU = 0.9
# rounds of averaging over the mesh's edges: to fill the surface from the outline, then to smooth it
SPREAD_ROUNDS = 300
SMOOTH_ROUNDS = 10


def outline_margin(size: int) -> int:
    """Pixels by which every silhouette of a body fitted to a video's person outline is grown when its frames are
    posed by their estimated joints, at an image side of ``size`` (:data:`GROW_PX` at 128, scaled)."""
    return max(1, int(round(GROW_PX * size / 128)))


def signed_distance(mask: np.ndarray) -> np.ndarray:
    """(S, S) float: each pixel's distance to the mask's outline, pixels, positive inside and negative outside
    (a pixel on either side of the outline is half a pixel from it)."""
    mask = np.asarray(mask, bool)
    return np.where(mask, distance_transform_edt(mask) - 0.5, 0.5 - distance_transform_edt(~mask))


def outline_offsets(uv: np.ndarray, fitted: np.ndarray, person: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far the person's outline lies past each vertex on the fitted silhouette's outline.

    Args:
        uv: (V, 2) the vertices in the reference, pixels; fitted: (S, S) bool the fitted body's silhouette there;
            person: (S, S) bool the person's mask.
    Returns:
        offsets (V,) pixels, positive where the person reaches past the body, and measured (V,) bool: the vertex
        lies within :data:`OUTLINE_PX` of the fitted outline (elsewhere the offset is 0).
    """
    uv = np.asarray(uv, np.float64)
    at = [uv[:, 1] - 0.5, uv[:, 0] - 0.5]  # array coordinates (row, column) of each vertex
    to_fitted = map_coordinates(signed_distance(fitted), at, order=1, mode="nearest")
    to_person = map_coordinates(signed_distance(person), at, order=1, mode="nearest")
    size = np.array(np.asarray(fitted).shape[::-1], np.float64)
    measured = (np.abs(to_fitted) <= OUTLINE_PX) & (uv >= 0).all(axis=1) & (uv < size).all(axis=1)
    return np.where(measured, to_person - to_fitted, 0.0), measured


def mesh_neighbours(triangles: np.ndarray, count: int) -> sparse.csr_matrix:
    """(V, V) sparse: each vertex's row averages its neighbours along the edges of ``triangles`` (T, 3)."""
    t = np.asarray(triangles, np.int64)
    a = np.concatenate([t[:, 0], t[:, 1], t[:, 2], t[:, 1], t[:, 2], t[:, 0]])
    b = np.concatenate([t[:, 1], t[:, 2], t[:, 0], t[:, 0], t[:, 1], t[:, 2]])
    adjacency = sparse.csr_matrix((np.ones(len(a)), (a, b)), shape=(count, count))
    adjacency.data[:] = 1.0  # an edge shared by two triangles counts once
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    return sparse.diags(1.0 / np.maximum(degree, 1.0)) @ adjacency


def spread_over_mesh(values: np.ndarray, known: np.ndarray, triangles: np.ndarray, points: np.ndarray
                     ) -> np.ndarray:
    """(V,) ``values`` known at ``known`` (V,) bool spread over the whole surface: the unknown vertices take the
    average of their neighbours, round after round (:data:`SPREAD_ROUNDS`, starting from the known values' mean),
    then every vertex is smoothed (:data:`SMOOTH_ROUNDS`). Parts of the mesh no edge joins to a known vertex (the
    eyes, the teeth) take the value of the nearest vertex that has one, by ``points`` (V, 3)."""
    values = np.asarray(values, np.float64)
    known = np.asarray(known, bool)
    if not known.any():
        return np.zeros(len(values))
    average = mesh_neighbours(triangles, len(values))
    reached = known.copy()
    x = np.where(known, values, values[known].mean())
    for _ in range(SPREAD_ROUNDS):
        x = np.where(known, values, average @ x)
        reached = reached | (average @ reached.astype(np.float64) > 0)
    for _ in range(SMOOTH_ROUNDS):
        x = average @ x
    if not reached.all():
        tree = cKDTree(np.asarray(points, np.float64)[reached])
        x[~reached] = x[reached][tree.query(np.asarray(points, np.float64)[~reached])[1]]
    return x


def kept_shape() -> np.ndarray:
    """(V,) bool: the vertices the outline fit leaves where the body model puts them (:data:`KEPT_BONES`): the head
    (the face is put on the pictured eyes, and hair is no skull) and the forearms with the hands (a hand holding
    something, or hanging against the hip, widens the outline there; moved out to it, the forearm became a thick
    skin-coloured blob across the chest whenever a target swung it in front of the body: three_walking.jpg)."""
    from renderers import anny_model

    names = anny_model.bone_names()
    kept = np.array([name.startswith(KEPT_BONES) for name in names])
    return anny_model.head_vertices() | kept[anny_model.dominant_bones()]


def pixels_per_metre(camera, point: np.ndarray, scale: float) -> float:
    """Pixels per metre at the depth of world ``point`` (3,) seen by ``camera``, its pixels scaled by ``scale`` (as a
    track's transform scales them)."""
    forward = camera.axes()[2]
    depth = float(np.dot(np.asarray(point, np.float64) - np.asarray(camera.position, np.float64), forward))
    return float(camera.focal * scale / depth)


def surface_offsets(uv: np.ndarray, fitted: np.ndarray, person: np.ndarray, *, rest, per_metre: float
                    ) -> np.ndarray:
    """(V, 3) metres: each rest vertex's move along its rest normal that puts the fitted body's outline on the
    person's (:func:`outline_offsets` spread by :func:`spread_over_mesh`, clipped to [-:data:`MAX_IN_M`,
    :data:`MAX_OUT_M`]).

    Args:
        uv: (V, 2) the posed vertices in the reference, pixels; fitted: (S, S) bool their silhouette; person: (S, S)
            bool the person's mask.
        rest: the body's :class:`renderers.anny_model.AnnyRest`; per_metre: pixels per metre at the body's depth in
            the reference (:func:`pixels_per_metre`).
    """
    from renderers import anny_model
    from renderers.mesh import vertex_normals

    offsets, measured = outline_offsets(uv, fitted, person)
    measured &= np.abs(offsets) <= MAX_MEASURED_PX * np.asarray(person).shape[0] / 128
    kept = kept_shape()
    offsets[kept] = 0.0
    triangles = anny_model.triangles()
    spread = spread_over_mesh(offsets / per_metre, measured | kept, triangles, rest.vertices)
    spread[kept] = 0.0  # after the smoothing too
    normals = vertex_normals(rest.vertices, triangles).astype(np.float64)
    return np.clip(spread, -MAX_IN_M, MAX_OUT_M)[:, None] * normals
