"""The Anny body posed from canonical H36M-17 joints by inverse kinematics, rendered with pyrender.

Inverse kinematics (:func:`pose_anny_from_joints`) writes one world transform per Anny bone, which
Anny's forward takes with ``pose_parameterization="world"``:

1. Scale: the clip's size differs from Anny's, so the whole mesh is scaled uniformly by
   ``scale = clip (leg + pelvis-to-shoulders) length / Anny's`` (median over frames). IK runs in Anny's
   own size on ``joints / scale`` and the posed vertices are multiplied back by ``scale``.
2. Pelvis: the root's orientation is the frame of the hip line (right hip -> left hip) and the lower
   spine (pelvis -> spine), relative to the same frame in Anny's rest pose; its head goes on the pelvis.
3. Chest: the same from the shoulder line and pelvis-side spine -> shoulder midpoint; the five spine bones
   rotate from the pelvis's to the chest's orientation (spherical interpolation) and keep Anny's spine
   lengths, with the remaining gap to the chest spread along them so ``spine01`` lands where the
   shoulders put it.
4. Limbs: down each chain (upper leg -> lower leg -> foot, clavicle -> upper arm -> lower arm -> wrist,
   neck -> head) a bone first inherits its parent's rotation, then turns by the swing (the smallest
   rotation, no twist) that takes its inherited direction to the target direction, and its head is put
   on the target joint (so the rendered joints land on the clip's joints; the small length mismatch
   left after scaling is absorbed by the skinning). The neck and head keep Anny's lengths and only
   follow the neck -> head direction, because the clip's neck/head joints are defined differently by
   different rigs.
5. Bones no joint drives (upperleg02, lowerarm02, fingers, toes, eyes, ...) follow their parent rigidly.
6. Feet: a foot near the clip's floor level is turned flat (only the heading of its shin is kept);
   a raised foot follows its shin; in between they are blended.

Rendering: :class:`BodyRenderer` batches Anny's forward (``BodyStyle.batch`` frames at a time), colours
vertices by body region (skin / top / trousers / shoes / hair / eyes, from the skinning weights) and draws
them through the process-wide :class:`~renderers.mesh.MeshRenderer` backend.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Iterator, Mapping

import numpy as np

from motion2video.core.camera import PinholeCamera, fit_camera, project
from motion2video.core.errors import InputError
from motion2video.core.motion import Motion
from motion2video.core.rotations import frame_from_axes, slerp_rotations, swing_rotation
from motion2video.core.skeletons import (
    PELVIS, R_HIP, R_KNEE, R_ANKLE, L_HIP, L_KNEE, L_ANKLE, SPINE, NECK, HEAD,
    L_SHOULDER, L_ELBOW, L_WRIST, R_SHOULDER, R_ELBOW, R_WRIST,
)
from renderers import anny_model
from renderers.anny_model import AnnyRest
from renderers.base import RendererBase
from renderers.mesh import MeshRenderer, vertex_visibility


SPINE_BONES = ("spine05", "spine04", "spine03", "spine02", "spine01")
SPINE_BLEND = (0.1, 0.3, 0.55, 0.8, 1.0)  # pelvis -> chest orientation weight per spine bone
NECK_TILT_RANGE = (6.0, 24.0)  # plausible clip-median forward tilt of neck -> head, degrees (Anny: 14)
HEAD_DEPTH_TOLERANCE = 1e-3  # relative depth difference within which the head is the body's front surface
KEEP_VERTICES_FRAMES = 300  # clips up to this long keep their posed vertices between camera fit and render
FLAT_FOOT_RANGE = 0.12  # metres above the clip's floor level over which a foot turns from flat to free


# --- inverse kinematics ------------------------------------------------------------------------------


@dataclass(frozen=True)
class AnnyPose:
    """Anny bone poses fitted to a joint sequence.

    Attributes:
        bone_poses: (T, 104, 4, 4) float64 world transform of every bone in Anny's own size (pass to
            Anny's forward with ``pose_parameterization="world"``).
        scale: uniform scale from Anny's size to the clip's: world vertices = ``scale`` * Anny vertices.
        phenotype: the 6 Anny phenotype values the pose was fitted for.
    """

    bone_poses: np.ndarray
    scale: float
    phenotype: tuple[float, ...]


def body_size(joints: np.ndarray) -> np.ndarray:
    """Per-frame leg + torso length: mean of the two (thigh + shin) plus pelvis -> shoulder midpoint.

    Args:
        joints: (..., 17, 3) canonical joints.
    Returns:
        (...) lengths in the joints' unit.
    """
    j = np.asarray(joints, np.float64)

    def seg(a: int, b: int) -> np.ndarray:
        return np.linalg.norm(j[..., a, :] - j[..., b, :], axis=-1)

    legs = 0.5 * (seg(R_HIP, R_KNEE) + seg(R_KNEE, R_ANKLE) + seg(L_HIP, L_KNEE) + seg(L_KNEE, L_ANKLE))
    shoulders = 0.5 * (j[..., L_SHOULDER, :] + j[..., R_SHOULDER, :])
    torso = np.linalg.norm(shoulders - j[..., PELVIS, :], axis=-1)
    return legs + torso


def _pelvis_frame(j: np.ndarray) -> np.ndarray:
    """(..., 3, 3) pelvis frame: x along right hip -> left hip, z towards the spine joint."""
    return frame_from_axes(j[..., L_HIP, :] - j[..., R_HIP, :], j[..., SPINE, :] - j[..., PELVIS, :])


def _chest_frame(j: np.ndarray) -> np.ndarray:
    """(..., 3, 3) chest frame: x along right shoulder -> left shoulder, z from the spine joint towards
    the shoulder midpoint."""
    mid = 0.5 * (j[..., L_SHOULDER, :] + j[..., R_SHOULDER, :])
    return frame_from_axes(j[..., L_SHOULDER, :] - j[..., R_SHOULDER, :], mid - j[..., SPINE, :])


def fitted_scale(joints: np.ndarray, rest: AnnyRest) -> float:
    """The uniform size of Anny posed on (T, 17, 3) canonical ``joints``: the median over frames of their leg +
    torso length (:func:`body_size`) over ``rest``'s."""
    return float(np.median(body_size(joints)) / body_size(rest.joints17))


