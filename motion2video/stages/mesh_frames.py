"""Generate body frames through a body mesh: the mesh generator's stage.

The keypoint generators take 2D joints; the mesh generator (:mod:`motion2video.frames.mesh_warp`) takes the
correspondence of one body mesh in the reference pose and in each target pose. This stage makes that mesh
for a video:

1. **The reference person's body.** Anny with the reference's phenotype (``pose.identity`` of the reference
   pose file, Anny's defaults otherwise), in the reference pose. The pose file gives 2D joints; they are lifted
   to 3D through the placement's camera at the depths of the first observed pose (each joint keeps the depth
   the clip's first frame has there), which is exact when the reference shows the first observed pose and a
   close guess otherwise.
2. **Every target pose on that body.** Anny's inverse kinematics follows the driving joints' directions, so
   the target meshes keep the motion's joint angles with the reference person's proportions (one scale for
   the whole video, fitted to leg + torso length; feet flat on the floor near it).
3. **Correspondence.** Each mesh is rendered (depth and silhouette) through the placement's camera; every
   vertex's pixel and front-surface flag go through the placement's 2D similarity onto the reference picture
   and into the generator's person crop; :func:`motion2video.frames.mesh_flow.dense_flow` makes the flow.

The crop and the paste follow the keypoint warp generator's (:func:`motion2video.frames.warp.person_crop`,
:func:`~motion2video.frames.warp.paste_mask`): the person is generated at the model's size inside a square crop
holding both poses and pasted back with a feathered mask, so the background keeps its resolution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2video.core.camera import affine_matrix
from motion2video.core.errors import InputError
from motion2video.frames.mesh_flow import MeshTrack

MASK_GREY = (200, 200, 200)  # the colour the correspondence renders use (only depth and silhouette are read)
# Anny "weight" values tried when fitting the body's width to the reference person's silhouette (fit_width).
WEIGHT_GRID = (0.15, 0.3, 0.45, 0.6, 0.75, 0.9)
WIDTH_FIT_MARGIN = 0.01  # IoU another weight must gain over the given phenotype's to replace it


def lift_reference(points: np.ndarray, guide: np.ndarray, camera, scale: float, shift: np.ndarray, *,
                   pictured: np.ndarray | None = None) -> np.ndarray:
    """3D joints whose projection is the reference pose.

    With ``pictured`` (the picture's own 3D pose, from its pose file): its bone lengths, and for each bone which
    way it points in depth. The pelvis sits at the depth where the picture's bones are no longer than those lengths
    (the picture's scale); each further joint, parents first, lies on its pixel's ray at its bone's length from its
    parent, the one of the two such points whose depth step is nearer the pictured one (Taylor's 2000
    reconstruction from one view, under perspective). On real-mocap pairs with a fitted reference body this gave
    0.4-1.8 dB more person PSNR than the guide's depths (on held-out real-mocap pairs).

    Without it: each joint at the depth of the same joint of ``guide``. Bones whose direction differs between the
    two poses are then stretched or shrunk in depth, but no bone length from another person is assumed.

    Args:
        points: (17, 2) reference joints in output pixels.
        guide: (17, 3) world joints (the first observed pose, placed).
        camera: the placement's PinholeCamera; its pixels map to output pixels by ``pixel * scale + shift``.
        scale, shift: that 2D similarity (float, (2,)).
        pictured: (17, 3) the pictured pose in its camera's axes (metres; x right, y up, z away), or None.
    Returns:
        (17, 3) world joints.
    """
    axes = camera.axes()  # rows: right, up, forward
    origin = np.asarray(camera.position, np.float64)
    pix = (np.asarray(points, np.float64) - np.asarray(shift, np.float64)) / scale  # camera pixels
    f = camera.focal
    rays = np.stack([(pix[:, 0] - 0.5 * camera.width) / f, (0.5 * camera.height - pix[:, 1]) / f,
                     np.ones(len(pix))], axis=1)  # (17, 3): the point at depth t is t * ray, camera axes
    if pictured is None:
        depth = (np.asarray(guide, np.float64) - origin) @ axes[2]  # (17,) the guide's depths
        return origin[None] + (depth[:, None] * rays) @ axes
    return origin[None] + lift_by_bones(rays, np.asarray(pictured, np.float64), f, pix) @ axes


def lift_by_bones(rays: np.ndarray, pictured: np.ndarray, focal: float, pixels: np.ndarray) -> np.ndarray:
    """(17, 3) camera-axes joints on ``rays`` (17, 3) with the bone lengths and depth steps of ``pictured`` (17, 3,
    camera axes); ``pixels`` (17, 2) and ``focal`` give the picture's scale (see :func:`lift_reference`)."""
    from motion2video.core.skeletons import H36M_17

    bones = [(j, p) for j, p in enumerate(H36M_17.parents) if p >= 0]
    lengths = {j: float(np.linalg.norm(pictured[j] - pictured[p])) for j, p in bones}
    # A bone can look shorter than it is (foreshortened), never longer: the pelvis goes where the bones that look
    # longest for their length lie in the picture's plane. The 10% quantile, not the minimum: one keypoint a few
    # pixels off should not move the whole body.
    ratio = [focal * lengths[j] / max(float(np.linalg.norm(pixels[j] - pixels[p])), 1e-6) for j, p in bones]
    joints = np.zeros((len(rays), 3))
    joints[0] = float(np.quantile(ratio, 0.1)) * rays[0]
    for j, p in bones:
        a, b = rays[j] @ rays[j], rays[j] @ joints[p]
        disc = b * b - a * (joints[p] @ joints[p] - lengths[j] ** 2)
        if disc <= 0:  # the ray passes further than the bone's length: its closest point
            t = b / a
        else:
            roots = (b + np.array([-1.0, 1.0]) * np.sqrt(disc)) / a
            step = pictured[j, 2] - pictured[p, 2]
            t = roots[np.argmin(np.abs(roots - joints[p, 2] - step))]
        joints[j] = t * rays[j]
    return joints


def camera_covering(camera, scales: np.ndarray, shifts: np.ndarray, size: int):
    """The camera widened (same centre and focal length, ``pad`` more pixels on every side) so that its image
    covers the whole track square of every frame: a body that leaves the camera's frame (a jump's head above
    the observed frames' framing) is still rendered where the track shows it.

    Args:
        camera: the PinholeCamera; scales (N,), shifts (N, 2): its pixels map to the track's by ``x * a + b``.
        size: the track's side.
    Returns:
        (camera, pad): its pixels are the given camera's + ``pad``.
    """
    lo = -shifts / scales[:, None]  # the track square's corners in the camera's pixels
    hi = (size - shifts) / scales[:, None]
    need = max(0.0, float(-lo.min()), float((hi - [camera.width, camera.height]).max()))
    pad = int(np.ceil(min(need, max(camera.width, camera.height))))  # at most doubles the render's side
    if pad == 0:
        return camera, 0
    height = camera.height + 2 * pad
    yfov = 2.0 * np.arctan(0.5 * height / camera.focal)
    return type(camera)(camera.position, camera.target, float(yfov), camera.width + 2 * pad, height), pad


def render_mesh_track(joints: np.ndarray, *, phenotype: dict, camera, transform: tuple,
                      size: int, progress=None, clear_arms: bool | np.ndarray = True) -> MeshTrack:
    """Pose Anny on ``joints`` and render its correspondence.

    In the frames ``clear_arms`` picks (True: all; or (N,) bool), elbows and wrists that fall inside the torso are
    moved out of it first (``renderers.collision``): a mocap actor's arms pass where this person's fitted, often
    wider, body is. A pictured person's own pose (a reference, a video's frames) is left as it is. Where two
    surfaces of the body meet in a frame (a forearm held against the waist, a hand beside a thigh), only the front
    one counts as shown (``renderers.mesh.behind_a_touching_surface``).

    Args:
        joints: (N, 17, 3) world joints (one body: a single size is fitted over all frames).
        phenotype: Anny phenotype values.
        camera: the render camera (PinholeCamera).
        transform: ``(a, b)``: the camera's pixels map to the track's by ``x * a + b``; ``a`` a float and ``b``
            (2,), or per frame: ``a`` (N,) and ``b`` (N, 2).
        size: the track's image side (square).
        progress: called with the number of frames done.
    Returns:
        The :class:`MeshTrack`.
    """
    import cv2

    from motion2video.core.camera import project
    from renderers import anny_model
    from renderers.body import fitted_scale, pose_anny_from_joints, posed_vertices
    from renderers.collision import arms_clear_of_torso
    from renderers.mesh import MeshRenderer, vertex_visibility

    n = len(joints)
    scales = np.broadcast_to(np.asarray(transform[0], np.float64), (n,))
    shifts = np.broadcast_to(np.asarray(transform[1], np.float64), (n, 2))
    camera, pad = camera_covering(camera, scales, shifts, size)
    shifts = shifts - scales[:, None] * pad  # the widened camera's pixels are the given camera's + pad
    shape = anny_model.anny_rest(phenotype)
    joints = np.asarray(joints, np.float64)
    clear = np.broadcast_to(np.asarray(clear_arms, bool), (n,))
    if clear.any():  # the arms out of the torso first, at the size pose_anny_from_joints fits
        scale = fitted_scale(joints, shape)
        joints = joints.copy()
        joints[clear] = arms_clear_of_torso(joints[clear], shape, scale=scale)
    pose = pose_anny_from_joints(joints, phenotype=phenotype)
    faces = anny_model.triangles()
    rest = shape.vertices
    renderer = MeshRenderer(camera.width, camera.height)
    uv, visible, masks = None, None, np.zeros((n, size, size), bool)
    try:
        for start, verts in posed_vertices(pose):
            if uv is None:
                uv = np.zeros((n, verts.shape[1], 2), np.float32)
                visible = np.zeros((n, verts.shape[1]), bool)
            for k, v in enumerate(verts):
                i = start + k
                out = renderer.render_mesh(v, faces, vertex_colors=MASK_GREY, camera=camera)
                uvz = project(v, camera)
                # where two surfaces meet, only the front one is shown: in a target so that the flow does not
                # alternate between them, in the reference so that the one behind (a thigh under the hand) does not
                # carry the other's pixel when a target moves them apart
                visible[i] = vertex_visibility(uvz, out.depth, rest=rest)
                uv[i] = uvz[:, :2] * scales[i] + shifts[i]
                m = cv2.warpAffine(out.mask.astype(np.float32), affine_matrix(scales[i], shifts[i]), (size, size),
                                   flags=cv2.INTER_LINEAR)
                masks[start + k] = m > 0.5
            if progress is not None:
                progress(len(verts))
    finally:
        renderer.close()
    return MeshTrack(uv=uv, visible=visible, masks=masks)


@dataclass
class MeshVideo:
    """Everything the mesh generator needs for one video, in the person crop at the model's size.

    Attributes:
        crop: (x0, y0, side) of the square crop in output pixels.
        reference: the reference mesh (1 frame); targets: the target meshes (N frames).
        ref_points, tgt_points: (17, 2) / (N, 17, 2) joints in crop pixels (for the structure maps).
        person: (S, S) bool the person segmented in the reference crop, or None when not segmented.
        margin: pixels (at S) by which the person's clothes and hair reach past the fitted mesh in the reference
            (:func:`clothes_margin`); every silhouette is grown by it.
        uv_sources: (V,) int64, or None: after the surface completion, vertex v samples where vertex
            ``uv_sources[v]`` does (:func:`hand_colour_sources`: a fitted hand sampling beside the pictured hand).
    """

    crop: tuple[int, int, int]
    reference: MeshTrack
    targets: MeshTrack
    ref_points: np.ndarray
    tgt_points: np.ndarray
    person: np.ndarray | None = None
    margin: int = 0
    uv_sources: np.ndarray | None = None


def mesh_video(placement, reference_points: np.ndarray, target_rows: np.ndarray, *, phenotype: dict,
               output_size: int, model_size: int, person=None, image: np.ndarray | None = None,
               fit_to_mask: bool = True, pictured: np.ndarray | None = None) -> MeshVideo:
    """The meshes of a placed body video.

    Args:
        placement: the :class:`motion2video.stages.structure.BodyPlacement` (3D: world joints and camera).
        reference_points: (17, 2) the reference pose in output pixels.
        target_rows: (N, 17, 2) the target joints in output pixels (to place the crop).
        phenotype: the reference person's Anny phenotype.
        output_size: the output frames' side; model_size: the generator's.
        person: what BlazePose found of the reference person in output pixels
            (:class:`motion2video.stages.reference.ReferencePerson`), or None. Anny's weight is fitted to its mask
            (:func:`fit_width`, when ``fit_to_mask``); where the colours are sampled, a vertex the reference mesh
            shows counts as shown only where it lands on the person, and the fitted head is moved onto its eyes
            (:func:`reference_sampling`).
        image: (output_size, output_size, 3) uint8 the reference picture, or None: a fitted hand vertex that lands
            beside the pictured hand samples where a hand vertex on it does (:func:`hand_colour_sources`).
        pictured: (17, 3) the reference picture's own 3D pose in its camera's axes (its pose file's
            ``camera_joints``), or None (:func:`lift_reference`).
    Raises:
        InputError: the placement has no 3D joints (a 2D motion model).
    """
    if placement.world_observed is None or placement.camera is None:
        raise InputError("the mesh frame generator needs a 3D body motion (this motion model predicts 2D "
                         "keypoints); use --frame-model frames-body-128")
    world = np.concatenate([placement.world_observed, placement.world_futures.reshape(-1, 17, 3)])  # (N, 17, 3)
    scale, shift = placement.scale, placement.shift
    from motion2video.frames.warp import person_crop

    x0, y0, side = person_crop(reference_points, target_rows, width=output_size, height=output_size,
                               model_size=model_size)
    k = model_size / side
    to_crop = (scale * k, (np.asarray(shift) - [x0, y0]) * k)
    lifted = lift_reference(reference_points, world[0], placement.camera, scale, shift, pictured=pictured)
    small, seen = None, None
    if person is not None:
        seen = person.moved(k, -np.array([x0, y0]) * k, (model_size, model_size))
        small = seen.segmented()
        if fit_to_mask:
            phenotype, _ = fit_width(lifted, camera=placement.camera, transform=to_crop, size=model_size,
                                     person_mask=small, phenotype=phenotype)
    both = render_mesh_track(np.concatenate([lifted[None], world]), phenotype=phenotype, camera=placement.camera,
                             transform=to_crop, size=model_size, clear_arms=np.arange(len(world) + 1) > 0)
    from renderers import anny_model

    rest = anny_model.anny_rest(phenotype)
    ref_uv, ref_visible = reference_sampling(both.uv[0], both.visible[0], both.masks[0], seen, rest=rest)
    sources = None
    if image is not None and seen is not None:
        picture = reference_crop(image, (x0, y0, side), model_size)
        sources = hand_colour_sources(ref_uv, ref_visible, picture, seen.hands, seen.hand_visibility, rest=rest)
    ref = MeshTrack(ref_uv[None], ref_visible[None], both.masks[:1])
    tgt = MeshTrack(both.uv[1:], both.visible[1:], both.masks[1:])
    ref_pts = (np.asarray(reference_points, np.float64) - [x0, y0]) * k
    tgt_pts = (np.asarray(target_rows, np.float64) - [x0, y0]) * k
    margin = 0 if small is None else clothes_margin(small, ref.masks[0])
    return MeshVideo((x0, y0, side), ref, tgt, ref_pts.astype(np.float32), tgt_pts.astype(np.float32), person=small,
                     margin=margin, uv_sources=sources)


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
    from scipy.ndimage import binary_erosion, distance_transform_edt

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
    from scipy.ndimage import binary_erosion

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
    from renderers import anny_model

    head = anny_model.head_vertices()
    top = rest.bone_heads[anny_model.bone_index("head"), 2]
    bottom = rest.bone_heads[anny_model.bone_index("neck01"), 2]
    ramp = np.clip((rest.vertices[:, 2] - bottom) / max(top - bottom, 1e-6), 0.0, 1.0)
    return np.where(head, 1.0, ramp)


FACE_HAIRLINE_M = 0.05  # face_weights: the hairline's height above the eyes in the rest pose (Anny's regions use 5 cm)


def face_weights(rest) -> np.ndarray:
    """(V,) float in [0, 1]: which head vertices are the face (1 at and below the eyes' height in the rest pose)
    and which the crown (0 from :data:`FACE_HAIRLINE_M` above the eyes up), linear between; 0 off the head."""
    from renderers import anny_model

    iris = anny_model.vertex_regions(rest) == anny_model.IRIS
    eyes = float(np.mean(rest.vertices[iris, 2]))
    face = np.clip((eyes + FACE_HAIRLINE_M - rest.vertices[:, 2]) / FACE_HAIRLINE_M, 0.0, 1.0)
    return np.where(anny_model.head_vertices(), face, 0.0)


def crown_offset(uv: np.ndarray, silhouette: np.ndarray, person: np.ndarray) -> float | None:
    """How far (pixels, + down) the pictured person's head top lies below the fitted head's: the median over the
    middle half of the fitted head's columns of the difference between the first person row and the first
    silhouette row; None when a column has no person or the head is under 4 columns wide."""
    from renderers import anny_model

    head = np.asarray(uv)[anny_model.head_vertices()]
    w = silhouette.shape[1]
    lo, hi = np.quantile(head[:, 0], [0.25, 0.75])
    columns = np.arange(max(0, int(np.floor(lo))), min(w, int(np.ceil(hi)) + 1))
    if len(columns) < 4:
        return None
    sil, per = np.asarray(silhouette, bool)[:, columns], np.asarray(person, bool)[:, columns]
    if not sil.any(axis=0).all() or not per.any(axis=0).all():
        return None
    return float(np.median(per.argmax(axis=0) - sil.argmax(axis=0)))


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
    from renderers import anny_model

    eyes = np.asarray(eyes, np.float64)
    if np.any(np.asarray(eye_visibility) < EYE_VISIBILITY):
        return uv, None
    iris = (anny_model.vertex_regions(rest) == anny_model.IRIS) & np.asarray(visible, bool)
    offsets = []
    for eye, side in zip(eyes, (rest.vertices[:, 0] > 0, rest.vertices[:, 0] < 0)):  # Anny's left is +x
        shown = iris & side
        if shown.sum() < MIN_IRIS_SHOWN:
            return uv, None
        offsets.append(eye - uv[shown].mean(axis=0))
    shift = np.mean(offsets, axis=0)
    if np.linalg.norm(shift) > MAX_FACE_SHIFT * np.linalg.norm(eyes[0] - eyes[1]):
        return uv, None
    per_vertex = head_weights(rest)[:, None] * shift[None]  # (V, 2)
    if crown_dy is not None:  # the crown moves down by the pictured crown's offset, the face by the eyes'
        face = face_weights(rest)[:, None]
        crown = np.array([shift[0], crown_dy])
        head = anny_model.head_vertices()[:, None]
        per_vertex = np.where(head, face * shift[None] + (1.0 - face) * crown[None], per_vertex)
    moved = np.asarray(uv, np.float64) + per_vertex
    return moved.astype(np.asarray(uv).dtype), shift


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
    :func:`motion2video.frames.mesh_flow.touching_other_part`); the head's are never flagged (its face is moved
    onto the pictured eyes).

    Such a vertex is squeezed into the last pixel of its part's outline, where the fit is a pixel off the picture
    as often as not: on the demo's reference the side of a thigh under the hanging hand read the hand, and the sides
    of the hand the trousers, and where a future turns them to the camera they came out as skin blobs on the
    trousers and dark fingers (`make demo`'s future 2 at +41 and +48). Counted as hidden, they take their colour
    by the surface completion from squarely seen vertices of their own region. A grazing vertex at the person's
    outer outline is left alone (the background there is filled from inside the person,
    :func:`motion2video.frames.mesh_warp.fill_outside_person`): made hidden everywhere, 14% of the demo
    reference's shown vertices, it cost 0.2-0.5 dB of person PSNR on fitted references (docs/results.md).

    Args:
        uv: (V, 2) the fitted vertices' pixels in an (size, size) image; shown: (V,) bool.
        rest: the fitted body's :class:`renderers.anny_model.AnnyRest`.
        fitted: (V, 2) the pixels the fit gave, when ``uv`` has the head moved onto the pictured eyes
            (:func:`align_face`): the facing is read from them (a moved head stretches the neck's triangles).
    """
    from motion2video.frames.mesh_flow import touching_other_part
    from renderers import anny_model

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
        crown = crown_offset(uv, silhouette, mask)
        uv, _ = align_face(uv, visible, person.eyes, person.eye_visibility, rest=rest, crown_dy=crown)
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
    on the demo 12 more trousers pixels, on the fitted held-out references 0.03-0.05 dB less person PSNR. Applied
    after the surface completion
    (:func:`motion2video.frames.mesh_flow.complete_reference_uv`), whose test of a thigh touching the hand must see
    the fitted hand where it lies.

    Args:
        uv: (V, 2) vertex pixels; shown: (V,) bool. image: (S, S, 3) uint8 in the same pixels.
        hands: (2, 4, 2) the left and right hand's landmarks in those pixels; hand_visibility: (2, 4).
        rest: the fitted body's :class:`renderers.anny_model.AnnyRest`.
    """
    from scipy.spatial import cKDTree

    from renderers import anny_model

    shown = np.asarray(shown, bool)
    sources = np.arange(len(uv), dtype=np.int64)
    h, w = image.shape[:2]
    picture = np.asarray(image, np.float64)

    def pixels(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = np.floor(np.asarray(points, np.float64)).astype(np.int64)
        return np.clip(p[:, 1], 0, h - 1), np.clip(p[:, 0], 0, w - 1)

    def take_nearest(off: np.ndarray, on: np.ndarray) -> bool:  # off vertices sample where their nearest on does
        if len(off) == 0 or len(on) == 0:
            return False
        _, nearest = cKDTree(rest.vertices[on]).query(rest.vertices[off])
        sources[off] = on[nearest]
        return True

    any_hand = anny_model.hand_vertices("L") | anny_model.hand_vertices("R")
    regions = anny_model.vertex_regions(rest)
    ys, xs = pixels(uv)
    colours = picture[ys, xs]  # (V, 3) what each vertex's pixel shows
    changed = False
    for side, points, seen in zip(("L", "R"), np.asarray(hands), np.asarray(hand_visibility)):
        points = points[seen >= HAND_VISIBILITY]
        if len(points) < MIN_HAND_LANDMARKS:
            continue
        patch = points[:, None, :] + np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1]), -1).reshape(1, 9, 2)
        colour = np.median(picture[pixels(patch.reshape(-1, 2))], axis=0)
        to_hand = np.linalg.norm(colours - colour, axis=1)
        hand = np.flatnonzero(anny_model.hand_vertices(side) & shown)
        far = to_hand[hand] > HAND_COLOUR_DISTANCE
        changed |= take_nearest(hand[far], hand[~far])
        centre = points.mean(axis=0)
        reach = HAND_REACH * max(np.linalg.norm(points - centre, axis=1).max(), 1.0)
        near = np.linalg.norm(np.asarray(uv, np.float64) - centre, axis=1) <= reach
        for region in (anny_model.TOP, anny_model.TROUSERS):
            clothes = shown & (regions == region) & ~any_hand
            if clothes.sum() < 2:
                continue
            own = np.linalg.norm(colours - np.median(colours[clothes], axis=0), axis=1)
            covered = clothes & near & (to_hand < HAND_COLOUR_DISTANCE) & (own > HAND_COLOUR_DISTANCE)
            changed |= take_nearest(np.flatnonzero(covered), np.flatnonzero(clothes & (own <= HAND_COLOUR_DISTANCE)))
    return sources if changed else None


