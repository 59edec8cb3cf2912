"""The Anny head and face driven by a :class:`~motion2video.core.motion.FaceMotion`, rendered close up.

- Expressions: the 52 ARKit coefficients are Anny's facial actions (same names, same order), so they go
  straight into Anny's forward.
- Head pose: the axis-angle rotation is in world axes (z up, the face looks along -y; +z turns the face
  to its left, +x nods it down, +y tilts it towards its left shoulder). It is spread over the neck: the
  bones ``neck02``, ``neck03`` and ``head`` each turn by a third of it, about their own heads, so the
  skull turns about the upper neck and the neck bends smoothly. The translation moves the whole mesh
  (the camera stays put, so the head moves in the picture).
- Identity: :attr:`FaceMotion.identity` holds Anny phenotype values (gender, age, muscle, weight,
  height, proportions).
- Camera: fixed per sequence, in front of the face, framing the head and neck at the mean translation.
- Styles: ``"appearance"`` colours skin, hair, lips, eyes, iris and the mouth by region
  (:func:`renderers.anny_model.region_weights`); ``"structure"`` is a uniform grey lit mesh, the face
  structure input of the frame generator.

Only the head, neck and upper chest are drawn (a sub-mesh chosen once on the rest pose), which keeps
the render cheap.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterator

import numpy as np

from motion2video.core.camera import PinholeCamera
from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion
from motion2video.core.rotations import axis_angle_to_matrix
from renderers import anny_model
from renderers.anny_model import AnnyRest
from renderers.base import RendererBase
from renderers.mesh import MeshRenderer, vertex_visibility

STYLES = ("appearance", "structure")
# A head vertex is the front surface when its depth lies within this of the depth map's at its pixel (metres). The
# body's VISIBILITY_TOLERANCE_M (2.5 cm, for wrists and fingers) let a third of the vertices it counted as shown on a
# neutral face at 128 px lie behind the surface (1,201 of 3,542 against a render at 768 px tested to 2 mm): the
# underside of the jaw and the inner lips, which then lent the crease's dark pixel when a future opened the mouth (a
# row of specks along the jaw, a dotted mouth). At 1 cm: 550 (and 50 shown ones missed, against 26); the held-out
# face pairs' person PSNR 30.06 -> 30.12 dB (0.5 cm: 30.08, 1.5 cm: 30.08; docs/results.md).
FACE_VISIBILITY_TOLERANCE_M = 0.01
# The mouth cavity and tongue (:func:`renderers.anny_model.mouth_vertices`) are seen only through the lips' opening,
# where they are the front surface itself; behind the skin they lie within 1 cm of it under the nose and behind the
# lips. At 1 cm, 104 of the 128 cavity vertices counted as shown on a fitted portrait (portrait_pearl_earring.jpg at
# 256 px) lay 1-10 mm behind the depth map: they took the nostril's shadow as the cavity's colour, and when a future
# showed them under the nostril (within 1 cm of its thin skin) they drew it there, a dark dot under the nose. Their
# own test is 2 mm: of the cavity vertices counted as shown over that clip's 137 renders, 23% lay within 1 mm of
# the depth map and 66% 3-10 mm behind it.
MOUTH_VISIBILITY_TOLERANCE_M = 0.002
# Face landmarks (Anny vertices picked on the rest mesh by :func:`face_landmark_vertices`), in this order.
FACE_LANDMARK_NAMES: tuple[str, ...] = (
    "right_eye", "left_eye", "nose_tip", "right_mouth_corner", "left_mouth_corner", "upper_lip",
    "lower_lip", "chin",
)
HEAD_TURN_BONES = ("neck02", "neck03", "head")  # each takes 1/3 of the head rotation


def head_bone_poses(rest: AnnyRest, rotations: np.ndarray, translations: np.ndarray) -> np.ndarray:
    """Anny bone world poses for a head pose; every other bone stays at rest.

    Args:
        rest: the rest model (its bone heads and poses).
        rotations: (T, 3) head axis-angle in world axes, radians.
        translations: (T, 3) whole-mesh translation, metres.
    Returns:
        (T, 104, 4, 4) float64 bone world transforms (``pose_parameterization="world"``).
    """
    rotations = np.asarray(rotations, np.float64)
    translations = np.asarray(translations, np.float64)
    num_frames = len(rotations)
    names = anny_model.bone_names()
    parents = anny_model.bone_parents()
    H = rest.bone_heads  # (B, 3)
    step = axis_angle_to_matrix(rotations / len(HEAD_TURN_BONES))  # (T, 3, 3)
    turning = {anny_model.bone_index(n) for n in HEAD_TURN_BONES}
    G = np.zeros((num_frames, len(names), 3, 3))
    h = np.zeros((num_frames, len(names), 3))
    G[:, 0] = np.eye(3)
    h[:, 0] = H[0] + translations
    for b in range(1, len(names)):
        p = parents[b]
        h[:, b] = h[:, p] + G[:, p] @ (H[b] - H[p])
        G[:, b] = step @ G[:, p] if b in turning else G[:, p]
    poses = np.zeros((num_frames, len(names), 4, 4))
    poses[..., :3, :3] = G @ rest.bone_poses[:, :3, :3]
    poses[..., :3, 3] = h
    poses[..., 3, 3] = 1.0
    return poses


def face_landmark_vertices(rest: AnnyRest) -> np.ndarray:
    """(K,) Anny vertex indices of :data:`FACE_LANDMARK_NAMES`, picked on the rest mesh.

    Eyes: the front-most vertex of each eyeball (the pupil). Nose tip: the front-most head vertex.
    Mouth corners: the outermost vertices of the lip region; upper / lower lip: the top-most / bottom-most
    lip vertices near the middle; chin: the most forward head vertex on the midline 1.5 cm below the lips.
    """
    v = rest.vertices
    dominant = anny_model.dominant_bones()
    on_head = dominant == anny_model.bone_index("head")
    picks = []
    for side in ("R", "L"):
        eye = np.flatnonzero(dominant == anny_model.bone_index(f"eye.{side}"))
        picks.append(eye[np.argmin(v[eye, 1])])
    head_ids = np.flatnonzero(on_head)
    picks.append(head_ids[np.argmin(v[head_ids, 1])])
    lips = np.flatnonzero(anny_model.lip_weights(rest) > 0.5)
    centre_x = float(np.median(v[lips, 0]))
    picks.append(lips[np.argmin(v[lips, 0])])
    picks.append(lips[np.argmax(v[lips, 0])])
    middle = lips[np.abs(v[lips, 0] - centre_x) < 0.004]
    front = middle[v[middle, 1] < np.percentile(v[middle, 1], 50)]  # the outer lip surface, not the inside
    picks.append(front[np.argmax(v[front, 2])])
    picks.append(front[np.argmin(v[front, 2])])
    below = head_ids[(np.abs(v[head_ids, 0] - centre_x) < 0.006) & (v[head_ids, 2] < v[lips, 2].min() - 0.015)]
    picks.append(below[np.argmin(v[below, 1])])  # the most forward point under the lips
    return np.asarray(picks, dtype=np.int64)


def _eye_centre(rest: AnnyRest) -> np.ndarray:
    """(3,) midpoint of the two eyeball centres."""
    H = rest.bone_heads
    return 0.5 * (H[anny_model.bone_index("eye.L")] + H[anny_model.bone_index("eye.R")])


def _head_framing(rest: AnnyRest, head_fraction: float) -> tuple[np.ndarray, float]:
    """The close-up view: (3,) target point (the head's centre at eye height) and the view height in
    metres such that chin-to-crown takes ``head_fraction`` of it (the eyes sit half way down the head)."""
    eyes = _eye_centre(rest)
    crown = rest.vertices[:, 2].max()
    chin_to_crown = 2.0 * (crown - eyes[2])
    target = np.array([eyes[0], rest.bone_heads[anny_model.bone_index("head")][1], eyes[2]])
    return target, chin_to_crown / head_fraction


@dataclass(frozen=True)
class FaceStyle:
    """How a face is drawn.

    Attributes:
        size: (width, height) in pixels.
        style: ``"appearance"`` (coloured by region) or ``"structure"`` (uniform grey).
        skin, hair, eyes, iris, lips, mouth, top: sRGB colours (0-255) for the appearance style.
        structure_color: the uniform colour of the structure style.
        background: an RGB colour (0-255) or an (H, W, 3) uint8 image.
        yfov_deg: vertical field of view of the close-up camera.
        head_fraction: fraction of the image height taken by the head (chin to crown).
        batch: frames per Anny forward call.
        platform: GL backend, ``"osmesa"`` or ``"egl"``.
    """

    size: tuple[int, int] = (256, 256)
    style: str = "appearance"
    skin: tuple[int, int, int] = (222, 171, 138)
    hair: tuple[int, int, int] = (72, 48, 32)
    eyes: tuple[int, int, int] = (240, 240, 236)
    iris: tuple[int, int, int] = (60, 45, 35)
    lips: tuple[int, int, int] = (190, 110, 100)
    mouth: tuple[int, int, int] = (110, 40, 45)
    top: tuple[int, int, int] = (52, 101, 190)
    structure_color: tuple[int, int, int] = (200, 200, 200)
    background: tuple[int, int, int] | np.ndarray = (255, 255, 255)
    yfov_deg: float = 20.0
    head_fraction: float = 0.72
    batch: int = 16
    platform: str = "osmesa"

    def region_colors(self) -> np.ndarray:
        """(len(REGION_NAMES), 3) uint8 colour per region (trousers and shoes never show: skin)."""
        colors = {name: getattr(self, name, self.skin) for name in anny_model.REGION_NAMES}
        return np.array([colors[name] for name in anny_model.REGION_NAMES], dtype=np.uint8)


def close_up_camera(rest: AnnyRest, style: FaceStyle, translation=(0.0, 0.0, 0.0)) -> PinholeCamera:
    """The close-up camera of ``style`` (its size, field of view and head fraction) in front of a head of rest
    model ``rest`` moved by ``translation`` (3,) metres: it looks along +y at the head's centre at eye height."""
    target, view_height = _head_framing(rest, style.head_fraction)
    target = target + np.asarray(translation, np.float64)
    distance = 0.5 * view_height / np.tan(0.5 * np.radians(style.yfov_deg))
    position = target + np.array([0.0, -distance, 0.0])
    width, height = (int(v) for v in style.size)
    return PinholeCamera(tuple(float(v) for v in position), tuple(float(v) for v in target),
                         float(np.radians(style.yfov_deg)), width, height)


@dataclass(frozen=True)
class FaceFrames:
    """Rendered face frames.

    Attributes:
        frames: (T, H, W, 3) uint8 RGB.
        masks: (T, H, W) bool silhouettes.
        camera: the camera used.
        landmarks: (T, K, 2) float32 pixel positions (x, y) of :data:`FACE_LANDMARK_NAMES` on the posed
            mesh (whether or not they are occluded).
        vertex_uv: (T, V, 2) float32 pixel positions of all Anny's V vertices (so that identities whose drawn
            sub-meshes differ share one index), or None (asked for with ``vertices=True``: the mesh generator's
            correspondence).
        vertex_visible: (T, V) bool, the vertex is drawn and the front surface (depth test), or None.
    """

    frames: np.ndarray
    masks: np.ndarray
    camera: PinholeCamera
    landmarks: np.ndarray
    vertex_uv: np.ndarray | None = None
    vertex_visible: np.ndarray | None = None


@dataclass
class _HeadMesh:
    """The drawn sub-mesh for one phenotype: vertex subset, remapped faces, colours."""

    vertex_ids: np.ndarray  # (K,) indices into Anny's vertices
    faces: np.ndarray  # (F', 3) indices into the subset
    colors: np.ndarray  # (K, 3) float sRGB
    landmarks: np.ndarray  # (L,) indices into the subset, FACE_LANDMARK_NAMES order
    rest: AnnyRest = field(repr=False)
    tolerance: np.ndarray = field(repr=False)  # (K,) metres a vertex may lie behind the depth map (front-surface test)


class FaceRenderer(RendererBase):
    """Renders :class:`FaceMotion` clips as a close-up of Anny's head.

    Args:
        style: the :class:`FaceStyle`.
    """

    def __init__(self, style: FaceStyle = FaceStyle()):
        width, height = (int(v) for v in style.size)
        if width <= 0 or height <= 0:
            raise InputError(f"image size must be positive, got {width}x{height}")
        if style.style not in STYLES:
            raise InputError(f"face style must be one of {', '.join(STYLES)}, got {style.style!r}")
        self.style = style
        self.width, self.height = width, height
        self._mesh = MeshRenderer(width, height, platform=style.platform)
        self._heads: dict[tuple[float, ...], _HeadMesh] = {}

    @property
    def offscreen(self):
        """The shared ``pyrender.OffscreenRenderer``."""
        return self._mesh.offscreen

    def _head_mesh(self, face: FaceMotion) -> _HeadMesh:
        try:
            phenotype = anny_model.phenotype_vector(face.identity)
        except ValueError as err:
            raise InputError(f"face identity: {err}", face.source) from None
        cached = self._heads.get(phenotype)
        if cached is not None:
            return cached
        rest = anny_model.anny_rest(dict(zip(anny_model.PHENOTYPE_NAMES, phenotype)))
        names = anny_model.bone_names()
        dominant = anny_model.dominant_bones()
        limb = np.array([n.startswith(("upperarm", "lowerarm", "wrist", "finger", "metacarpal"))
                         for n in names])[dominant]  # (V,)
        # Everything from a little below the bottom edge of the close-up view upwards, arms excluded.
        _, view_height = _head_framing(rest, self.style.head_fraction)
        eyes_z = _eye_centre(rest)[2]
        keep = (rest.vertices[:, 2] > eyes_z - 0.5 * view_height - 0.08) & ~limb  # (V,)
        all_faces = anny_model.triangles()
        face_keep = keep[all_faces].all(axis=1)
        vertex_ids = np.unique(all_faces[face_keep].ravel())
        remap = np.full(len(keep), -1, dtype=np.int64)
        remap[vertex_ids] = np.arange(len(vertex_ids))
        faces = remap[all_faces[face_keep]]
        if self.style.style == "structure":
            colors = np.broadcast_to(np.asarray(self.style.structure_color, np.float64) / 255.0,
                                     (len(vertex_ids), 3))
        else:
            colors = anny_model.vertex_colors(self.style.region_colors(), rest)[vertex_ids]
        tolerance = np.where(np.isin(vertex_ids, anny_model.mouth_vertices()), MOUTH_VISIBILITY_TOLERANCE_M,
                             FACE_VISIBILITY_TOLERANCE_M)
        head = _HeadMesh(vertex_ids=vertex_ids, faces=faces, colors=np.ascontiguousarray(colors),
                         landmarks=remap[face_landmark_vertices(rest)], rest=rest, tolerance=tolerance)
        if np.any(head.landmarks < 0):
            raise RuntimeError("a face landmark lies outside the drawn head mesh")
        self._heads[phenotype] = head
        return head

    def camera_for(self, face: FaceMotion) -> PinholeCamera:
        """A fixed close-up camera in front of the face at the clip's mean head translation."""
        return close_up_camera(self._head_mesh(face).rest, self.style, face.head_translation.mean(axis=0))

    def vertices(self, face: FaceMotion, shape: np.ndarray | None = None):
        """Yield ``(start, vertices)`` chunks: (b, K, 3) float32 world positions of the drawn sub-mesh.

        Args:
            shape: (V, 3) a person's face as offsets of Anny's vertices, metres in the head's rest frame
                (:func:`motion2video.pose.face_shape.head_shape`), turned with the head in every frame; None: Anny's.
        """
        import torch

        head = self._head_mesh(face)
        model = anny_model.get_anny()
        poses = head_bone_poses(head.rest, face.head_rotation, face.head_translation)  # (T, 104, 4, 4)
        pheno = dict(zip(anny_model.PHENOTYPE_NAMES, head.rest.phenotype))
        ids = torch.as_tensor(head.vertex_ids)
        for start in range(0, face.num_frames, self.style.batch):
            stop = min(start + self.style.batch, face.num_frames)
            with torch.no_grad():
                out = model(torch.as_tensor(poses[start:stop], dtype=model.dtype), phenotype_kwargs=pheno,
                            facial_actions=torch.as_tensor(face.expressions[start:stop], dtype=model.dtype),
                            pose_parameterization="world")
            verts = out["vertices"][:, ids].cpu().numpy().astype(np.float32)
            if shape is not None:  # the face's vertices follow the head bone: R v + c(R) + T, so R offset
                turn = axis_angle_to_matrix(np.asarray(face.head_rotation[start:stop], np.float64))  # (b, 3, 3)
                verts += np.einsum("bij,kj->bki", turn, np.asarray(shape, np.float64)[head.vertex_ids])
            yield start, verts

    def render_with_masks(self, face: FaceMotion, *, camera: PinholeCamera | None = None,
                          progress: Callable[[int], object] | None = None, vertices: bool = False,
                          shape: np.ndarray | None = None) -> FaceFrames:
        """Render every frame of ``face``; see :class:`FaceFrames`.

        Args:
            face: the face motion.
            camera: the camera; None places the close-up camera of :meth:`camera_for`.
            progress: called with the number of frames rendered after each batch.
            vertices: also keep every vertex's pixel and front-surface flag (``vertex_uv``, ``vertex_visible``).
            shape: (V, 3) the person's face on Anny's head (:meth:`vertices`), or None.
        """
        if not isinstance(face, FaceMotion):
            raise InputError(f"the face renderer needs a FaceMotion, got {type(face).__name__}")
        head = self._head_mesh(face)
        if camera is None:
            camera = self.camera_for(face)
        elif (camera.width, camera.height) != (self.width, self.height):
            camera = camera.with_size(self.width, self.height)
        frames = np.zeros((face.num_frames, self.height, self.width, 3), dtype=np.uint8)
        masks = np.zeros((face.num_frames, self.height, self.width), dtype=bool)
        landmarks = np.zeros((face.num_frames, len(FACE_LANDMARK_NAMES), 2), dtype=np.float32)
        vertex_uv = vertex_visible = None
        if vertices:
            count = len(head.rest.vertices)
            vertex_uv = np.zeros((face.num_frames, count, 2), np.float32)
            vertex_visible = np.zeros((face.num_frames, count), bool)
        for start, verts in self.vertices(face, shape):
            landmarks[start:start + len(verts)] = camera.project(verts[:, head.landmarks])[..., :2]
            for k, v in enumerate(verts):
                out = self._mesh.render_mesh(v, head.faces, vertex_colors=head.colors, camera=camera,
                                             background=self.style.background)
                frames[start + k], masks[start + k] = out.color, out.mask
                if vertex_uv is not None:
                    uvz = camera.project(v)  # (K, 3) the drawn vertices
                    vertex_uv[start + k, head.vertex_ids] = uvz[:, :2]
                    vertex_visible[start + k, head.vertex_ids] = vertex_visibility(
                        uvz, out.depth, tolerance=head.tolerance)
            if progress is not None:
                progress(len(verts))
        return FaceFrames(frames=frames, masks=masks, camera=camera, landmarks=landmarks, vertex_uv=vertex_uv,
                          vertex_visible=vertex_visible)

    def iter_frames(self, face: FaceMotion, *, camera: PinholeCamera | None = None) -> Iterator[np.ndarray]:
        """Yield ``face``'s close-up frames as (b, H, W, 3) uint8 chunks (equal to :meth:`render`'s)."""
        if not isinstance(face, FaceMotion):
            raise InputError(f"the face renderer needs a FaceMotion, got {type(face).__name__}")
        head = self._head_mesh(face)
        if camera is None:
            camera = self.camera_for(face)
        elif (camera.width, camera.height) != (self.width, self.height):
            camera = camera.with_size(self.width, self.height)
        for _, verts in self.vertices(face):
            yield np.stack([self._mesh.render_mesh(v, head.faces, vertex_colors=head.colors, camera=camera,
                                                   background=self.style.background).color for v in verts])

    def render(self, face: FaceMotion, *, camera: PinholeCamera | None = None,
               progress: Callable[[int], object] | None = None) -> np.ndarray:
        """(T, H, W, 3) uint8 close-up frames of ``face``."""
        return self.render_with_masks(face, camera=camera, progress=progress).frames

    def close(self) -> None:
        self._mesh.close()
