"""Draw structure: the stage that turns motion into pictures of where the person is.

The renderer dispatch is one table, :data:`renderers.registry.RENDERERS`: :func:`renderer_for` (layout, style)
gives the renderer, :meth:`~renderers.registry.StructureRenderer.draw` draws a sequence with it. The table lives
with the renderers so the frame generator's training data (:mod:`motion2video.generator.render_data`, below the
stages) draws through the same table; every application draws through this module.

The frame generator's structures (:func:`render_structures`) follow its training data's conventions
(:mod:`motion2video.generator.data`):

- body: 2D joints in generator pixels (:func:`place_body`: the clip turned to face the camera at its first
  frame, followed on the ground, one camera fitted to the observed frames, then a 2D similarity onto the
  reference picture's pose); :func:`structure_maps` turns them into 17 Gaussian heatmaps + 16 limb maps.
- face: the Anny face rendered in the shaded grey ``"structure"`` style on black, in each frame's head pose,
  through the reference's camera.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Iterator

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.rotations import heading_of
from motion2video.stages.reference import Reference
from renderers.registry import PIXELS, renderer_for

if TYPE_CHECKING:  # annotations only: the mesh code is imported where it is used
    from motion2video.generator.mesh_flow import MeshTrack

# Two clearly different Anny identities: the source keeps the renderer's default look, the target gets
# another phenotype and other clothes, so the video shows the behaviour moving to another person.
SOURCE_LOOK: dict = {}
TARGET_LOOK: dict = {
    "phenotype": {"gender": 0.1, "age": 0.35, "muscle": 0.65, "weight": 0.35, "height": 0.6},
    "skin": (150, 104, 78), "top": (196, 62, 50), "trousers": (86, 104, 58), "shoes": (90, 60, 40),
    "hair": (24, 20, 18),
}
# Face identity and colours used for the second face when its file names no identity of its own.
ALT_FACE_IDENTITY: dict = {"gender": 0.1, "age": 0.3, "muscle": 0.5, "weight": 0.35, "height": 0.5,
                           "proportions": 0.5}
ALT_FACE_COLOURS: dict = {"skin": (150, 104, 78), "hair": (24, 20, 18), "top": (196, 62, 50)}

SEQUENCE_STYLES = ("mesh", "frames", "skeleton")  # the styles transfer and analogy offer

DOMAIN_OF_LAYOUT = {"body3d": "body", "body2d": "body", "face": "face"}
# Joints whose 2D positions align a placed body with the reference pose: pelvis, legs, spine, neck, head
# (not the arms, whose pose varies the most between a reference picture and a clip).
ALIGN_JOINTS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10)
BODY_ELEVATION_DEG = 8.0  # the body renderer's default camera
BODY_YFOV_DEG = 35.0
BODY_MARGIN = 0.12  # joints-only fits leave room for the mesh around the joints (head top, feet, hands)


def similarity_fit(source: np.ndarray, target: np.ndarray) -> tuple[float, np.ndarray]:
    """Scale and shift (no rotation) taking one 2D point set onto another: ``target ~ source * s + t``.

    The scale is the ratio of the sets' RMS spreads about their centroids and the shift matches the
    centroids (robust to a different pose, unlike a least-squares fit).

    Args:
        source, target: (N, 2) points.
    Returns:
        (s, t) with t of shape (2,).
    """
    src, dst = np.asarray(source, np.float64), np.asarray(target, np.float64)
    cs, ct = src.mean(axis=0), dst.mean(axis=0)
    spread_s = np.sqrt(((src - cs) ** 2).sum(axis=1).mean())
    spread_t = np.sqrt(((dst - ct) ** 2).sum(axis=1).mean())
    scale = float(spread_t / max(spread_s, 1e-9))
    return scale, ct - scale * cs


def follow_on_ground(joints: np.ndarray) -> np.ndarray:
    """Move every frame so its pelvis (joint 0) sits at the first frame's ground position.

    Args:
        joints: (N, 17, 3) world joints (z up).
    Returns:
        (N, 17, 3) float64; heights, turning and limbs unchanged.
    """
    j = np.asarray(joints, np.float64).copy()
    shift = j[:, 0, :2] - j[0, 0, :2]  # (N, 2)
    j[..., :2] -= shift[:, None, :]
    return j


def face_camera_front(joints: np.ndarray, first: int = 0) -> np.ndarray:
    """Turn (N, 17, 3) world joints about z (through frame ``first``'s pelvis) so the person faces -y at
    frame ``first`` (hip vector right -> left along +x, as Anny and the default camera expect)."""
    from motion2video.data.windows import canonical_frame, to_canonical

    j = np.asarray(joints, np.float64)
    frame = canonical_frame(j[None], anchor=first)
    out = to_canonical(j[None], frame)[0]
    out[..., :2] += j[first, 0, :2]  # keep the ground position (only the heading changes)
    return out


@dataclass(frozen=True)
class BodyPlacement:
    """Body joints in generator pixels.

    Attributes:
        observed: (To, 17, 2) pixels. futures: (K, Tf, 17, 2) pixels. reference: (17, 2) pixels.
        world_observed, world_futures: (To, 17, 3) / (K, Tf, 17, 3) the followed, front-facing world joints
            the camera looked at (None for 2D models), for the mesh video.
        camera: that camera (None for 2D models), before the 2D similarity.
        scale, shift: the 2D similarity from the camera's (or the 2D framing's) pixels to the generator's:
            ``pixel * scale + shift``.
    """

    observed: np.ndarray
    futures: np.ndarray
    reference: np.ndarray
    world_observed: np.ndarray | None = None
    world_futures: np.ndarray | None = None
    camera: object | None = None
    scale: float = 1.0
    shift: np.ndarray = field(default_factory=lambda: np.zeros(2))


def place_body(observed: np.ndarray, futures: np.ndarray, *, size: int,
               reference_points: np.ndarray | None = None) -> BodyPlacement:
    """Place a body forecast in the generator's square image (see "Placement" in the module docstring).

    Args:
        observed: (To, 17, 3) world joints or (To, 17, 2) pixels.
        futures: (K, Tf, 17, D) the same.
        size: image size in pixels.
        reference_points: (17, 2) the reference pose in these pixels, or None to place the first observed
            frame as a single-frame render would.
    Returns:
        A :class:`BodyPlacement`.
    """
    from motion2video.core.camera import fit_camera, fit_image_framing, project

    obs = np.asarray(observed, np.float64)
    fut = np.asarray(futures, np.float64)
    k, tf = fut.shape[:2]
    dim = obs.shape[-1]
    every = np.concatenate([obs, fut.reshape(k * tf, 17, dim)])  # (To + K*Tf, 17, D)
    to = obs.shape[0]
    world = None
    camera = None
    if dim == 3:
        world = follow_on_ground(face_camera_front(every))
        # Fitted to the observed frames only, so the observed part does not depend on the sampled futures.
        camera = fit_camera(world[:to], size, size, elevation_deg=BODY_ELEVATION_DEG, yfov_deg=BODY_YFOV_DEG,
                            margin=BODY_MARGIN)
        pts = project(world, camera)[..., :2]  # (N, 17, 2)
        if reference_points is None:
            single = fit_camera(world[0], size, size, elevation_deg=BODY_ELEVATION_DEG, yfov_deg=BODY_YFOV_DEG,
                                margin=BODY_MARGIN)
            reference_points = project(world[0], single)[..., :2]
    else:
        pts = every.copy()
        pts[..., 0] -= (pts[:, 0, 0] - pts[0, 0, 0])[:, None]  # follow the pelvis horizontally
        framing = fit_image_framing(pts[:to], size, size, margin=BODY_MARGIN)
        pts = framing.apply(pts)
        if reference_points is None:
            reference_points = fit_image_framing(pts[0], size, size, margin=BODY_MARGIN).apply(pts[0])
    reference_points = np.asarray(reference_points, np.float64)
    scale, shift = similarity_fit(pts[0, list(ALIGN_JOINTS)], reference_points[list(ALIGN_JOINTS)])
    pts = pts * scale + shift
    return BodyPlacement(
        observed=pts[:to], futures=pts[to:].reshape(k, tf, 17, 2), reference=reference_points,
        world_observed=None if world is None else world[:to],
        world_futures=None if world is None else world[to:].reshape(k, tf, 17, 3), camera=camera,
        scale=float(scale), shift=np.asarray(shift, np.float64).reshape(2))


# view_to_fit: room around the joints for what is not a joint, as fractions of the reference body's height
VIEW_HEAD_ROOM = 0.18  # above the head joint: the top of the head (about 0.1) and room for a video cell's border
VIEW_FOOT_ROOM = 0.06  # below the lowest ankle (the feet) and beside the outermost joint (hands, shoulders)


def view_to_fit(points: np.ndarray, size: int) -> tuple[float, float, float] | None:
    """The square of the generator's pixels (x0, y0, side) that keeps every placed body in view, or None when the
    picture already does.

    Args:
        points: (N, 17, 2) joints in the square picture's pixels, row 0 the reference pose
            (:attr:`Structures.points`).
        size: the picture's side.
    Returns:
        The smallest square (at least the picture) holding every joint with room for the head, feet and hands,
        nearest the picture; None when nothing leaves the picture.
    """
    pts = np.asarray(points, np.float64)
    ref = pts[0]
    tall = max(float(ref[:, 1].max() - ref[:, 1].min()), 1.0)
    lo = pts.reshape(-1, 2).min(axis=0) - (VIEW_FOOT_ROOM * tall, VIEW_HEAD_ROOM * tall)
    hi = pts.reshape(-1, 2).max(axis=0) + VIEW_FOOT_ROOM * tall
    if lo.min() >= -0.5 and hi.max() <= size + 0.5:  # within half a pixel
        return None
    side = max(float(size), float((hi - lo).max()))
    corner = np.minimum(np.maximum(0.0, hi - side), lo)  # holds [lo, hi], as near (0, 0) as it can
    return float(corner[0]), float(corner[1]), side


def reference_in_view(forecast, reference: Reference, *, size: int, fit_view: bool) -> Reference:
    """The reference, re-framed so that every observed and future body of ``forecast`` stays in the picture when
    ``fit_view`` (:func:`view_to_fit`, :func:`motion2video.stages.reference.zoom_to_view`, whose note says by how
    much); without ``fit_view``, the same reference, nothing added (the option's help says when to ask for it).
    Face references are returned as they are.

    Args:
        forecast: a :class:`motion2video.stages.sampling.Forecast` (observed (To, 17, D), futures (K, Tf, 17, D)).
        reference: from :func:`motion2video.stages.reference.load_reference`, at ``size``.
        size: the generator's image size.
    """
    from dataclasses import replace

    from motion2video.stages.reference import ReferencePose, zoom_to_view

    if not fit_view or DOMAIN_OF_LAYOUT[forecast.layout] != "body":
        return reference
    ref_points = None if reference.pose is None else reference.pose.points
    placement = place_body(forecast.observed, forecast.futures, size=size, reference_points=ref_points)
    rows = np.concatenate([placement.reference[None], placement.observed, placement.futures.reshape(-1, 17, 2)])
    view = view_to_fit(rows, size)
    if view is None:
        return reference
    if reference.pose is None:  # the placement's own framing becomes the pose that is zoomed
        reference = replace(reference, pose=ReferencePose("body", size, size, points=placement.reference))
    return zoom_to_view(reference, view)


@dataclass(frozen=True)
class Structures:
    """What the generator is conditioned on, for the reference, the observed frames and every future.

    Body structures are kept as 2D joints (``points``) and turned into maps batch by batch
    (:func:`structure_maps`); face structures are the grey renders (``images``).

    Attributes:
        domain: ``"body"`` or ``"face"``.
        size: image size S.
        points: body: (1 + To + K*Tf, 17, 2) pixels, rows = reference, observed, future 1, ..., future K.
        images: face: (1 + To + K*Tf, S, S) uint8 grey renders in the same row order.
        observed: To. samples: K. horizon: Tf.
        placement: the body placement (body only), for the mesh video.
        face_mesh: face: the head mesh's correspondence in the same rows
            (:class:`motion2video.generator.mesh_flow.MeshTrack`: vertex pixels, front-surface flags, silhouettes),
            for the mesh generator.
    """

    domain: str
    size: int
    observed: int
    samples: int
    horizon: int
    points: np.ndarray | None = None
    images: np.ndarray | None = None
    placement: BodyPlacement | None = None
    face_mesh: "MeshTrack | None" = None

    @property
    def num_targets(self) -> int:
        """Frames to generate: To + K * Tf."""
        return self.observed + self.samples * self.horizon


def structure_maps(structures: Structures, rows: slice | np.ndarray) -> np.ndarray:
    """Generator input maps for some rows of :class:`Structures` (0 = reference, then the targets).

    Returns:
        (R, C, S, S) float32: body 17 heatmaps + 16 limb maps, face 1 grey channel.
    """
    from motion2video.generator.data import body_structures, face_structures

    if structures.domain == "body":
        return body_structures(structures.points[rows], structures.size)
    return face_structures(structures.images[rows])


def render_structures(forecast, *, domain: str, size: int, reference: Reference) -> Structures:
    """Place the observed frames and the futures in the generator's pixels (body) or render the face
    structure (face) with the conventions of the generator's training data.

    Args:
        forecast: the :class:`motion2video.stages.sampling.Forecast` from :func:`sample_futures`.
        domain: the frame generator's domain; must match the forecast's layout.
        size: the generator's image size.
        reference: from :func:`load_reference`.
    """
    layout_domain = DOMAIN_OF_LAYOUT[forecast.layout]
    if layout_domain != domain:
        raise InputError(f"the frame model makes {domain} frames, but the motion model {forecast.model} predicts "
                         f"{layout_domain} motion")
    k, tf = forecast.futures.shape[:2]
    to = forecast.observed.shape[0]
    if domain == "body":
        ref_points = None if reference.pose is None else reference.pose.points
        placement = place_body(forecast.observed, forecast.futures, size=size, reference_points=ref_points)
        points = np.concatenate([placement.reference[None], placement.observed,
                                 placement.futures.reshape(k * tf, 17, 2)]).astype(np.float32)
        return Structures("body", size, to, k, tf, points=points, placement=placement)
    images, track = _render_face_structures(forecast, size, reference)
    return Structures("face", size, to, k, tf, images=images, face_mesh=track)


def relative_head_pose(params: np.ndarray, first: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Face parameters whose head pose is taken relative to ``first`` and applied on top of ``reference``'s: the
    rotation ``R_t R_first^T R_ref`` (world axes), the translation ``T_t - T_first + T_ref``; the 52 coefficients
    unchanged. So row ``first`` becomes the reference's head pose, and the head turns and moves from there as it
    does in ``params``.

    Args:
        params: (N, 58); first, reference: (58,).
    Returns:
        (N, 58) float32.
    """
    from motion2video.core.motion import NUM_EXPRESSIONS
    from motion2video.core.rotations import axis_angle_to_matrix, matrix_to_axis_angle

    e = NUM_EXPRESSIONS
    params = np.asarray(params, np.float64)
    first, reference = np.asarray(first, np.float64), np.asarray(reference, np.float64)
    turn = axis_angle_to_matrix(params[:, e:e + 3]) @ axis_angle_to_matrix(first[e:e + 3]).T  # (N, 3, 3)
    out = params.copy()
    out[:, e:e + 3] = matrix_to_axis_angle(turn @ axis_angle_to_matrix(reference[e:e + 3]))
    out[:, e + 3:] = params[:, e + 3:] - first[e + 3:] + reference[e + 3:]
    return out.astype(np.float32)


def _render_face_structures(forecast, size: int, reference: Reference):
    """(1 + To + K*Tf, S, S) uint8 grey structure renders (reference, observed, futures) and the head mesh's
    :class:`~motion2video.generator.mesh_flow.MeshTrack` in the same rows."""
    from motion2video.core.motion import FaceMotion
    from motion2video.generator.mesh_flow import MeshTrack

    k, tf = forecast.futures.shape[:2]
    pose = reference.pose
    identity = dict(pose.identity) if pose is not None else {}
    ref_params = pose.face if pose is not None else forecast.observed[0]
    motion = np.concatenate([forecast.observed, forecast.futures.reshape(k * tf, -1)])  # (To + K*Tf, 58)
    if reference.relative_head and pose is not None:
        motion = relative_head_pose(motion, forecast.observed[0], ref_params)
    params = np.concatenate([np.asarray(ref_params, np.float32)[None], motion]).astype(np.float32)
    shape = None
    if pose is not None and pose.face_shape is not None:  # the pictured face's shape, every frame
        from motion2video.pose.face_shape import head_shape

        shape = head_shape(pose.face_shape)
    with renderer_for("face", "structure", size=size) as renderer:
        if pose is not None:
            camera = pose.camera
        else:  # the close-up camera a single-frame render of the first observed frame uses
            camera = renderer.renderer.camera_for(FaceMotion(params[1:2], forecast.fps, identity=identity))
        out = renderer.renderer.render_with_masks(FaceMotion(params, forecast.fps, identity=identity), camera=camera,
                                                  vertices=True, shape=shape)
    grey = np.rint(out.frames.astype(np.float32).mean(axis=-1)).astype(np.uint8)  # as the training data
    return grey, MeshTrack(uv=out.vertex_uv, visible=out.vertex_visible, masks=out.masks)


def structure_previews(structures: Structures, rows: slice | np.ndarray = slice(None)) -> np.ndarray:
    """RGB pictures of the structures: (1 + To + K*Tf, S, S, 3) uint8 (reference row first), or of the
    chosen ``rows`` only.

    Body: the skeleton drawn with the left/right palette; face: the grey structure render.
    """
    size = structures.size
    if structures.domain == "face":
        return np.repeat(structures.images[rows][..., None], 3, axis=-1)
    with renderer_for("body2d", "skeleton", size=size, thickness=max(1, round(size / 64)),
                      joint_radius=size / 96) as renderer:  # the points are generator pixels already
        return renderer.draw(structures.points[rows].astype(np.float64), framing=PIXELS)


def timeline_rows(structures: Structures, start: int, stop: int) -> np.ndarray:
    """Structure rows of timeline steps ``start..stop-1`` for each of the K cells: (stop - start, K) ints.

    Step t < To is observed row ``1 + t`` in every cell; step t >= To is cell k's future row
    ``1 + To + k*Tf + (t - To)``.
    """
    to, k, tf = structures.observed, structures.samples, structures.horizon
    t = np.arange(start, stop)[:, None]
    future = 1 + to + np.arange(k)[None] * tf + (t - to)
    return np.where(t < to, 1 + t, future)


def split_rows(rows: np.ndarray, structures: Structures) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(1 + To + K*Tf, ...) rows -> reference (...), observed (To, ...), futures (K, Tf, ...)."""
    to, k, tf = structures.observed, structures.samples, structures.horizon
    return rows[0], rows[1:1 + to], rows[1 + to:].reshape(k, tf, *rows.shape[1:])


def body_style(look: dict, size: int):
    """A :class:`renderers.body.BodyStyle` of ``size`` x ``size`` pixels with ``look``'s phenotype and colours."""
    from renderers.body import BodyStyle

    return BodyStyle(size=(size, size), **look)


def render_sequence(seq: np.ndarray, *, layout: str, style: str, size: int, fps: float,
                    look: dict | None = None, identity: dict | None = None,
                    face_colours: dict | None = None) -> np.ndarray:
    """Draw one sequence with its own fixed camera, fitted over the whole sequence; 3D bodies are seen from
    the front of their FIRST frame (camera azimuth = the start heading), so every cell shows its person's
    start posture from the front and the motion relative to it. All frames in memory: :func:`iter_sequence`
    streams them.

    Args:
        seq: (T, 17, 3) world joints, (T, 17, 2) pixels (body2d) or (T, 58) face parameters.
        layout: ``body3d``, ``body2d`` or ``face``.
        style: ``skeleton`` or ``mesh`` (body3d); faces are always drawn with the Anny face renderer.
        look: BodyStyle fields (phenotype, colours) for ``mesh``.
        identity, face_colours: the face's Anny identity and FaceStyle colours.
    Returns:
        (T, size, size, 3) uint8.
    """
    return np.concatenate(list(iter_sequence(seq, layout=layout, style=style, size=size, fps=fps, look=look,
                                             identity=identity, face_colours=face_colours)))


def iter_sequence(seq: np.ndarray, *, layout: str, style: str, size: int, fps: float,
                  look: dict | None = None, identity: dict | None = None,
                  face_colours: dict | None = None) -> Iterator[np.ndarray]:
    """:func:`render_sequence` as a stream of (t, size, size, 3) uint8 chunks (the style is checked at once,
    before anything is drawn)."""
    if layout != "face":
        if style == "mesh" and layout != "body3d":
            raise InputError("--style mesh needs a 3D body model; this model predicts 2D keypoints")
        if style not in ("mesh", "skeleton"):
            raise InputError(f"unknown style {style!r}; choose one of {', '.join(SEQUENCE_STYLES)}")
    return _iter_sequence(seq, layout, style, size, fps, look, identity, face_colours)


def _iter_sequence(seq, layout, style, size, fps, look, identity, face_colours) -> Iterator[np.ndarray]:
    from motion2video.core.camera import fit_camera, fit_image_framing

    if layout == "face":
        with renderer_for("face", "face", size=size, **(face_colours or {})) as r:
            yield from r.iter_draw(seq, fps, identity=identity)
        return
    azimuth = float(np.degrees(heading_of(seq[0]))) if layout == "body3d" else 0.0
    if style == "mesh":
        with renderer_for(layout, "mesh", size=size, **{**(look or {}), "azimuth_deg": azimuth}) as r:
            yield from r.iter_draw(seq, fps)
        return
    if layout == "body3d":
        placement = {"camera": fit_camera(seq.reshape(-1, 3), size, size, azimuth_deg=azimuth)}
    else:  # one 2D framing for the whole sequence, so chunks are placed alike
        placement = {"framing": fit_image_framing(seq, size, size)}
    with renderer_for(layout, "skeleton", size=size) as r:
        yield from r.iter_draw(seq, fps, **placement)