def fit_width(joints: np.ndarray, *, camera, transform: tuple, size: int, person_mask: np.ndarray,
              phenotype: dict | None = None) -> tuple[dict, float]:
    """Anny's ``weight`` phenotype value whose silhouette in one pose best covers a person's mask (intersection
    over union, over :data:`WEIGHT_GRID`): a stocky person gets a stocky body, a slim one a slim body. The given
    phenotype stays unless another weight covers the mask better by :data:`WIDTH_FIT_MARGIN` (a segmentation mask
    is a few pixels off at the edges).

    Args:
        joints: (17, 3) world joints of the pictured pose; camera, transform, size: as :func:`render_mesh_track`.
        person_mask: (size, size) bool, the person's pixels (BlazePose's segmentation).
        phenotype: the other phenotype values (Anny's defaults when None).
    Returns:
        (phenotype with the fitted weight, its IoU).
    """
    mask = np.asarray(person_mask, bool)
    best, best_iou = dict(phenotype or {}), -1.0
    for weight in (None, *WEIGHT_GRID):  # None: the given phenotype as it is
        candidate = dict(phenotype or {}) if weight is None else {**(phenotype or {}), "weight": weight}
        sil = render_mesh_track(np.asarray(joints, np.float64)[None], phenotype=candidate, camera=camera,
                                transform=transform, size=size, clear_arms=False).masks[0]
        iou = float((sil & mask).sum() / max(1, (sil | mask).sum()))
        if iou > best_iou + (0.0 if weight is None else WIDTH_FIT_MARGIN):  # another width must cover it better
            best, best_iou = candidate, iou
    return best, best_iou