def pose_anny_from_joints(
    joints: np.ndarray,
    *,
    phenotype: Mapping[str, float] | None = None,
    fit_scale: bool = True,
    flat_feet: bool = True,
) -> AnnyPose:
    """Anny bone world transforms that put Anny's joints on a canonical H36M-17 joint sequence.

    Args:
        joints: (T, 17, 3) canonical joints, world metres, z up (a (17, 3) single pose is accepted too).
        phenotype: Anny phenotype values (missing ones 0.5).
        fit_scale: scale Anny uniformly to the clip's leg + torso length; if False the scale is 1.
        flat_feet: turn feet flat near the clip's floor level (see the module docstring).
    Returns:
        The fitted :class:`AnnyPose`.
    """
    j_world = np.asarray(joints, dtype=np.float64)
    if j_world.ndim == 2:
        j_world = j_world[None]
    if j_world.ndim != 3 or j_world.shape[1:] != (17, 3):
        raise ValueError(f"joints must be (T, 17, 3) canonical h36m-17, got {j_world.shape}")
    rest = anny_model.anny_rest(phenotype)
    scale = 1.0
    if fit_scale:
        scale = fitted_scale(j_world, rest)
        if not np.isfinite(scale) or scale <= 1e-3:
            raise ValueError(f"cannot fit Anny's size to these joints (scale {scale})")
    j = j_world / scale  # (T, 17, 3) in Anny's size
    G, h = _solve_bones(j, rest, flat_feet=flat_feet)
    num_frames, num_bones = G.shape[:2]
    poses = np.zeros((num_frames, num_bones, 4, 4))
    poses[..., :3, :3] = G @ rest.bone_poses[:, :3, :3]  # rotate each bone's rest frame
    poses[..., :3, 3] = h
    poses[..., 3, 3] = 1.0
    return AnnyPose(bone_poses=poses, scale=scale, phenotype=rest.phenotype)


