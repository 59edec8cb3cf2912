"""Generate body frames through a body mesh: the mesh generator's stage, which composes the generator's parts.

The keypoint generators take 2D joints; the mesh generator (:mod:`motion2video.generator.mesh_warp`) takes the
correspondence of one body mesh in the reference pose and in each target pose. This stage makes that mesh
for a placed video (:func:`mesh_video`) and runs the generator on it (:func:`generate_mesh_frames`):

1. **The reference person's body.** Anny with the reference's phenotype (``pose.identity`` of the reference
   pose file, Anny's defaults otherwise), in the reference pose lifted to 3D through the placement's camera
   (:func:`motion2video.generator.mesh_fit.lift_reference`), its weight fitted to the person's mask
   (:func:`~motion2video.generator.mesh_fit.fit_width`), then its surface to the mask's outline
   (:func:`fit_to_person`, :mod:`motion2video.generator.outline_fit`).
2. **Every target pose on that body.** Anny's inverse kinematics follows the driving joints' directions, so
   the target meshes keep the motion's joint angles with the reference person's proportions (one scale for
   the whole video, fitted to leg + torso length; feet flat on the floor near it).
3. **Correspondence.** Each mesh is rendered (depth and silhouette) through the placement's camera
   (:func:`~motion2video.generator.mesh_fit.render_mesh_track`); where the reference lends its colours is decided by
   :mod:`motion2video.generator.mesh_reference`; :func:`motion2video.generator.mesh_flow.dense_flow` makes the flow.

The crop follows the keypoint warp generator's (:func:`motion2video.generator.warp.person_crop`): the person is generated
at the model's size inside a square crop holding both poses and composited with a soft matte over the reference
picture with its person inpainted at the output's resolution (:func:`reference_background`), so the background keeps
its resolution and the reference person leaves no ghost. A skirt or a dress the reference shows across both legs is
laid over each frame as one panel moved with the hips and legs (:mod:`motion2video.generator.garment`), then the
photo's face over each head.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import cv2
import numpy as np
import torch

from motion2video.core.camera import fit_camera, project
from motion2video.core.errors import InputError
from motion2video.core.skeletons import L_WRIST, R_WRIST
from motion2video.generator.background import (MATTE_FEATHER_PX, attached_objects, composite, inpaint_background,
                                               soft_matte)
from motion2video.generator.data import face_structures, pooled_body_structures
from motion2video.generator.garment import Skirt, find_skirt, lay_skirts
from motion2video.generator.head_paste import HeadMoves
from motion2video.generator.mesh_fit import fit_width, lift_reference, reference_crop, render_mesh_track
from motion2video.generator.mesh_flow import MeshTrack, complete_reference_uv, flows_to_targets, grow_masks
from motion2video.generator.mesh_reference import clothes_margin, hand_colour_sources, reference_sampling
from motion2video.generator.mesh_warp import head_cut, mesh_plate, person_colours, sampled_colours
from motion2video.generator.outline_fit import FIT_IOU, pixels_per_metre, surface_offsets
from motion2video.generator.warp import limb_region, person_crop
from motion2video.stages.pictured_face import PicturedFace, face_moves, lay_face
from motion2video.stages.structure import ALIGN_JOINTS, similarity_fit
from renderers import anny_model

# The joints (H36M-17) near which what the person holds is looked for
# (:func:`~motion2video.generator.background.attached_objects`): the wrists. Not the ankles: near the feet, the
# lines of a floor or a road were taken for held things as often as skis were.
ATTACHED_ANCHORS = (L_WRIST, R_WRIST)


@dataclass
class MeshVideo:
    """Everything the mesh generator needs for one video, in the person crop at the model's size.

    Attributes:
        crop: (x0, y0, side) of the square crop in output pixels.
        reference: the reference mesh (1 frame); targets: the target meshes (N frames).
        ref_points, tgt_points: (17, 2) / (N, 17, 2) joints in crop pixels (for the structure maps).
        person: (S, S) bool the person segmented in the reference crop, or None when not segmented.
        margin: pixels (at S) by which the person's clothes and hair reach past the fitted mesh in the reference
            (:func:`~motion2video.generator.mesh_reference.clothes_margin`); every silhouette is grown by it.
        uv_sources: (V,) int64, or None: after the surface completion, vertex v samples where vertex
            ``uv_sources[v]`` does (:func:`~motion2video.generator.mesh_reference.hand_colour_sources`: a fitted hand
            sampling beside the pictured hand).
        background: (S_out, S_out, 3) uint8 the reference picture with its person inpainted
            (:func:`reference_background`), or None (made from the fitted silhouette and the joints when needed).
        face: the face the reference photo shows (:func:`motion2video.stages.pictured_face.reference_face`), laid over
            every generated head where the head faces as it does in the photo; None: the generator's heads stay.
        head: where the pictured face goes in each target (output pixels of the reference -> of the target) and
            how much of it each target takes (:func:`motion2video.stages.pictured_face.face_moves`); None without a
            face.
        skirt: cloth the reference shows hanging from the hips across both legs
            (:func:`motion2video.generator.garment.find_skirt`), laid over every frame as one panel moved with the
            hips and legs; None: none found.
    """

    crop: tuple[int, int, int]
    reference: MeshTrack
    targets: MeshTrack
    ref_points: np.ndarray
    tgt_points: np.ndarray
    person: np.ndarray | None = None
    margin: int = 0
    uv_sources: np.ndarray | None = None
    background: np.ndarray | None = None
    face: PicturedFace | None = None
    head: HeadMoves | None = None
    skirt: Skirt | None = None


def view_crop(view: tuple[float, float, float], size: int) -> tuple[int, int, int]:
    """(x0, y0, side) integer square of a (size, size) picture nearest the square ``view`` (x0, y0, side), inside it."""
    side = int(min(size, max(8, round(view[2]))))
    x0 = int(np.clip(round(view[0]), 0, size - side))
    y0 = int(np.clip(round(view[1]), 0, size - side))
    return x0, y0, side


def joints_in(points: np.ndarray, picture: np.ndarray) -> np.ndarray:
    """(17,) bool: which joints (17, 2) pixels lie on a (H, W) map's true pixels (the picture's own, not a pad)."""
    pts = np.round(np.asarray(points, np.float64)).astype(int)
    h, w = picture.shape[:2]
    inside = (pts[:, 0] >= 0) & (pts[:, 0] < w) & (pts[:, 1] >= 0) & (pts[:, 1] < h)
    shown = np.zeros(len(pts), bool)
    shown[inside] = np.asarray(picture, bool)[pts[inside, 1], pts[inside, 0]]
    return shown


def mesh_video(placement, reference_points: np.ndarray, target_rows: np.ndarray, *, phenotype: dict,
               output_size: int, model_size: int, person=None, image: np.ndarray | None = None,
               fit_to_mask: bool = True, pictured: np.ndarray | None = None,
               face: PicturedFace | None = None, from_file: np.ndarray | None = None,
               view: tuple[float, float, float] | None = None) -> MeshVideo:
    """The meshes of a placed body video.

    Args:
        placement: the :class:`motion2video.stages.structure.BodyPlacement` (3D: world joints and camera).
        reference_points: (17, 2) the reference pose in output pixels.
        target_rows: (N, 17, 2) the target joints in output pixels (to place the crop).
        phenotype: the reference person's Anny phenotype.
        output_size: the output frames' side; model_size: the generator's.
        person: what BlazePose found of the reference person in output pixels
            (:class:`motion2video.stages.reference.ReferencePerson`), or None. Anny's weight is fitted to its mask
            (:func:`~motion2video.generator.mesh_fit.fit_width`, when ``fit_to_mask``), then its surface to the mask's
            outline (:func:`fit_to_person`); where the colours are sampled,
            a vertex the reference mesh shows counts as shown only where it lands on the person, and the fitted head
            is moved onto its eyes
            (:func:`~motion2video.generator.mesh_reference.reference_sampling`).
        image: (output_size, output_size, 3) uint8 the reference picture, or None: a fitted hand vertex that lands
            beside the pictured hand samples where a hand vertex on it does
            (:func:`~motion2video.generator.mesh_reference.hand_colour_sources`).
        pictured: (17, 3) the reference picture's own 3D pose in its camera's axes (its pose file's
            ``camera_joints``), or None (:func:`~motion2video.generator.mesh_fit.lift_reference`).
        face: the reference photo's face (:func:`motion2video.stages.pictured_face.reference_face`), or None.
        from_file: (output_size, output_size) bool the pixels of ``image`` that come from the image file, or None (all
            of them): a border the pipeline replicated around a photo is inpainted with the person
            (:func:`reference_background`).
        view: (x0, y0, side) the square of the output the frames are cut to
            (:attr:`motion2video.stages.reference.Reference.view`), or None: the person is generated in that square
            at the model's size, not in the square around every pose (a half-length portrait's guessed legs, out of
            view, would shrink the pictured part to a third of the model's pixels).
    Raises:
        InputError: the placement has no 3D joints (a 2D motion model).
    """
    if placement.world_observed is None or placement.camera is None:
        raise InputError("the mesh frame generator needs a 3D body motion (this motion model predicts 2D "
                         "keypoints); use --frame-model frames-body-128")
    world = np.concatenate([placement.world_observed, placement.world_futures.reshape(-1, 17, 3)])  # (N, 17, 3)
    scale, shift = placement.scale, placement.shift
    if view is None:
        x0, y0, side = person_crop(reference_points, target_rows, width=output_size, height=output_size,
                                   model_size=model_size)
    else:
        x0, y0, side = view_crop(view, output_size)
    k = model_size / side
    to_crop = (scale * k, (np.asarray(shift) - [x0, y0]) * k)
    lifted = lift_reference(reference_points, world[0], placement.camera, scale, shift, pictured=pictured,
                            shown=None if from_file is None else joints_in(reference_points, from_file))
    small, seen, offsets = None, None, None
    if person is not None:
        seen = person.moved(k, -np.array([x0, y0]) * k, (model_size, model_size))
        small = seen.segmented()
        if fit_to_mask:
            phenotype, offsets = fit_to_person(lifted, camera=placement.camera, transform=to_crop, size=model_size,
                                               person_mask=small, phenotype=phenotype)
    both = render_mesh_track(np.concatenate([lifted[None], world]), phenotype=phenotype, camera=placement.camera,
                             transform=to_crop, size=model_size, clear_arms=np.arange(len(world) + 1) > 0,
                             offsets=offsets)
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
    video = MeshVideo((x0, y0, side), ref, tgt, ref_pts.astype(np.float32), tgt_pts.astype(np.float32), person=small,
                      margin=margin, uv_sources=sources)
    if face is not None:  # the fitted face's move, in output pixels
        corner = np.array([x0, y0], np.float64)
        video.face = face
        # the reference's vertices as its colours are sampled: the fitted face moved onto the pictured eyes
        video.head = face_moves(face, ref_uv / k + corner, tgt.uv / k + corner, tgt.visible, rest=rest)
    if image is not None:
        video.background = reference_background(image, video, None if person is None else person.mask,
                                                 reference_points, from_file=from_file)
        if person is not None:
            video.skirt = find_skirt(image, person.mask, reference_points)
    return video


def reference_background(image: np.ndarray, video: MeshVideo, person: np.ndarray | None,
                         points: np.ndarray, *, from_file: np.ndarray | None = None) -> np.ndarray:
    """(S, S, 3) uint8: the reference picture with its person inpainted
    (:func:`motion2video.generator.background.inpaint_background`), the background every generated person is
    composited over.

    The hole is the person BlazePose segments (or the picture's alpha channel, ``person`` (S, S) in [0, 1]) joined
    with the fitted reference body's silhouette grown by the clothes margin, which covers a limb the segmentation
    missed; with no segmented person, the silhouette joined with the pose's limbs drawn thick
    (:func:`motion2video.generator.warp.limb_region` of ``points`` (17, 2), output pixels), as hair and clothes reach
    past the body model.

    What the person holds, thin and outside the segmentation (a bar, ski poles), is filled too
    (:func:`~motion2video.generator.background.attached_objects` near the wrists): left in the picture, it stayed
    where it was pictured while the person moved away from it.

    A border the pipeline replicated around the photo (``from_file`` (S, S) bool False there: ``--crop-person``'s pad,
    ``--fit-view``'s zoom) is filled too: replicated, the picture's edge drew stretched stripes, and of a person cut by
    that edge (legs below the frame) a ghost of their legs that stayed where they were in every frame.
    """
    h, w = image.shape[:2]
    x0, y0, side = video.crop
    silhouette = grow_masks(video.reference.masks[:1, None], video.margin)[0, 0].astype(np.float32)
    hole = np.zeros((h, w), np.float32)
    hole[y0:y0 + side, x0:x0 + side] = cv2.resize(silhouette, (side, side), interpolation=cv2.INTER_LINEAR)
    if person is not None and (np.asarray(person) > 0.5).any():
        hole = np.maximum(hole, np.asarray(person, np.float32))
        held = attached_objects(image, person, points[list(ATTACHED_ANCHORS)], picture=from_file)
        hole = np.maximum(hole, held.astype(np.float32))
    else:
        hole = np.maximum(hole, limb_region(points, width=w, height=h).astype(np.float32))
    if from_file is not None:
        hole = np.where(np.asarray(from_file, bool), hole, 1.0)
    return inpaint_background(image, hole)


def video_mesh_track(joints3d: np.ndarray, points2d: np.ndarray, *, size: int, phenotype: dict | None = None,
                     person_mask: np.ndarray | None = None) -> tuple[MeshTrack, dict]:
    """The body mesh of a person seen in a real video, in the pixels of its frames.

    The estimator's 3D joints (canonical metres) pose Anny; a frontal camera fitted over the frames renders it,
    and each frame's 2D similarity (:func:`motion2video.stages.structure.similarity_fit` on the pelvis, legs,
    spine and head) puts the render onto that frame's 2D joints.

    Args:
        joints3d: (N, 17, 3) canonical joints (z up). points2d: (N, 17, 2) the same joints in frame pixels.
        size: the frames' side (square). phenotype: Anny phenotype (its defaults when None).
        person_mask: (size, size) bool the person in frame 0: the body's width is fitted to it
            (:func:`~motion2video.generator.mesh_fit.fit_width`), then its surface to its outline
            (:func:`fit_to_person`).
    Returns:
        the track, and the phenotype it was rendered with (the fitted width's).
    """
    joints3d = np.asarray(joints3d, np.float64)
    camera = fit_camera(joints3d, size, size, elevation_deg=0.0)
    projected = project(joints3d, camera)[..., :2]  # (N, 17, 2)
    fits = [similarity_fit(p[list(ALIGN_JOINTS)], q[list(ALIGN_JOINTS)]) for p, q in zip(projected, points2d)]
    scales = np.array([f[0] for f in fits])
    shifts = np.stack([f[1] for f in fits])
    offsets = None
    if person_mask is not None:
        phenotype, offsets = fit_to_person(joints3d[0], camera=camera, transform=(scales[0], shifts[0]), size=size,
                                           person_mask=person_mask, phenotype=phenotype)
    # the joints are this person's own, observed in every frame: no arms moved out of a torso (moved, dancer.avi's
    # person PSNR fell 21.26 -> 19.88 dB while L1 0.0191 -> 0.0174 and akd 3.42 -> 2.79 px; docs/results.md)
    phenotype = phenotype or {}
    return render_mesh_track(joints3d, phenotype=phenotype, camera=camera, transform=(scales, shifts), size=size,
                             clear_arms=False, offsets=offsets), phenotype


def fit_to_person(joints: np.ndarray, *, camera, transform: tuple, size: int, person_mask: np.ndarray,
                  phenotype: dict | None) -> tuple[dict, np.ndarray | None]:
    """Anny fitted to a pictured person's mask: its weight (:func:`~motion2video.generator.mesh_fit.fit_width`), then,
    unless that body already covers the mask (intersection over union :data:`~motion2video.generator.outline_fit.
    FIT_IOU`), its surface to the mask's outline (:func:`outline_surface`).

    Args:
        joints: (17, 3) world joints of the pictured pose; camera, transform, size: as
            :func:`~motion2video.generator.mesh_fit.render_mesh_track` (one frame).
        person_mask: (size, size) bool the person's pixels; phenotype: the other phenotype values (None: Anny's).
    Returns:
        (the phenotype with the fitted weight, (V, 3) rest offsets in metres or None).
    """
    phenotype, iou = fit_width(joints, camera=camera, transform=transform, size=size, person_mask=person_mask,
                               phenotype=phenotype)
    if iou >= FIT_IOU:
        return phenotype, None
    return phenotype, outline_surface(joints, camera=camera, transform=transform, size=size, person_mask=person_mask,
                                      phenotype=phenotype)


def outline_surface(joints: np.ndarray, *, camera, transform: tuple, size: int, person_mask: np.ndarray,
                    phenotype: dict | None) -> np.ndarray:
    """(V, 3) metres: Anny's rest surface moved so that, posed on the pictured ``joints`` (17, 3), its outline is
    the person's (:func:`motion2video.generator.outline_fit.surface_offsets`).

    Args:
        joints: (17, 3) world joints of the pictured pose; camera, transform, size: as
            :func:`~motion2video.generator.mesh_fit.render_mesh_track` (one frame).
        person_mask: (size, size) bool the person's pixels; phenotype: the fitted phenotype.
    """
    phenotype = phenotype or {}
    joints = np.asarray(joints, np.float64)[None]
    seen = render_mesh_track(joints, phenotype=phenotype, camera=camera, transform=transform, size=size,
                             clear_arms=False)
    per_metre = pixels_per_metre(camera, joints[0, 0], float(transform[0]))
    return surface_offsets(seen.uv[0], seen.masks[0], person_mask, rest=anny_model.anny_rest(phenotype),
                           per_metre=per_metre)


def sampled_person(video: MeshVideo):
    """(1, 1, S, S) float tensor: the reference pixels whose colours the mesh generator samples (its
    ``source_mask``): the person BlazePose segments in the reference; None when nobody is segmented (the generator
    then samples inside the fitted silhouette it is given). A fitted silhouette reaches past a real person where
    the fit is off (:func:`motion2video.generator.mesh_warp.mesh_source_mask` says what that cost)."""
    if video.person is None or not video.person.any():
        return None
    return torch.from_numpy(video.person[None, None].astype(np.float32))


def generate_mesh_frames(net, image: np.ndarray, video: MeshVideo, rows: np.ndarray, *,
                         batch_size: int = 8) -> np.ndarray:
    """Frames of the mesh generator for target ``rows`` of ``video``: the generated person (at the model's size,
    resized to the crop) laid over the reference's background (``video.background``, :func:`reference_background`)
    through its soft matte (:func:`motion2video.generator.background.soft_matte` of the generator's alpha), so where
    the reference person stood shows the background, and no background colour is mixed into the person. With a
    pictured face (``video.face``) the photo's face is laid over each generated head, moved as the fitted face moves
    and faded out as the head turns away (:func:`motion2video.stages.pictured_face.lay_face`). The flows of the next
    batch are read in one worker thread while the network runs on this one.

    Args:
        net: a :class:`motion2video.generator.mesh_warp.MeshWarpGenerator`.
        image: (S, S, 3) uint8 the reference at the output size.
        video: from :func:`mesh_video`.
        rows: (R,) indices into ``video.targets``.
    Returns:
        (R, S, S, 3) uint8.
    """

    size = net.config.image_size
    x0, y0, side = video.crop
    small = reference_crop(image, video.crop, size)
    x_ref = torch.from_numpy(np.ascontiguousarray(small)).permute(2, 0, 1)[None].float() / 255.0
    ref_mask = torch.from_numpy(grow_masks(video.reference.masks[:1, None], video.margin).astype(np.float32))
    background = video.background
    if background is None:
        background = reference_background(image, video, None, (video.ref_points * side / size) + [x0, y0])
    # the network's plate is the same background, at its size
    plate = torch.from_numpy(np.ascontiguousarray(reference_crop(background, video.crop, size))).permute(2, 0, 1)[
        None].float() / 255.0
    behind = background[y0:y0 + side, x0:x0 + side]
    out = np.repeat(background[None], len(rows), axis=0)
    segmented = sampled_person(video)
    colours = sampled_colours(x_ref, ref_mask, plate, segmented)  # once for every target
    # the head's halo cut off (head_cut): where the flow lands beside the pictured head, the background
    cut = None if segmented is None else torch.from_numpy(head_cut(video.person.astype(np.float32),
                                                                    video.ref_points))[None, None]
    ref_uv = complete_reference_uv(video.reference.uv[0], video.reference.visible[0], image=small,
                                   person=video.person)
    if video.uv_sources is not None:  # a fitted hand beside the pictured one samples the pictured one
        ref_uv = ref_uv[video.uv_sources]
    net.eval()
    rows = np.asarray(rows, np.int64)
    starts = range(0, len(rows), batch_size)

    def correspondence(start: int) -> tuple[np.ndarray, np.ndarray]:
        return flows_to_targets(ref_uv, video.reference.visible[0], video.targets, rows[start:start + batch_size],
                                margin=video.margin)

    with torch.inference_mode(), ThreadPoolExecutor(max_workers=1) as ahead:
        # the next batch's flows (NumPy and SciPy, which release the GIL in their loops) are read while the network
        # and the compositing run on this one
        pending = ahead.submit(correspondence, 0) if len(rows) else None
        for start in starts:
            part = rows[start:start + batch_size]
            flows, vis = pending.result()
            if start + batch_size < len(rows):
                pending = ahead.submit(correspondence, start + batch_size)
            n = len(part)
            sil = torch.from_numpy(grow_masks(video.targets.masks[part][:, None], video.margin).astype(np.float32))
            structure = torch.from_numpy(pooled_body_structures(video.tgt_points[part], size, net.config.net_scale))
            parts = net.forward_parts(x_ref.expand(n, -1, -1, -1), ref_mask.expand(n, -1, -1, -1),
                                      torch.from_numpy(flows), torch.from_numpy(vis)[:, None],
                                      sil, structure, plate=plate.expand(n, -1, -1, -1),
                                      colours=colours.expand(n, -1, -1, -1),
                                      person_cut=None if cut is None else cut.expand(n, -1, -1, -1))
            person = parts.person.clamp(0, 1).permute(0, 2, 3, 1).numpy()  # (n, size, size, 3)
            alpha = parts.alpha[:, 0].numpy()  # (n, size, size)
            if side != size:
                person = np.stack([cv2.resize(p, (side, side), interpolation=cv2.INTER_CUBIC) for p in person])
                alpha = np.stack([cv2.resize(a, (side, side), interpolation=cv2.INTER_LINEAR) for a in alpha])
            # the feather is MATTE_FEATHER_PX at the model's size: a person enlarged to a bigger output (--size 512)
            # keeps the model's outline, whose stair of pixels grows with it
            matte = soft_matte(alpha, feather_px=MATTE_FEATHER_PX * side / size)
            out[start:start + n, y0:y0 + side, x0:x0 + side] = composite(behind, person, matte)
            if video.skirt is not None:  # a skirt or a dress: one panel over both legs, the arms in front
                points = video.tgt_points[part] * (side / size) + [x0, y0]  # output pixels
                out[start:start + n] = lay_skirts(out[start:start + n], video.skirt, points)
            if video.face is not None:  # the photo's own face over the generated heads, inside the generated person
                face = video.face
                for i, row in enumerate(part):
                    within = np.zeros(out.shape[1:3], np.float32)
                    within[y0:y0 + side, x0:x0 + side] = matte[i]
                    out[start + i] = lay_face(out[start + i], face, video.head, row, within=within)
    return out


def generate_face_mesh_frames(net, image: np.ndarray, structures, rows: np.ndarray, *,
                              batch_size: int = 8) -> np.ndarray:
    """Face frames of the mesh generator for target ``rows`` (0 = the first observed frame) of face
    ``structures``: the reference image moved along the head mesh's correspondence between the reference row
    and each target row (the whole frame: a face close-up fills it).

    Args:
        net: a face :class:`motion2video.generator.mesh_warp.MeshWarpGenerator`.
        image: (S, S, 3) uint8 the reference at the model's size.
        structures: face :class:`motion2video.stages.structure.Structures` with ``face_mesh``.
        rows: (R,) target indices.
    Returns:
        (R, S, S, 3) uint8.
    """

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