def video_mesh_track(joints3d: np.ndarray, points2d: np.ndarray, *, size: int, phenotype: dict | None = None,
                     person_mask: np.ndarray | None = None) -> MeshTrack:
    """The body mesh of a person seen in a real video, in the pixels of its frames.

    The estimator's 3D joints (canonical metres) pose Anny; a frontal camera fitted over the frames renders it,
    and each frame's 2D similarity (:func:`motion2video.stages.structure.similarity_fit` on the pelvis, legs,
    spine and head) puts the render onto that frame's 2D joints.

    Args:
        joints3d: (N, 17, 3) canonical joints (z up). points2d: (N, 17, 2) the same joints in frame pixels.
        size: the frames' side (square). phenotype: Anny phenotype (its defaults when None).
        person_mask: (size, size) bool the person in frame 0: the body's width is fitted to it (:func:`fit_width`).
    """
    from motion2video.core.camera import fit_camera, project
    from motion2video.stages.structure import ALIGN_JOINTS, similarity_fit

    joints3d = np.asarray(joints3d, np.float64)
    camera = fit_camera(joints3d, size, size, elevation_deg=0.0)
    projected = project(joints3d, camera)[..., :2]  # (N, 17, 2)
    fits = [similarity_fit(p[list(ALIGN_JOINTS)], q[list(ALIGN_JOINTS)]) for p, q in zip(projected, points2d)]
    scales = np.array([f[0] for f in fits])
    shifts = np.stack([f[1] for f in fits])
    if person_mask is not None:
        phenotype, _ = fit_width(joints3d[0], camera=camera, transform=(scales[0], shifts[0]), size=size,
                                 person_mask=person_mask, phenotype=phenotype)
    # the joints are this person's own, observed in every frame: no arms moved out of a torso (moved, dancer.avi's
    # person PSNR fell 21.26 -> 19.88 dB while L1 0.0191 -> 0.0174 and akd 3.42 -> 2.79 px; docs/results.md)
    return render_mesh_track(joints3d, phenotype=phenotype or {}, camera=camera, transform=(scales, shifts),
                             size=size, clear_arms=False)


