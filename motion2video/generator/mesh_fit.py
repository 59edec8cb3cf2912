"""The Anny body fitted to a pictured person and its correspondence track: what the mesh generator
(:mod:`motion2video.generator.mesh_warp`) takes as input for a picture and a motion.

:func:`lift_reference` lifts a picture's 2D joints to 3D (on their pixels' rays, at the pictured bone lengths
when the picture's own 3D pose is known); :func:`fit_width` picks Anny's weight whose silhouette best covers the
person's mask; :func:`render_mesh_track` poses that one body on every frame's joints and renders each vertex's
pixel and front-surface flag (:class:`motion2video.generator.mesh_flow.MeshTrack`) through a camera widened to the
whole output square (:func:`camera_covering`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np

from motion2video.core.camera import affine_matrix, project
from motion2video.core.skeletons import H36M_17
from motion2video.generator.mesh_flow import MeshTrack
from renderers import anny_model
from renderers.body import fitted_scale, pose_anny_from_joints, posed_vertices
from renderers.collision import arms_clear_of_torso
from renderers.mesh import MeshRenderer, vertex_visibility

MASK_GREY = (200, 200, 200)  # the colour the correspondence renders use (only depth and silhouette are read)
# Anny "weight" values tried when fitting the body's width to the reference person's silhouette (fit_width).
WEIGHT_GRID = (0.15, 0.3, 0.45, 0.6, 0.75, 0.9)
WIDTH_FIT_MARGIN = 0.01  # IoU another weight must gain over the given phenotype's to replace it
MIN_SCALE_BONES = 4  # lift_by_bones: fewer bones between shown joints than this, and all bones set the scale


def lift_reference(points: np.ndarray, guide: np.ndarray, camera, scale: float, shift: np.ndarray, *,
                   pictured: np.ndarray | None = None, shown: np.ndarray | None = None) -> np.ndarray:
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
        shown: (17,) bool the joints the picture shows, or None (all): only bones between shown joints set the
            picture's scale (:func:`lift_by_bones`).
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
    return origin[None] + lift_by_bones(rays, np.asarray(pictured, np.float64), f, pix, shown=shown) @ axes


def lift_by_bones(rays: np.ndarray, pictured: np.ndarray, focal: float, pixels: np.ndarray, *,
                  shown: np.ndarray | None = None) -> np.ndarray:
    """(17, 3) camera-axes joints on ``rays`` (17, 3) with the bone lengths and depth steps of ``pictured`` (17, 3,
    camera axes); ``pixels`` (17, 2) and ``focal`` give the picture's scale (see :func:`lift_reference`), from the
    bones between ``shown`` (17,) joints when there are at least :data:`MIN_SCALE_BONES` of them (the legs a
    half-length portrait's pose estimate guesses below the picture are shorter than the person's)."""
    bones = [(j, p) for j, p in enumerate(H36M_17.parents) if p >= 0]
    lengths = {j: float(np.linalg.norm(pictured[j] - pictured[p])) for j, p in bones}
    scaling = bones
    if shown is not None:
        inside = [(j, p) for j, p in bones if shown[j] and shown[p]]
        scaling = inside if len(inside) >= MIN_SCALE_BONES else bones
    # A bone can look shorter than it is (foreshortened), never longer: the pelvis goes where the bones that look
    # longest for their length lie in the picture's plane. The 10% quantile, not the minimum: one keypoint a few
    # pixels off should not move the whole body.
    ratio = [focal * lengths[j] / max(float(np.linalg.norm(pixels[j] - pixels[p])), 1e-6) for j, p in scaling]
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


def track_resolution(camera, scales: np.ndarray) -> tuple[object, np.ndarray]:
    """The square camera at the track's resolution when every frame shows its pixels smaller (all ``scales`` (N,)
    below 1), with the scales from its pixels: a 512 px output whose person the generator draws at 256 was rendered
    at 512 and then shrunk, four times the pixels the track keeps. Same centre and field of view, so each pixel
    coordinate scales by the side's ratio exactly (:func:`motion2video.core.camera.project`). Other cameras come back
    as they are."""
    top = float(np.max(scales))
    if top >= 1.0 or camera.width != camera.height:
        return camera, scales
    side = int(np.ceil(camera.height * top))
    ratio = side / camera.height
    return type(camera)(camera.position, camera.target, camera.yfov, side, side), scales / ratio


def render_mesh_track(joints: np.ndarray, *, phenotype: dict, camera, transform: tuple,
                      size: int, progress=None, clear_arms: bool | np.ndarray = True,
                      offsets: np.ndarray | None = None) -> MeshTrack:
    """Pose Anny on ``joints`` and render its correspondence.

    In the frames ``clear_arms`` picks (True: all; or (N,) bool), elbows and wrists that fall inside the torso are
    moved out of it first (``renderers.collision``): a mocap actor's arms pass where this person's fitted, often
    wider, body is. A pictured person's own pose (a reference, a video's frames) is left as it is. Where two
    surfaces of the body meet in a frame (a forearm held against the waist, a hand beside a thigh), only the front
    one counts as shown (``renderers.mesh.behind_a_touching_surface``). Each render is read (visibility, pixels,
    silhouette) in one worker thread while the next one renders.

    Args:
        joints: (N, 17, 3) world joints (one body: a single size is fitted over all frames).
        phenotype: Anny phenotype values.
        camera: the render camera (PinholeCamera).
        transform: ``(a, b)``: the camera's pixels map to the track's by ``x * a + b``; ``a`` a float and ``b``
            (2,), or per frame: ``a`` (N,) and ``b`` (N, 2).
        size: the track's image side (square).
        progress: called with the number of frames done.
        offsets: (V, 3) metres added to the rest vertices (the surface fitted to a pictured person's outline,
            :func:`motion2video.generator.outline_fit.surface_offsets`), or None.
    Returns:
        The :class:`MeshTrack`.
    """

    n = len(joints)
    scales = np.broadcast_to(np.asarray(transform[0], np.float64), (n,))
    shifts = np.broadcast_to(np.asarray(transform[1], np.float64), (n, 2))
    camera, scales = track_resolution(camera, scales)
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

    def read(i: int, v: np.ndarray, depth: np.ndarray, mask: np.ndarray) -> None:
        """Frame ``i``'s correspondence from its render."""
        uvz = project(v, camera)
        # where two surfaces meet, only the front one is shown: in a target so that the flow does not alternate
        # between them, in the reference so that the one behind (a thigh under the hand) does not carry the other's
        # pixel when a target moves them apart
        visible[i] = vertex_visibility(uvz, depth, rest=rest)
        uv[i] = uvz[:, :2] * scales[i] + shifts[i]
        m = cv2.warpAffine(mask.astype(np.float32), affine_matrix(scales[i], shifts[i]), (size, size),
                           flags=cv2.INTER_LINEAR)
        masks[i] = m > 0.5

    # a frame is read in a second thread while the next one renders (OSMesa and NumPy release the GIL)
    reading = ThreadPoolExecutor(max_workers=1)
    pending = []
    try:
        for start, verts in posed_vertices(pose, offsets=offsets):
            if uv is None:
                uv = np.zeros((n, verts.shape[1], 2), np.float32)
                visible = np.zeros((n, verts.shape[1]), bool)
            for k, v in enumerate(verts):
                out = renderer.render_mesh(v, faces, vertex_colors=MASK_GREY, camera=camera)
                pending.append(reading.submit(read, start + k, v, out.depth, out.mask))
            for job in pending:
                job.result()
            pending.clear()
            if progress is not None:
                progress(len(verts))
    finally:
        reading.shutdown(wait=True, cancel_futures=True)
        renderer.close()
    return MeshTrack(uv=uv, visible=visible, masks=masks)


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


def reference_crop(image: np.ndarray, crop: tuple[int, int, int], size: int) -> np.ndarray:
    """(size, size, 3) uint8: the square ``crop`` (x0, y0, side) of an (S, S, 3) picture at the model's size, as
    the mesh generator sees the reference."""
    x0, y0, side = crop
    part = image[y0:y0 + side, x0:x0 + side]
    return part if side == size else cv2.resize(part, (size, size), interpolation=cv2.INTER_AREA)