def _solve_bones(j: np.ndarray, rest: AnnyRest, *, flat_feet: bool) -> tuple[np.ndarray, np.ndarray]:
    """Per-bone world rotation change G (T, B, 3, 3) from the rest pose and world head h (T, B, 3)."""
    names = anny_model.bone_names()
    parents = anny_model.bone_parents()
    idx = {n: i for i, n in enumerate(names)}
    H = rest.bone_heads  # (B, 3)
    num_frames, num_bones = j.shape[0], len(names)
    G = np.zeros((num_frames, num_bones, 3, 3))
    h = np.zeros((num_frames, num_bones, 3))
    done = np.zeros(num_bones, dtype=bool)

    def follow(b: int) -> None:
        p = parents[b]
        G[:, b] = G[:, p]
        h[:, b] = h[:, p] + G[:, p] @ (H[b] - H[p])
        done[b] = True

    def swing_to(b: int, child: int, target_dir: np.ndarray, head: np.ndarray | None) -> None:
        """Bone b inherits its parent's rotation, then swings its (head -> child head) direction onto
        target_dir; head None keeps the rigidly-followed head."""
        follow(b)
        inherited = G[:, b] @ (H[child] - H[b])  # (T, 3)
        G[:, b] = swing_rotation(inherited, target_dir) @ G[:, b]
        if head is not None:
            h[:, b] = head

    # Root / pelvis.
    r = idx["root"]
    G[:, r] = _pelvis_frame(j) @ _pelvis_frame(rest.joints17).T
    # the canonical pelvis is the hips' midpoint (Human3.6M's body point), not quite Anny's root head
    h[:, r] = j[:, PELVIS] + G[:, r] @ (H[r] - rest.joints17[PELVIS])
    done[r] = True
    g_chest = _chest_frame(j) @ _chest_frame(rest.joints17).T  # (T, 3, 3)

    # Spine: blend of pelvis and chest orientation, Anny's lengths, gap to the chest spread along it.
    for name, weight in zip(SPINE_BONES, SPINE_BLEND):
        b = idx[name]
        follow(b)
        G[:, b] = slerp_rotations(G[:, r], g_chest, weight)
    top = idx[SPINE_BONES[-1]]
    rest_mid = 0.5 * (rest.joints17[L_SHOULDER] + rest.joints17[R_SHOULDER])
    target_top = 0.5 * (j[:, L_SHOULDER] + j[:, R_SHOULDER]) + g_chest @ (H[top] - rest_mid)  # (T, 3)
    gap = target_top - h[:, top]  # (T, 3)
    lengths = [np.linalg.norm(H[idx[n]] - H[parents[idx[n]]]) for n in SPINE_BONES[1:]]
    along = np.cumsum([0.0] + lengths)  # (5,) distance of each spine head from the root along the spine
    for name, frac in zip(SPINE_BONES, along / along[-1]):
        h[:, idx[name]] += frac * gap

    # Legs. The clip's floor level for the feet: its low ankle height (5th percentile over both ankles).
    floor_level = float(np.percentile(np.concatenate([j[:, L_ANKLE, 2], j[:, R_ANKLE, 2]]), 5))
    for side, hip, knee, ankle in (("L", L_HIP, L_KNEE, L_ANKLE), ("R", R_HIP, R_KNEE, R_ANKLE)):
        follow(idx[f"pelvis.{side}"])
        swing_to(idx[f"upperleg01.{side}"], idx[f"lowerleg01.{side}"], j[:, knee] - j[:, hip], j[:, hip])
        follow(idx[f"upperleg02.{side}"])
        swing_to(idx[f"lowerleg01.{side}"], idx[f"foot.{side}"], j[:, ankle] - j[:, knee], j[:, knee])
        follow(idx[f"lowerleg02.{side}"])
        foot = idx[f"foot.{side}"]
        follow(foot)
        h[:, foot] = j[:, ankle]
        if flat_feet:
            forward_rest = H[idx[f"toe3-1.{side}"]] - H[idx[f"foot.{side}"]]  # heel -> toes
            G[:, foot] = _foot_rotation(G[:, foot], G[:, r], forward_rest=forward_rest,
                                        height=j[:, ankle, 2] - floor_level)

    # Arms.
    arms = (("L", L_SHOULDER, L_ELBOW, L_WRIST), ("R", R_SHOULDER, R_ELBOW, R_WRIST))
    for side, shoulder, elbow, wrist in arms:
        clav = idx[f"clavicle.{side}"]
        upper = idx[f"upperarm01.{side}"]
        follow(clav)
        swing_to(clav, upper, j[:, shoulder] - h[:, clav], None)
        follow(idx[f"shoulder01.{side}"])
        swing_to(upper, idx[f"lowerarm01.{side}"], j[:, elbow] - j[:, shoulder], j[:, shoulder])
        follow(idx[f"upperarm02.{side}"])
        swing_to(idx[f"lowerarm01.{side}"], idx[f"wrist.{side}"], j[:, wrist] - j[:, elbow], j[:, elbow])
        follow(idx[f"lowerarm02.{side}"])
        follow(idx[f"wrist.{side}"])
        h[:, idx[f"wrist.{side}"]] = j[:, wrist]

    # Neck and head: direction only, Anny's lengths, with the clip's typical tilt kept plausible.
    follow(idx["neck01"])
    swing_to(idx["neck01"], idx["head"], _neck_direction(j, _chest_frame(j)), None)

    # Everything else (upperleg02 done above, fingers, toes, neck02/03, head, eyes) follows its parent.
    for b in range(num_bones):
        if not done[b]:
            follow(b)
    return G, h


