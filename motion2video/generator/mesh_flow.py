"""Dense correspondence between two renders of the same body mesh: where each target pixel's surface point
was in the reference frame, and whether the reference shows it.

The mesh generator (:mod:`motion2video.generator.mesh_warp`) moves the reference person along this flow
instead of along per-limb transforms of 2D keypoints (the idea of Liquid Warping GAN, Liu et al. 2019, and
Dense Pose Transfer, Neverova et al. 2018): the mesh carries limb twist, foreshortening and which side of a
limb faces the camera, which 2D keypoints do not.

Both frames are renders of one mesh topology (Anny's 13,718 vertices), so a vertex index is a surface point.
Per frame we keep each vertex's projected pixel position and whether it is the front surface there (its depth
against the rendered depth map, :func:`renderers.mesh.vertex_visibility`). For a pair, every target silhouette pixel
takes the inverse-squared-distance-weighted reference positions of its ``k`` nearest *visible* target vertices
(:func:`dense_flow`, a KD-tree from SciPy), leaving out those whose reference position disagrees with the nearest
one's (a fold: averaging would land between the two surfaces); the weights of the same vertices' reference
visibility give the visibility map. At 128 px a body shows about one visible vertex per pixel, so the interpolation
error is below a pixel away from occlusion edges.

Since 2026-11-27 the generators read the flow from the target's triangles where they can (``triangles``: each pixel
whose centre lies in a triangle with all three corners shown takes the barycentric mix of their reference pixels,
:func:`triangle_pixels`), which is exact for a surface that moves affinely within a triangle, where the nearest
vertices' weighted mean is exact only at the vertices. Triangles that join surface points the reference shows far
apart are left to the vertices, by the same fold rule (:func:`across_a_fold`). Where the chin's underside meets the
neck, the nearest-vertex rule alternated pixel by pixel between the two sides of the reference's jaw crease and drew
the jaw line as a row of dashes; a triangle joins them smoothly.

Pixel coordinates follow :func:`motion2video.core.camera.project`: x right, y down, pixel centres at
integer + 0.5.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

NEIGHBOURS = 4  # target vertices interpolated per pixel
BAND_PX = 4  # the flow is carried this far outside the silhouette (at 128 px; extend_flow)
WEIGHT_EPS_PX = 0.1  # Shepard's inverse-distance weights 1 / (d^2 + eps^2): a vertex at the pixel dominates
# A pixel's neighbours are averaged only where their reference pixels agree with its nearest vertex's: within
# AGREE_PX (at 128 px; scaled with the image) or AGREE_STRETCH times their distance in the target. Neighbours across
# a fold (a turned leg's front and side, which the reference shows 30 px apart, or surface points completed from two
# sides) would otherwise average to a reference pixel between them: the background between the legs, the white dots
# along turned shins.
AGREE_PX = 2.0
AGREE_STRETCH = 3.0


@dataclass
class MeshFlow:
    """The correspondence of one (reference, target) pair.

    Attributes:
        flow: (H, W, 2) float32 reference pixel coordinates of each target pixel's surface point (inside the
            target silhouette; the pixel's own centre outside it, i.e. the background stays).
        visibility: (H, W) float32 in [0, 1], how much of that surface point the reference shows (0 outside
            the silhouette).
        silhouette: (H, W) bool, the target pixels covered by the mesh.
    """

    flow: np.ndarray
    visibility: np.ndarray
    silhouette: np.ndarray


@dataclass
class MeshTrack:
    """A body or head mesh seen over frames, in the pixels of one image.

    Attributes:
        uv: (N, V, 2) float32 vertex pixel positions.
        visible: (N, V) bool front-surface flags.
        masks: (N, h, w) bool silhouettes.
    """

    uv: np.ndarray
    visible: np.ndarray
    masks: np.ndarray


def pixel_centres(mask: np.ndarray) -> np.ndarray:
    """(M, 2) float (x + 0.5, y + 0.5) of the True pixels of an (H, W) mask, row-major order."""
    ys, xs = np.nonzero(mask)
    return np.stack([xs + 0.5, ys + 0.5], axis=1).astype(np.float64)


def identity_flow(height: int, width: int) -> np.ndarray:
    """(H, W, 2) float32 pixel centres: the flow that leaves every pixel where it is."""
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    return np.stack([xs + 0.5, ys + 0.5], axis=-1)


@lru_cache(maxsize=1)
def surface_graph():
    """Anny's mesh as a sparse graph (13,718 vertices, edges weighted by their rest-pose length in metres): the
    body and the face renders share its vertex index."""
    from scipy.sparse import coo_matrix

    from renderers import anny_model

    faces = anny_model.triangles()
    rest = anny_model.anny_rest().vertices
    a = np.concatenate([faces[:, 0], faces[:, 1], faces[:, 2]])
    b = np.concatenate([faces[:, 1], faces[:, 2], faces[:, 0]])
    w = np.linalg.norm(rest[a] - rest[b], axis=1) + 1e-6
    n = len(rest)
    return coo_matrix((np.concatenate([w, w]), (np.concatenate([a, b]), np.concatenate([b, a]))), shape=(n, n)).tocsr()


# Completion sources (:func:`touching_other_part`): a shown vertex within DOUBT_RADIUS_PX pixels of a shown vertex
# more than DOUBT_APART_M metres from it on the body at rest is not one.
DOUBT_RADIUS_PX = 1.0
DOUBT_APART_M = 0.10


def touching_other_part(uv: np.ndarray, seen: np.ndarray, *, radius_px: float | None = None,
                        apart: float | None = None) -> np.ndarray:
    """Shown vertices that touch another body part in the picture: within ``radius_px`` pixels of a shown vertex
    more than ``apart`` metres away from it on Anny's body at rest.

    Where a hand rests beside a thigh, the thigh's vertices at the hand's pixels pass the depth test (the hand is
    within its tolerance) and show the hand. Which of the two is in front, the 2D test does not say, so both are
    left out as sources of :func:`complete_reference_uv`: on the demo's reference, the hidden trousers vertices
    that took a skin pixel went from 61 to 18 (``tests/test_mesh_sampling_edges.py``).

    Args:
        uv: (V, 2) reference pixels; seen: (V,) bool shown by the reference.
    Returns:
        (V,) bool, a subset of ``seen``.
    """
    from renderers import anny_model

    radius_px = DOUBT_RADIUS_PX if radius_px is None else radius_px
    apart = DOUBT_APART_M if apart is None else apart
    if apart <= 0:
        return np.zeros(len(uv), bool)
    a, b = shown_pairs(uv, seen, radius_px)
    rest = anny_model.anny_rest().vertices
    return in_pairs(len(uv), a, b, np.linalg.norm(rest[a] - rest[b], axis=1) > apart)


def shown_pairs(uv: np.ndarray, seen: np.ndarray, radius_px: float) -> tuple[np.ndarray, np.ndarray]:
    """Every pair of shown vertices within ``radius_px`` pixels of each other in the picture (a KD-tree from
    SciPy): uv (V, 2), seen (V,) bool -> vertex ids a (P,), b (P,) int64 (empty with fewer than two shown)."""
    from scipy.spatial import cKDTree

    shown = np.flatnonzero(seen)
    if len(shown) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    pairs = cKDTree(np.asarray(uv, np.float64)[shown]).query_pairs(radius_px, output_type="ndarray")
    pairs = pairs.reshape(-1, 2)
    return shown[pairs[:, 0]], shown[pairs[:, 1]]


def in_pairs(count: int, a: np.ndarray, b: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """(count,) bool: the vertices that are either end of a chosen pair (a, b (P,) vertex ids; chosen (P,) bool)."""
    out = np.zeros(count, bool)
    out[a[chosen]] = True
    out[b[chosen]] = True
    return out


@lru_cache(maxsize=1)
def region_graph():
    """:func:`surface_graph` with only the edges inside one clothing region (skin, top, trousers, shoes, hair, ...:
    :func:`renderers.anny_model.vertex_regions`), and each vertex's region."""
    from scipy.sparse import coo_matrix

    from renderers import anny_model

    graph = surface_graph().tocoo()
    regions = anny_model.vertex_regions()
    keep = regions[graph.row] == regions[graph.col]
    inside = coo_matrix((graph.data[keep], (graph.row[keep], graph.col[keep])), shape=graph.shape).tocsr()
    return inside, regions