def sampled_person(video: MeshVideo):
    """(1, 1, S, S) float tensor: the reference pixels whose colours the mesh generator samples (its
    ``source_mask``): the person BlazePose segments in the reference; None when nobody is segmented (the generator
    then samples inside the fitted silhouette it is given). A fitted silhouette reaches past a real person where
    the fit is off (:func:`motion2video.frames.mesh_warp.mesh_source_mask` says what that cost)."""
    import torch

    if video.person is None or not video.person.any():
        return None
    return torch.from_numpy(video.person[None, None].astype(np.float32))


def reference_crop(image: np.ndarray, crop: tuple[int, int, int], size: int) -> np.ndarray:
    """(size, size, 3) uint8: the square ``crop`` (x0, y0, side) of an (S, S, 3) picture at the model's size, as
    the mesh generator sees the reference."""
    import cv2

    x0, y0, side = crop
    part = image[y0:y0 + side, x0:x0 + side]
    return part if side == size else cv2.resize(part, (size, size), interpolation=cv2.INTER_AREA)


def generate_mesh_frames(net, image: np.ndarray, video: MeshVideo, rows: np.ndarray, *,
                         batch_size: int = 8) -> np.ndarray:
    """Frames of the mesh generator for target ``rows`` of ``video``, pasted into the reference.

    Args:
        net: a :class:`motion2video.frames.mesh_warp.MeshWarpGenerator`.
        image: (S, S, 3) uint8 the reference at the output size.
        video: from :func:`mesh_video`.
        rows: (R,) indices into ``video.targets``.
    Returns:
        (R, S, S, 3) uint8.
    """
    import torch

    from motion2video.frames.data import body_structures
    from motion2video.frames.mesh_flow import complete_reference_uv, flows_to_targets, grow_masks
    from motion2video.frames.mesh_warp import mesh_plate, sampled_colours
    from motion2video.frames.warp import MASK_SHARPNESS, part_logits, paste_generated, paste_mask

    size = net.config.image_size
    x0, y0, side = video.crop
    crop = image[y0:y0 + side, x0:x0 + side]
    small = reference_crop(image, video.crop, size)
    x_ref = torch.from_numpy(np.ascontiguousarray(small)).permute(2, 0, 1)[None].float() / 255.0
    ref_mask = torch.from_numpy(grow_masks(video.reference.masks[:1, None], video.margin).astype(np.float32))
    # The background plate removes the mesh's silhouette and the keypoint warp's person region: a real person's
    # hair and clothes reach past the Anny mesh.
    ref_pts = torch.from_numpy(video.ref_points[None]).float()
    region = 1.0 - torch.softmax(MASK_SHARPNESS * part_logits(ref_pts, size, size), dim=1)[:, -1:]
    plate = mesh_plate(x_ref, torch.maximum(ref_mask, (region > 0.05).float()))
    out = np.repeat(image[None], len(rows), axis=0)
    colours = sampled_colours(x_ref, ref_mask, plate, sampled_person(video))  # once for every target
    ref_uv = complete_reference_uv(video.reference.uv[0], video.reference.visible[0], image=small)
    if video.uv_sources is not None:  # a fitted hand beside the pictured one samples the pictured one
        ref_uv = ref_uv[video.uv_sources]
    net.eval()
    rows = np.asarray(rows, np.int64)
    with torch.inference_mode():
        for start in range(0, len(rows), batch_size):
            part = rows[start:start + batch_size]
            flows, vis = flows_to_targets(ref_uv, video.reference.visible[0], video.targets, part, margin=video.margin)
            n = len(part)
            sil = torch.from_numpy(grow_masks(video.targets.masks[part][:, None], video.margin).astype(np.float32))
            structure = torch.from_numpy(body_structures(video.tgt_points[part], size))
            parts = net.forward_parts(x_ref.expand(n, -1, -1, -1), ref_mask.expand(n, -1, -1, -1),
                                      torch.from_numpy(flows), torch.from_numpy(vis)[:, None],
                                      sil, structure, plate=plate.expand(n, -1, -1, -1),
                                      colours=colours.expand(n, -1, -1, -1))
            gen = parts.image.clamp(0, 1).permute(0, 2, 3, 1).numpy()
            region = np.maximum(parts.alpha[:, 0].numpy(), ref_mask[0].numpy())
            alpha = paste_mask(region, size)
            paste_generated(out[start:start + n], crop, (x0, y0, side), gen, alpha)
    return out