def _neck_direction(j: np.ndarray, chest: np.ndarray) -> np.ndarray:
    """(T, 3) target neck -> head direction, its clip-median forward tilt clamped to :data:`NECK_TILT_RANGE`.

    Rigs put the canonical neck and head joints at different places (the tilt of neck -> head in the
    chest frame has a clip median from -12 to +30 degrees over the shared mocap), so the whole clip is
    turned about the chest's left-right axis by the amount its median tilt lies outside the plausible
    range; movements about the median are kept.

    Args:
        j: (T, 17, 3) joints.
        chest: (T, 3, 3) chest frames (columns: left, back, up).
    """
    d = np.einsum("tji,tj->ti", chest, j[:, HEAD] - j[:, NECK])  # (T, 3) in chest axes
    tilt = np.degrees(np.arctan2(-d[:, 1], d[:, 2]))  # forward tilt, degrees
    median = float(np.median(tilt))
    delta = np.radians(np.clip(median, *NECK_TILT_RANGE) - median)
    c, s = np.cos(delta), np.sin(delta)
    turn = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])  # about the chest's x (left) axis
    return np.einsum("tij,tj->ti", chest, d @ turn.T)


def _foot_rotation(g_shin: np.ndarray, g_root: np.ndarray, *, forward_rest: np.ndarray,
                   height: np.ndarray) -> np.ndarray:
    """Foot rotation: flat near the floor, carried by the shin when raised, blended in between.

    Args:
        g_shin: (T, 3, 3) rotation of the shin (what the foot gets when it follows rigidly).
        g_root: (T, 3, 3) rotation of the pelvis (its heading is the fallback).
        forward_rest: (3,) heel -> toes direction in the rest pose.
        height: (T,) ankle height above the clip's floor level, metres.
    Returns:
        (T, 3, 3): a pure turn about z (the heading of the shin-carried foot, or of the pelvis when the
        foot points up or down) at height 0, the shin's rotation from :data:`FLAT_FOOT_RANGE` up.
    """
    flat_axis = np.array([1.0, 1.0, 0.0])
    forward_rest = forward_rest * flat_axis  # (3,) horizontal
    heading = (g_shin @ forward_rest) * flat_axis  # (T, 3)
    pelvis_forward = (g_root @ np.array([0.0, -1.0, 0.0])) * flat_axis  # (T, 3)
    weak = np.linalg.norm(heading, axis=-1) < 0.3 * np.linalg.norm(forward_rest)
    heading = np.where(weak[:, None], pelvis_forward, heading)
    flat = swing_rotation(np.broadcast_to(forward_rest, heading.shape), heading)  # both horizontal: a yaw
    weight = np.clip(1.0 - height / FLAT_FOOT_RANGE, 0.0, 1.0)  # (T,) 1 = flat
    return slerp_rotations(g_shin, flat, weight)