def _nearest_sources(graph, sources: np.ndarray) -> np.ndarray:
    """(V,) the nearest of ``sources`` along ``graph`` for every vertex (-1 where none is reachable)."""
    from scipy.sparse.csgraph import dijkstra

    if len(sources) == 0:
        return np.full(graph.shape[0], -1, np.int64)
    _, _, nearest = dijkstra(graph, directed=False, indices=sources, min_only=True, return_predecessors=True)
    return nearest


# A shown vertex is a completion source of its own region (:func:`complete_reference_uv`) only where its pixel's
# colour lies within max(COLOUR_MIN, COLOUR_SPREAD x the median distance) of the region's median colour (RGB, 0-255):
# the vertices along a region's outline show the arm, the neck or the background beside it in part, and they are the
# nearest sources of the whole hidden side (27% of the demo person's hidden shirt vertices took a skin pixel from them).
# Since 2026-11-27 every pixel of the source's bilinear footprint must be typical, not only the one it lies in.
COLOUR_MIN = 60.0
COLOUR_SPREAD = 3.0
COLOUR_MIN_SOURCES = 20  # regions showing fewer vertices keep them all


def pixel_indices(xy: np.ndarray, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The pixel each of the (N, 2) points lies in (pixel centres at integer + 0.5): rows, cols (N,) int64, clipped
    to the image."""
    xy = np.asarray(xy, np.float64)
    cols = np.clip(np.floor(xy[:, 0]).astype(np.int64), 0, width - 1)
    rows = np.clip(np.floor(xy[:, 1]).astype(np.int64), 0, height - 1)
    return rows, cols


def bilinear_footprint(xy: np.ndarray, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The four pixels a bilinear sample at each of the (N, 2) points reads (pixel centres at integer + 0.5):
    rows, cols (N, 4) int64, clipped to the image."""
    x0 = np.floor(np.asarray(xy[:, 0], np.float64) - 0.5).astype(np.int64)
    y0 = np.floor(np.asarray(xy[:, 1], np.float64) - 0.5).astype(np.int64)
    cols = np.clip(np.stack([x0, x0 + 1, x0, x0 + 1], axis=1), 0, width - 1)
    rows = np.clip(np.stack([y0, y0, y0 + 1, y0 + 1], axis=1), 0, height - 1)
    return rows, cols


LIMB_SEGMENTS = ("upperleg", "lowerleg", "upperarm", "lowerarm")  # colour_groups: bone-name prefixes of a limb's parts
SEGMENT_SPLIT_COLOUR = 100.0  # colour_groups: a segment this far (RGB) from the rest of its region is a garment apart


@lru_cache(maxsize=1)
def limb_segments() -> np.ndarray:
    """(V,) int64: 1 + the index in :data:`LIMB_SEGMENTS` of each vertex's dominant bone's limb part (both sides
    together), 0 for the trunk, head, hands and feet."""
    from renderers import anny_model

    names = anny_model.bone_names()
    of_bone = np.array([next((i + 1 for i, p in enumerate(LIMB_SEGMENTS) if n.startswith(p)), 0) for n in names],
                       np.int64)
    segments = of_bone[anny_model.dominant_bones()]
    segments.setflags(write=False)
    return segments


def colour_groups(ref_uv: np.ndarray, sources: np.ndarray, image: np.ndarray) -> np.ndarray:
    """(V,) int64: the group whose typical colour each vertex's completion sources are judged by
    (:func:`typical_colour_sources`): its clothing region, with a limb segment of the clothes (the thighs, the shins,
    the upper arms, the forearms: :func:`limb_segments`) a group of its own where its sources' median colour lies
    further than :data:`SEGMENT_SPLIT_COLOUR` from the rest of its region's.

    A clothes region is a garment of Anny's clothes (long trousers, a T-shirt), and a person's clothes often end
    elsewhere: shorts over bare shins, a singlet over bare shoulders. Judged over the whole region, the shins' skin was
    untypical of black shorts, and the hidden shins took the shorts' black. Judged always by segment, a shin half in
    shadow kept its shadow as typical of grey trousers (``fashion_man_red_jacket.png``'s dark shins); the skin keeps
    one group (the neck of a person seen from behind, judged alone, is the hair over it).

    Args:
        ref_uv: (V, 2) reference pixels; sources: (S,) int the shown vertices; image: (H, W, 3) in those pixels.
    """
    from renderers import anny_model

    regions = anny_model.vertex_regions().astype(np.int64)
    segments = limb_segments()
    groups = regions * (len(LIMB_SEGMENTS) + 1)
    h, w = image.shape[:2]
    xy = np.asarray(ref_uv, np.float64)[sources]
    colour = np.asarray(image, np.float64)[pixel_indices(xy, h, w)][:, :3]
    for region in (anny_model.TOP, anny_model.TROUSERS):
        inside = regions[sources] == region
        for segment in range(1, len(LIMB_SEGMENTS) + 1):
            mine = inside & (segments[sources] == segment)
            rest = inside & ~mine
            if mine.sum() < COLOUR_MIN_SOURCES or rest.sum() < COLOUR_MIN_SOURCES:
                continue
            apart = np.linalg.norm(np.median(colour[mine], axis=0) - np.median(colour[rest], axis=0))
            if apart > SEGMENT_SPLIT_COLOUR:
                groups[(regions == region) & (segments == segment)] += segment
    return groups


def typical_colour_sources(ref_uv: np.ndarray, sources: np.ndarray, image: np.ndarray,
                           regions: np.ndarray) -> np.ndarray:
    """The subset of ``sources`` (vertex ids) whose colour in ``image`` is typical of the vertex's region: every
    pixel a bilinear sample at it reads (:func:`bilinear_footprint`; the pixel it lies in is one of them) within
    max(COLOUR_MIN, COLOUR_SPREAD x median distance) of the region's median colour (the median and the distances
    over the pixels the sources lie in). A region with fewer than COLOUR_MIN_SOURCES sources keeps them all; one
    with fewer than that whose footprint is typical keeps those whose own pixel is.

    The footprint, because a hidden vertex is drawn by sampling the picture bilinearly where its source lies, and
    the generator moves that sample by a pixel or so: a source whose own pixel was skin but whose neighbour was the
    white gap between arm and waist or the trousers beside the wrist (the fitted forearm of the demo's reference a
    pixel wider than the pictured one) drew the hidden side of the forearm striped white and dark when a future
    turned it to the camera (`make demo`'s future 5 at +35 to +48).

    Args:
        ref_uv: (V, 2) reference pixels; sources: (S,) int vertex ids; image: (H, W, 3) the reference picture in
            the same pixels; regions: (V,) int region of every vertex.
    Returns:
        (S',) int, in the order of ``sources``.
    """
    h, w = image.shape[:2]
    picture = np.asarray(image, np.float64)[..., :3]
    xy = np.asarray(ref_uv, np.float64)[sources]
    inside = (xy[:, 0] >= 0) & (xy[:, 0] < w) & (xy[:, 1] >= 0) & (xy[:, 1] < h)  # outside a crop: no colour
    sources, xy = sources[inside], xy[inside]
    colour = picture[pixel_indices(xy, h, w)]  # (S, 3)
    rows, cols = bilinear_footprint(xy, h, w)
    footprint = picture[rows, cols]  # (S, 4, 3)
    keep = np.ones(len(sources), bool)
    for r in np.unique(regions[sources]):
        idx = np.flatnonzero(regions[sources] == r)
        if len(idx) < COLOUR_MIN_SOURCES:
            continue
        median = np.median(colour[idx], axis=0)
        dist = np.linalg.norm(colour[idx] - median, axis=1)
        limit = max(COLOUR_MIN, COLOUR_SPREAD * float(np.median(dist)))
        whole = (np.linalg.norm(footprint[idx] - median, axis=2) <= limit).all(axis=1)  # its own pixel is one
        keep[idx] = whole if whole.sum() >= COLOUR_MIN_SOURCES else dist <= limit
    return sources[keep]


# A clothes region's completion sources keep INTERIOR_PX pixels (at 128 px; scaled with the image) from every shown
# vertex of another region (:func:`interior_sources`): the generator corrects the flow by up to a pixel or two, and from
# a source on a region's edge that lands on the neighbour (the back of a turned body's trousers, completed from trousers
# pixels beside the hanging hands, came out skin-coloured in `make demo`). The regions of a face are left alone: they
# are a few pixels wide in a photo, and their hidden sides then took colours from far away.
INTERIOR_PX = 2.0
CORE_PX = 1.0  # core_sources: a source this far (at 128 px) inside the person, at least


def core_sources(ref_uv: np.ndarray, sources: np.ndarray, person: np.ndarray, regions: np.ndarray) -> np.ndarray:
    """The subset of ``sources`` (vertex ids) whose pixel lies at least CORE_PX (at 128 px, scaled) inside the
    segmented ``person`` (H, W) bool: the outline's pixels are the person mixed with what lies behind (the top of a
    dancer's head half blue backdrop), and the hidden back of her head, completed from them, came out navy. A region
    left with fewer than COLOUR_MIN_SOURCES sources keeps all of its sources."""
    from scipy.ndimage import distance_transform_edt

    h, w = person.shape
    depth = distance_transform_edt(np.asarray(person, bool))  # pixels to the nearest pixel outside the person
    xy = np.asarray(ref_uv, np.float64)[sources]
    inside = depth[pixel_indices(xy, h, w)] > CORE_PX * h / 128
    keep = inside.copy()
    for region in np.unique(regions[sources]):
        mine = regions[sources] == region
        if (inside & mine).sum() < COLOUR_MIN_SOURCES:
            keep[mine] = True
    return sources[keep]


def interior_sources(ref_uv: np.ndarray, sources: np.ndarray, seen: np.ndarray, regions: np.ndarray, *,
                     radius_px: float) -> np.ndarray:
    """The subset of ``sources`` (vertex ids) without the clothes sources (shirt, trousers, shoes) that lie within
    ``radius_px`` pixels of a shown vertex of another region; a region left with fewer than COLOUR_MIN_SOURCES
    sources keeps all of its sources.

    Args:
        ref_uv: (V, 2) reference pixels; sources: (S,) int vertex ids; seen: (V,) bool shown by the reference;
        regions: (V,) int region of every vertex (:func:`renderers.anny_model.vertex_regions`).
    Returns:
        (S',) int, in the order of ``sources``.
    """
    from renderers.anny_model import SHOES, TOP, TROUSERS

    if len(sources) == 0 or np.count_nonzero(seen) < 2:
        return sources
    a, b = shown_pairs(ref_uv, seen, radius_px)
    edge = in_pairs(len(ref_uv), a, b, regions[a] != regions[b])
    keep = ~edge[sources] | ~np.isin(regions[sources], (TOP, TROUSERS, SHOES))
    for r in np.unique(regions[sources]):
        mine = regions[sources] == r
        if (keep & mine).sum() < COLOUR_MIN_SOURCES:
            keep |= mine
    return sources[keep]


MIRROR_FACING = 0.3  # mirror_vertices: only vertices that face the front or the back this squarely (|normal_y|)
MIRROR_APART_M = 0.03  # and a mirror no farther than this from the vertex seen from the front


@lru_cache(maxsize=1)
def mirror_vertices() -> np.ndarray:
    """(V,) int64: for every vertex of Anny's body, the vertex at the same place on the other side of the body (the
    front of the chest <-> the back, the front of a thigh <-> its back), -1 for the head, the hands and the feet,
    whose two sides differ (a face and its hair), for the sides seen edge-on, and where none is found.

    In the rest pose (x the body's left-right, y its depth, z up; trunk and limbs spread in the frontal plane), a
    vertex facing the front (normal's y component below -:data:`MIRROR_FACING`) takes the vertex facing the back
    nearest to it seen from the front (in x and z), within :data:`MIRROR_APART_M`, and the other way round.
    (Reflecting through each bone's plane failed on bones that carry one side only: a spine bone's back vertices
    were their own mirrors; a ray into the body along the normal left the chest's curve sideways.)"""
    import trimesh
    from scipy.spatial import cKDTree

    from renderers import anny_model

    rest = np.asarray(anny_model.anny_rest({}).vertices, np.float64)
    normals = trimesh.Trimesh(rest, anny_model.triangles(), process=False).vertex_normals
    skip = anny_model.head_vertices() | anny_model.hand_vertices("L") | anny_model.hand_vertices("R")
    skip |= anny_model.vertex_regions() == anny_model.SHOES
    front = np.flatnonzero(~skip & (normals[:, 1] < -MIRROR_FACING))
    back = np.flatnonzero(~skip & (normals[:, 1] > MIRROR_FACING))
    mirror = np.full(len(rest), -1, np.int64)
    for mine, theirs in ((front, back), (back, front)):
        apart, nearest = cKDTree(rest[theirs][:, [0, 2]]).query(rest[mine][:, [0, 2]])
        close = apart < MIRROR_APART_M
        mirror[mine[close]] = theirs[nearest[close]]
    mirror.setflags(write=False)
    return mirror


def complete_reference_uv(ref_uv: np.ndarray, seen: np.ndarray, *, by_region: bool = True,
                          image: np.ndarray | None = None, person: np.ndarray | None = None,
                          mirror: bool = True, by_segment: bool = True) -> np.ndarray:
    """(V, 2) reference pixels where every vertex the reference does not show takes the pixel of the nearest
    shown vertex *along the body's surface* (Dijkstra over :func:`surface_graph`): the hidden side of a thigh
    starts from the colour of its front, not from whatever covers its own pixel in the reference (a hand) or lies
    beside it in the image. Shown vertices that touch another body part in the picture are not sources
    (:func:`touching_other_part`).

    With ``by_region`` the path stays inside the vertex's clothing region (:func:`region_graph`) where that region
    shows any vertex it can reach: the back of a shirt takes the shirt's colour and the back of the head the hair's,
    not the nearest skin of a neck or an arm across the cut line. Vertices whose region shows nothing reachable
    take the nearest shown vertex of any region.

    Given the reference ``image``, a region's sources are only its shown vertices of a typical colour
    (:func:`typical_colour_sources`): the outline's vertices, which show part of what lies beside the region, do not
    colour its hidden side; and a clothes region's only those INTERIOR_PX (at 128 px) from every shown vertex of
    another region (:func:`interior_sources`), so that the generator's small flow correction does not carry the
    samples across. With ``by_segment`` a clothes segment whose colour differs from the rest of its region's is
    judged alone (:func:`colour_groups`: shorts over bare shins).

    With ``mirror``, before the nearest source, a hidden vertex takes the place on the other side of the body
    (:func:`mirror_vertices`) where that is a source of its own region: the back is completed from the front's
    clothing at the same place, as Photo Wake-Up textures a body's back with its front (a singlet seen from behind
    gives a singlet in front, where the nearest sources made a patchwork of its straps' skin and its black).

    Args:
        ref_uv: (V, 2) reference pixels; seen: (V,) bool shown by the reference.
        by_region: keep to the clothing region first (the default); False: any region.
        mirror: the other side of the body first (with ``by_region``).
        by_segment: the typical colour per body segment (with ``by_region`` and ``image``).
        image: (H, W, 3) the reference picture in the pixels of ``ref_uv`` (None: every shown vertex is a source).
        person: (H, W) bool the segmented person in the same pixels, or None: with it, a region's sources are its
            shown vertices inside the person's core (:func:`core_sources`).
    """
    uv = np.array(ref_uv, np.float32, copy=True)
    graph = surface_graph()
    if len(uv) != graph.shape[0]:
        raise ValueError(f"the completion follows Anny's surface ({graph.shape[0]} vertices), got {len(uv)} vertices")
    sources = np.flatnonzero(seen)
    if len(sources) == 0 or len(sources) == len(seen):
        return uv
    doubtful = touching_other_part(uv, seen)
    if (~doubtful[sources]).any():
        sources = sources[~doubtful[sources]]
    nearest = _nearest_sources(graph, sources)
    if by_region:
        inside, regions = region_graph()
        typical = sources
        if person is not None:
            typical = core_sources(uv, typical, person, regions)
        if image is not None:
            groups = colour_groups(uv, typical, image) if by_segment else regions
            typical = typical_colour_sources(uv, typical, image, groups)
            typical = interior_sources(uv, typical, seen, regions, radius_px=INTERIOR_PX * image.shape[0] / 128)
        within = _nearest_sources(inside, typical)
        nearest = np.where(within >= 0, within, nearest)
        if mirror:
            other = mirror_vertices()
            usable = np.zeros(len(uv), bool)
            usable[typical] = True
            ok = other >= 0
            ok[ok] = usable[other[ok]] & (regions[other[ok]] == regions[ok])
            nearest = np.where(ok, other, nearest)
    hidden = ~np.asarray(seen, bool) & (nearest >= 0)
    uv[hidden] = uv[nearest[hidden]]
    return uv


@lru_cache(maxsize=1)
def mesh_triangles() -> np.ndarray:
    """(F, 3) int64 Anny's triangles, which every mesh flow is read from (:func:`dense_flow`): the training
    pairs (:func:`motion2video.generator.data.pair_mesh_flows`) and :func:`flows_to_targets`."""
    from renderers import anny_model

    return np.ascontiguousarray(anny_model.triangles(), dtype=np.int64)


def triangle_map(uv: np.ndarray, triangles: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) int64: which of ``triangles`` (F, 3) holds each pixel centre of an image of ``shape``, -1 where none
    does; ``uv`` (V, 2) the corners' pixels. A centre on an edge shared by two triangles goes to either (both give
    the same barycentric mix there); where triangles overlap the later one wins (the callers pass only triangles of
    the front surface, which overlap at most along an outline).

    Rasterised here rather than with OpenCV's polygon fill, which also draws pixels whose centres lie up to a
    pixel outside the triangle: read from the wrong triangle, such a pixel's flow is off by up to a pixel. Each
    triangle's candidate pixels are the centres in its bounding box, tested by their barycentric weights,
    vectorised over the triangles whose boxes have the same size.
    """
    h, w = shape
    ids = np.full(shape, -1, np.int64)
    corners = np.asarray(uv, np.float64)[np.asarray(triangles, np.int64)]  # (F, 3, 2)
    x0 = np.ceil(corners[..., 0].min(axis=1) - 0.5).astype(np.int64)  # first pixel whose centre is inside the box
    y0 = np.ceil(corners[..., 1].min(axis=1) - 0.5).astype(np.int64)
    x1 = np.floor(corners[..., 0].max(axis=1) - 0.5).astype(np.int64)
    y1 = np.floor(corners[..., 1].max(axis=1) - 0.5).astype(np.int64)
    x0, y0, x1, y1 = np.maximum(x0, 0), np.maximum(y0, 0), np.minimum(x1, w - 1), np.minimum(y1, h - 1)
    bw, bh = x1 - x0 + 1, y1 - y0 + 1
    drawn = np.flatnonzero((bw > 0) & (bh > 0))
    for size_w, size_h in sorted(set(zip(bw[drawn].tolist(), bh[drawn].tolist()))):
        group = drawn[(bw[drawn] == size_w) & (bh[drawn] == size_h)]  # (G,)
        dy, dx = np.mgrid[0:size_h, 0:size_w]
        px = x0[group, None] + dx.ravel()[None]  # (G, C) candidate pixels
        py = y0[group, None] + dy.ravel()[None]
        weights = _barycentric_raw(np.stack([px + 0.5, py + 0.5], axis=-1).reshape(-1, 2),
                                   np.repeat(corners[group], px.shape[1], axis=0))
        inside = (weights >= -1e-9).all(axis=1).reshape(px.shape)
        g = np.broadcast_to(group[:, None], px.shape)
        ids[py[inside], px[inside]] = g[inside]
    return ids


def _barycentric_raw(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(M, 3) barycentric weights of ``points`` (M, 2) in ``corners`` (M, 3, 2), unclipped (negative outside);
    -inf for a degenerate triangle, which holds no point."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    e1, e2, d = b - a, c - a, points - a
    det = e1[:, 0] * e2[:, 1] - e2[:, 0] * e1[:, 1]
    ok = np.abs(det) > 1e-9
    safe = np.where(ok, det, 1.0)
    w1 = (d[:, 0] * e2[:, 1] - e2[:, 0] * d[:, 1]) / safe
    w2 = (e1[:, 0] * d[:, 1] - d[:, 0] * e1[:, 1]) / safe
    out = np.stack([1.0 - w1 - w2, w1, w2], axis=1)
    out[~ok] = -np.inf
    return out


def barycentric(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(M, 3) barycentric weights of ``points`` (M, 2) in the triangles ``corners`` (M, 3, 2), clipped to [0, 1]
    and summing to 1 (a point just outside its triangle takes a mix of the nearest corners; a degenerate triangle
    weights its corners equally)."""
    raw = _barycentric_raw(points, corners)
    flat = ~np.isfinite(raw).all(axis=1)
    w = np.clip(np.where(flat[:, None], 1.0 / 3.0, raw), 0.0, 1.0)
    return w / np.maximum(w.sum(axis=1, keepdims=True), 1e-12)