def generate_face_mesh_frames(net, image: np.ndarray, structures, rows: np.ndarray, *,
                              batch_size: int = 8) -> np.ndarray:
    """Face frames of the mesh generator for target ``rows`` (0 = the first observed frame) of face
    ``structures``: the reference image moved along the head mesh's correspondence between the reference row
    and each target row (the whole frame: a face close-up fills it).

    Args:
        net: a face :class:`motion2video.frames.mesh_warp.MeshWarpGenerator`.
        image: (S, S, 3) uint8 the reference at the model's size.
        structures: face :class:`motion2video.stages.structure.Structures` with ``face_mesh``.
        rows: (R,) target indices.
    Returns:
        (R, S, S, 3) uint8.
    """
    import torch

    from motion2video.frames.data import face_structures
    from motion2video.frames.mesh_flow import complete_reference_uv, flows_to_targets
    from motion2video.frames.mesh_warp import mesh_plate, person_colours

    track = structures.face_mesh
    size = net.config.image_size
    if image.shape != (size, size, 3) or track.masks.shape[1:] != (size, size):
        raise ValueError(f"the face mesh generator makes {size} px frames: reference {image.shape}, "
                         f"structures {track.masks.shape[1:]}")
    x_ref = torch.from_numpy(np.ascontiguousarray(image)).permute(2, 0, 1)[None].float() / 255.0
    ref_mask = torch.from_numpy(track.masks[:1, None].astype(np.float32))
    plate = mesh_plate(x_ref, ref_mask)
    colours = person_colours(x_ref, ref_mask, plate)  # once for every target
    rows = np.asarray(rows, np.int64)
    out = np.empty((len(rows), size, size, 3), np.uint8)
    ref_uv = complete_reference_uv(track.uv[0], track.visible[0], image=image)
    net.eval()
    with torch.inference_mode():
        for start in range(0, len(rows), batch_size):
            part = rows[start:start + batch_size] + 1  # structure rows (0 = the reference)
            flows, vis = flows_to_targets(ref_uv, track.visible[0], track, part)
            n = len(part)
            gen = net.forward_parts(x_ref.expand(n, -1, -1, -1), ref_mask.expand(n, -1, -1, -1),
                                    torch.from_numpy(flows), torch.from_numpy(vis)[:, None],
                                    torch.from_numpy(track.masks[part][:, None].astype(np.float32)),
                                    torch.from_numpy(face_structures(structures.images[part])),
                                    plate=plate.expand(n, -1, -1, -1), colours=colours.expand(n, -1, -1, -1)).image
            out[start:start + n] = (gen.clamp(0, 1) * 255).round().to(torch.uint8).permute(0, 2, 3, 1).numpy()
    return out