# --- rendering ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BodyStyle:
    """How a body is drawn.

    Attributes:
        size: (width, height) in pixels.
        phenotype: Anny phenotype values (gender, age, muscle, weight, height, proportions in [0, 1]).
        skin, top, trousers, shoes, hair, eyes, iris, lips, mouth: sRGB colours (0-255) per body region.
        background: an RGB colour (0-255) or an (H, W, 3) uint8 image.
        fit_scale: scale the mesh to the clip's size (see :func:`pose_anny_from_joints`).
        flat_feet: keep feet flat near the floor.
        azimuth_deg, elevation_deg, yfov_deg, margin: the default camera (:func:`fit_camera`).
        batch: frames per Anny forward call.
        platform: GL backend, ``"osmesa"`` or ``"egl"``.
        vertex_colors: optional (V, 3) float sRGB colours in [0, 1] per Anny vertex, replacing the region
            colours (e.g. patterned clothing).
    """

    size: tuple[int, int] = (256, 256)
    phenotype: Mapping[str, float] = field(default_factory=dict)
    skin: tuple[int, int, int] = (222, 171, 138)
    top: tuple[int, int, int] = (52, 101, 190)
    trousers: tuple[int, int, int] = (48, 48, 64)
    shoes: tuple[int, int, int] = (28, 28, 28)
    hair: tuple[int, int, int] = (72, 48, 32)
    eyes: tuple[int, int, int] = (240, 240, 236)
    iris: tuple[int, int, int] = (60, 45, 35)
    lips: tuple[int, int, int] = (190, 110, 100)
    mouth: tuple[int, int, int] = (110, 40, 45)
    background: tuple[int, int, int] | np.ndarray = (255, 255, 255)
    fit_scale: bool = True
    flat_feet: bool = True
    azimuth_deg: float = 0.0
    elevation_deg: float = 8.0
    yfov_deg: float = 35.0
    margin: float = 0.08
    batch: int = 16
    platform: str = "osmesa"
    vertex_colors: np.ndarray | None = None

    def region_colors(self) -> np.ndarray:
        """(len(REGION_NAMES), 3) uint8 colour per region code."""
        return np.array([getattr(self, name) for name in anny_model.REGION_NAMES], dtype=np.uint8)


@dataclass(frozen=True)
class BodyFrames:
    """Rendered body frames.

    Attributes:
        frames: (T, H, W, 3) uint8 RGB.
        masks: (T, H, W) bool silhouettes.
        camera: the camera used.
        pose: the fitted Anny pose.
        head_masks: (T, H, W) bool pixels where the visible surface is the head
            (:func:`renderers.anny_model.head_vertices`), or None when not asked for.
        vertex_uv: (T, V, 2) float32 every mesh vertex's pixel position, or None when not asked for.
        vertex_visible: (T, V) bool, the vertex is the front surface at its pixel (the mesh generator's
            correspondence, :mod:`motion2video.generator.mesh_flow`), or None.
    """

    frames: np.ndarray
    masks: np.ndarray
    camera: PinholeCamera
    pose: AnnyPose
    head_masks: np.ndarray | None = None
    vertex_uv: np.ndarray | None = None
    vertex_visible: np.ndarray | None = None


def skin_vertices(rest: AnnyRest, bone_poses: np.ndarray) -> np.ndarray:
    """Anny's linear blend skinning of the rest mesh by world bone poses, without facial actions.

    Equal to Anny's forward with ``pose_parameterization="world"`` for this phenotype, but it reuses the
    cached rest model instead of rebuilding it (bone orientations by Procrustes) on every call, which
    costs more than the skinning itself.

    Args:
        rest: the rest model of the phenotype.
        bone_poses: (B, 104, 4, 4) world transforms.
    Returns:
        (B, V, 3) float64 posed vertices in Anny's size.
    """
    import torch

    model = anny_model.get_anny()
    poses = torch.as_tensor(np.asarray(bone_poses), dtype=model.dtype)  # (B, 104, 4, 4)
    rest_poses = torch.tensor(rest.bone_poses, dtype=model.dtype)[None]  # (1, 104, 4, 4)
    rest_vertices = torch.tensor(rest.vertices, dtype=model.dtype)[None]  # (1, V, 3)
    with torch.no_grad():
        transforms, _ = model.get_bone_transforms(poses, rest_poses, pose_parameterization="world")
        verts = model.get_skinned_vertices(rest_vertices.expand(len(poses), -1, -1), transforms)
    return verts.double().cpu().numpy()