def across_a_fold(ref: np.ndarray, tgt: np.ndarray, height: int) -> np.ndarray:
    """(F,) bool: triangles whose corners lie further apart in the reference (F, 3, 2) than in the target (F, 3, 2)
    allows: their longest edge beyond AGREE_PX (at 128 px) and beyond AGREE_STRETCH times the target's longest
    edge, the rule that keeps :func:`dense_flow`'s neighbours from averaging across a fold. Such a triangle joins
    surface points the reference shows far apart (a hidden back completed from two sides), and reading it would
    sample the picture along the line between them."""
    def longest_squared(c: np.ndarray) -> np.ndarray:
        edges = c - c[:, [1, 2, 0]]
        return (edges * edges).sum(axis=-1).max(axis=1)

    allowed = np.maximum(AGREE_PX * height / 128, AGREE_STRETCH * np.sqrt(longest_squared(tgt)))
    return longest_squared(ref) > allowed * allowed


def triangle_pixels(ref_uv: np.ndarray, tgt_uv: np.ndarray, tgt_visible: np.ndarray, triangles: np.ndarray,
                    silhouette: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The ``silhouette`` pixels read from a triangle: those whose centre lies in a triangle the target shows whole
    (all three corners visible) that does not join a fold (:func:`across_a_fold`).

    Returns:
        ys, xs (M,) the pixels; tri (M, 3) the vertex ids of each pixel's triangle; weights (M, 3) the pixel
        centre's barycentric weights in the target.
    """
    shown = np.asarray(tgt_visible, bool)
    front = triangles[shown[triangles].all(axis=1)]
    tgt, ref = np.asarray(tgt_uv, np.float64), np.asarray(ref_uv, np.float64)
    front = front[~across_a_fold(ref[front], tgt[front], silhouette.shape[0])]
    if len(front) == 0:
        empty = np.zeros(0, np.int64)
        return empty, empty, np.zeros((0, 3), np.int64), np.zeros((0, 3))
    which = triangle_map(tgt, front, silhouette.shape)
    ys, xs = np.nonzero(silhouette & (which >= 0))
    tri = front[which[ys, xs]]
    return ys, xs, tri, barycentric(np.stack([xs + 0.5, ys + 0.5], axis=1), tgt[tri])


def dense_flow(ref_uv: np.ndarray, ref_visible: np.ndarray, tgt_uv: np.ndarray, tgt_visible: np.ndarray,
               silhouette: np.ndarray, *, neighbours: int = NEIGHBOURS, complete: bool = True,
               image: np.ndarray | None = None, triangles: np.ndarray | None = None) -> MeshFlow:
    """The backward flow target -> reference of one pair.

    Args:
        ref_uv, tgt_uv: (V, 2) the vertices' pixel positions in the reference and the target frame.
        ref_visible, tgt_visible: (V,) bool, front surface in each frame (:func:`renderers.mesh.vertex_visibility`).
        silhouette: (H, W) bool, the target render's mask (the pixels to fill).
        neighbours: target vertices interpolated per pixel.
        complete: surface points the reference does not show sample the reference where the nearest shown
            point along the surface is (:func:`complete_reference_uv`; their visibility stays 0). Off, they
            sample their own (occluded) reference pixel.
        image: (H, W, 3) the reference picture in the pixels of ``ref_uv``, for the completion's colour test.
        triangles: (F, 3) the mesh's triangles (:func:`mesh_triangles`): pixels inside a triangle the target shows
            whole are read from it (:func:`triangle_pixels`), only the rest from the vertices; None: the vertices
            only.
    Returns:
        The :class:`MeshFlow`; with no visible target vertex, the identity flow and zero visibility.
    """
    from scipy.spatial import cKDTree

    h, w = silhouette.shape
    flow = identity_flow(h, w)
    visibility = np.zeros((h, w), np.float32)
    silhouette = np.asarray(silhouette, bool)
    if complete:
        ref_uv = complete_reference_uv(ref_uv, ref_visible, image=image)
    seen = np.flatnonzero(tgt_visible)
    if len(seen) == 0 or not silhouette.any():
        return MeshFlow(flow, visibility, silhouette)
    by_vertices = silhouette.copy()  # the pixels no triangle reads
    if triangles is not None:
        ty, tx, tri, bary = triangle_pixels(ref_uv, tgt_uv, tgt_visible, triangles, silhouette)
        flow[ty, tx] = (bary[..., None] * np.asarray(ref_uv, np.float64)[tri]).sum(axis=1)
        visibility[ty, tx] = (bary * np.asarray(ref_visible, np.float64)[tri]).sum(axis=1)
        by_vertices[ty, tx] = False
    if by_vertices.any():
        k = min(neighbours, len(seen))
        tree = cKDTree(np.asarray(tgt_uv, np.float64)[seen])
        pix = pixel_centres(by_vertices)
        dist, idx = tree.query(pix, k=k)
        dist, idx = dist.reshape(len(pix), k), idx.reshape(len(pix), k)
        vert = seen[idx]  # (M, k) vertex ids, nearest first
        ref = np.asarray(ref_uv, np.float64)[vert]  # (M, k, 2)
        tgt = np.asarray(tgt_uv, np.float64)[vert]  # (M, k, 2)
        allowed = np.maximum(AGREE_PX * h / 128, AGREE_STRETCH * np.linalg.norm(tgt - tgt[:, :1], axis=2))
        agree = np.linalg.norm(ref - ref[:, :1], axis=2) <= allowed  # the nearest always agrees with itself
        weight = agree / (dist ** 2 + WEIGHT_EPS_PX ** 2)  # (M, k)
        weight /= weight.sum(axis=1, keepdims=True)
        ys, xs = np.nonzero(by_vertices)
        flow[ys, xs] = (weight[..., None] * ref).sum(axis=1)
        visibility[ys, xs] = (weight * np.asarray(ref_visible, np.float64)[vert]).sum(axis=1)
    return MeshFlow(flow, visibility, silhouette)


def transform_uv(uv: np.ndarray, *, size: int, flip: bool = False, origin: tuple[float, float] = (0.0, 0.0)
                 ) -> np.ndarray:
    """Vertex pixel positions (..., 2) after the pair augmentations of :func:`generator.data.make_pairs`: a
    left-right mirror of a ``size``-wide image, then a crop whose top-left corner is ``origin`` (x0, y0)."""
    out = np.array(uv, np.float32, copy=True)
    if flip:
        out[..., 0] = size - out[..., 0]
    out[..., 0] -= origin[0]
    out[..., 1] -= origin[1]
    return out


def extend_flow(mesh: MeshFlow, band: int) -> MeshFlow:
    """Carry the flow into a band of ``band`` pixels around the silhouette: each band pixel moves like its nearest
    silhouette pixel (``flow(p) = flow(q) + (p - q)``, a translation continuing the surface), with its visibility.

    A body fitted to a real person is thinner or wider than the person in places (clothes, hair, a body model's
    proportions), so the generator needs a flow a little outside the mesh; the silhouette is unchanged (the
    generator's alpha decides how much of the band is person).

    Returns:
        A new :class:`MeshFlow` with the same silhouette.
    """
    from scipy.ndimage import binary_dilation, distance_transform_edt

    sil = mesh.silhouette
    if band <= 0 or not sil.any():
        return mesh
    ring = binary_dilation(sil, structure=np.ones((3, 3), bool), iterations=int(band)) & ~sil
    _, (iy, ix) = distance_transform_edt(~sil, return_indices=True)
    ys, xs = np.nonzero(ring)
    qy, qx = iy[ys, xs], ix[ys, xs]
    flow = mesh.flow.copy()
    visibility = mesh.visibility.copy()
    flow[ys, xs, 0] = mesh.flow[qy, qx, 0] + (xs - qx)
    flow[ys, xs, 1] = mesh.flow[qy, qx, 1] + (ys - qy)
    visibility[ys, xs] = mesh.visibility[qy, qx]
    return MeshFlow(flow, visibility, sil)


def grow_masks(masks: np.ndarray, pixels: int) -> np.ndarray:
    """(..., H, W) bool masks dilated by ``pixels`` (a 3x3 cross per step, SciPy); the masks as they are for 0."""
    from scipy.ndimage import binary_dilation

    masks = np.asarray(masks, bool)
    if pixels <= 0:
        return masks
    flat = masks.reshape((-1,) + masks.shape[-2:])
    return np.stack([binary_dilation(m, iterations=int(pixels)) for m in flat]).reshape(masks.shape)


def band_width(size: int) -> int:
    """The band :func:`extend_flow` adds at an image side of ``size`` pixels (4 at 128)."""
    return max(1, round(BAND_PX * size / 128))


def flows_to_targets(ref_uv: np.ndarray, ref_visible: np.ndarray, targets: MeshTrack, rows, *,
                     margin: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The correspondence from one reference to many target frames: :func:`dense_flow` (read from Anny's
    triangles, :func:`mesh_triangles`) carried into the band (:func:`extend_flow`) for each of ``rows``.

    Args:
        ref_uv: (V, 2) the reference vertices' pixels, already completed (:func:`complete_reference_uv`: done once
            per reference, not once per target); ref_visible: (V,) bool.
        targets: the target frames; rows: indices into them.
        margin: pixels the person's silhouettes are grown by
            (:func:`motion2video.generator.mesh_reference.clothes_margin`): the flow is carried :func:`band_width` past the silhouette, or half that past the margin when further.
    Returns:
        flow (R, H, W, 2) float32, visibility (R, H, W) float32.
    """
    width = band_width(targets.masks.shape[2])
    band = max(width, int(margin) + width // 2)
    flows = [extend_flow(dense_flow(ref_uv, ref_visible, targets.uv[r], targets.visible[r], targets.masks[r],
                                    complete=False, triangles=mesh_triangles()), band) for r in rows]
    return np.stack([f.flow for f in flows]), np.stack([f.visibility for f in flows])