def posed_vertices(pose: AnnyPose, *, batch: int = 16, offsets: np.ndarray | None = None):
    """Yield Anny's posed vertices for a fitted pose, chunk by chunk.

    Args:
        pose: a fitted pose (T frames).
        batch: frames per skinning call.
        offsets: (V, 3) metres added to the rest vertices before skinning (a surface fitted to a pictured person's
            outline), or None.
    Yields:
        (start, vertices) with vertices (b, V, 3) float32 world metres for frames start..start+b-1.
    """
    rest = anny_model.anny_rest(dict(zip(anny_model.PHENOTYPE_NAMES, pose.phenotype)))
    if offsets is not None:
        rest = replace(rest, vertices=rest.vertices + np.asarray(offsets, np.float64))
    num_frames = len(pose.bone_poses)
    for start in range(0, num_frames, batch):
        stop = min(start + batch, num_frames)
        verts = skin_vertices(rest, pose.bone_poses[start:stop]) * pose.scale  # (b, V, 3)
        yield start, verts.astype(np.float32)


class BodyRenderer(RendererBase):
    """Renders canonical H36M-17 motions as a posed, lit Anny body.

    Args:
        style: the :class:`BodyStyle`.
    """

    def __init__(self, style: BodyStyle = BodyStyle()):
        width, height = (int(v) for v in style.size)
        if width <= 0 or height <= 0:
            raise InputError(f"image size must be positive, got {width}x{height}")
        try:
            anny_model.phenotype_vector(style.phenotype)
        except ValueError as err:
            raise InputError(str(err)) from None
        self.style = style
        self.width, self.height = width, height
        self._mesh = MeshRenderer(width, height, platform=style.platform)
        self._colors: np.ndarray | None = None

    @property
    def offscreen(self):
        """The shared ``pyrender.OffscreenRenderer``."""
        return self._mesh.offscreen

    def _vertex_colors(self) -> np.ndarray:
        if self._colors is None and self.style.vertex_colors is not None:
            self._colors = np.asarray(self.style.vertex_colors, np.float64)
        if self._colors is None:
            rest = anny_model.anny_rest(self.style.phenotype)
            self._colors = anny_model.vertex_colors(self.style.region_colors(), rest)  # (V, 3) float
        return self._colors

    def fit_pose(self, motion: Motion) -> AnnyPose:
        """Inverse kinematics for a canonical 3D motion (raises InputError for other motions)."""
        if motion.skeleton != "h36m-17" or motion.dim != 3:
            raise InputError(f"the body renderer needs 3D h36m-17 joints, got {motion.skeleton} with "
                             f"D={motion.dim}", motion.source)
        return pose_anny_from_joints(motion.joints, phenotype=self.style.phenotype,
                                     fit_scale=self.style.fit_scale, flat_feet=self.style.flat_feet)

    def camera_for(self, pose: AnnyPose, joints: np.ndarray, *, chunks=None) -> PinholeCamera:
        """A fixed camera keeping the whole posed mesh (and the joints) in view over the sequence.

        ``chunks`` may pass already computed :func:`posed_vertices` output for ``pose``.
        """
        points = [np.asarray(joints, np.float64).reshape(-1, 3)]
        for _, verts in (chunks if chunks is not None else posed_vertices(pose, batch=self.style.batch)):
            points.append(verts[:, ::7].reshape(-1, 3))  # a subsample is enough for the extent
        s = self.style
        return fit_camera(np.concatenate(points), self.width, self.height, azimuth_deg=s.azimuth_deg,
                          elevation_deg=s.elevation_deg, yfov_deg=s.yfov_deg, margin=s.margin)

    def render_with_masks(self, motion: Motion, *, camera: PinholeCamera | None = None,
                          progress: Callable[[int], object] | None = None, head: bool = False,
                          vertices: bool = False) -> BodyFrames:
        """Render every frame of ``motion``; see :class:`BodyFrames`.

        Args:
            motion: a 3D canonical (h36m-17) motion.
            camera: the camera; None fits one over the whole sequence (mesh included).
            progress: called with the number of frames rendered after each batch.
            head: also render the head masks (a second, depth-only pass of the head's triangles; a pixel is
                head where that depth equals the whole body's, so a hand in front of the face is not head).
        """
        pose = self.fit_pose(motion)
        chunks = None
        if camera is None:
            if motion.num_frames <= KEEP_VERTICES_FRAMES:  # keep them for the render: one forward pass
                chunks = list(posed_vertices(pose, batch=self.style.batch))
            camera = self.camera_for(pose, motion.joints, chunks=chunks)
        elif (camera.width, camera.height) != (self.width, self.height):
            camera = camera.with_size(self.width, self.height)
        faces = anny_model.triangles()
        colors = self._vertex_colors()
        frames = np.zeros((motion.num_frames, self.height, self.width, 3), dtype=np.uint8)
        masks = np.zeros((motion.num_frames, self.height, self.width), dtype=bool)
        head_masks = np.zeros_like(masks) if head else None
        head_ids, head_faces = anny_model.head_submesh() if head else (None, None)
        vertex_uv = vertex_visible = None
        if vertices:
            count = len(anny_model.anny_rest(self.style.phenotype).vertices)
            vertex_uv = np.zeros((motion.num_frames, count, 2), np.float32)
            vertex_visible = np.zeros((motion.num_frames, count), bool)
        for start, verts in (chunks if chunks is not None else posed_vertices(pose, batch=self.style.batch)):
            for k, v in enumerate(verts):
                out = self._mesh.render_mesh(v, faces, vertex_colors=colors, camera=camera,
                                             background=self.style.background)
                frames[start + k], masks[start + k] = out.color, out.mask
                if head_masks is not None:
                    head_masks[start + k] = self._head_mask(v[head_ids], head_faces, out.depth, camera)
                if vertex_uv is not None:
                    uvz = project(v, camera)  # (V, 3)
                    vertex_uv[start + k] = uvz[:, :2]
                    vertex_visible[start + k] = vertex_visibility(uvz, out.depth)
            if progress is not None:
                progress(len(verts))
        return BodyFrames(frames=frames, masks=masks, camera=camera, pose=pose, head_masks=head_masks,
                          vertex_uv=vertex_uv, vertex_visible=vertex_visible)

    def _head_mask(self, head_vertices: np.ndarray, head_faces: np.ndarray, depth: np.ndarray,
                   camera: PinholeCamera) -> np.ndarray:
        """(H, W) bool: pixels where the head sub-mesh ((K, 3) vertices, (F, 3) triangles) is the front surface
        of the body whose depth map is ``depth`` (H, W)."""
        alone = self._mesh.render_mesh(head_vertices, head_faces, vertex_colors=(255, 255, 255), camera=camera).depth
        return (alone > 0) & (depth > 0) & (np.abs(alone - depth) <= HEAD_DEPTH_TOLERANCE * np.maximum(depth, 1e-6))

    def iter_frames(self, motion: Motion, *, camera: PinholeCamera | None = None) -> Iterator[np.ndarray]:
        """Yield ``motion``'s frames as (b, H, W, 3) uint8 chunks of ``style.batch`` frames.

        The camera is fitted over the whole sequence first (one extra skinning pass for clips longer than
        KEEP_VERTICES_FRAMES), so the frames equal :meth:`render`'s while only one chunk is in memory.
        """
        pose = self.fit_pose(motion)
        chunks = None
        if camera is None:
            if motion.num_frames <= KEEP_VERTICES_FRAMES:
                chunks = list(posed_vertices(pose, batch=self.style.batch))
            camera = self.camera_for(pose, motion.joints, chunks=chunks)
        elif (camera.width, camera.height) != (self.width, self.height):
            camera = camera.with_size(self.width, self.height)
        faces = anny_model.triangles()
        colors = self._vertex_colors()
        for _, verts in (chunks if chunks is not None else posed_vertices(pose, batch=self.style.batch)):
            yield np.stack([self._mesh.render_mesh(v, faces, vertex_colors=colors, camera=camera,
                                                   background=self.style.background).color for v in verts])

    def render(self, motion: Motion, *, camera: PinholeCamera | None = None,
               progress: Callable[[int], object] | None = None) -> np.ndarray:
        """(T, H, W, 3) uint8 frames of ``motion`` (camera fitted over the whole sequence by default)."""
        return self.render_with_masks(motion, camera=camera, progress=progress).frames

    def close(self) -> None:
        self._mesh.close()
