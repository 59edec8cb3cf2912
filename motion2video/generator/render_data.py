"""Rendering the synthetic appearance sequences of :mod:`motion2video.generator.data` with the Anny renderers.

Bodies: a window of a real mocap clip (loaded as canonical h36m-17 through the BVH loader), posed on an
Anny body by the body renderer's IK, one identity (phenotype + region colours), a background crop, a camera
yaw and elevation, a light level and tint; control points are the 3D joints projected with the camera that
rendered the frames.

Faces: a window of a real ARKit capture (expression) with head pose from the face-dynamics module, an
Anny face with one identity, background, camera yaw and light; the structure is the same face rendered in
the face renderer's shaded grey structure style; control points are projected face-mesh vertices.

Everything a shard holds depends only on ``(spec, shard index)``, so shards can be rendered in any order
and an interrupted generation resumes where it stopped.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from motion2video.core.errors import InputError
from motion2video.generator.specs import (DatasetSpec, FrameSequences, Identity, background_crop, background_images,
                                       default_data_root, identities, is_test_clip)

# Camera and light variation per sequence.
BODY_AZIMUTH_DEG = (-40.0, 40.0)
BODY_ELEVATION_DEG = (0.0, 15.0)
FACE_AZIMUTH_DEG = (-25.0, 25.0)
FACE_HEAD_AMPLITUDE = 1.5  # procedural head-pose excursions (x the face-dynamics defaults)
FACE_CONTROL_POINTS = 48  # projected face-mesh vertices used by the limb-warp baseline
LIGHT_GAIN = (0.75, 1.15)
LIGHT_TINT = 0.08  # per-channel multiplicative tint range around 1


@dataclass
class SequenceSource:
    """Everything needed to render the sequences of one split: the clips, identities and backgrounds."""

    spec: DatasetSpec
    clip_paths: list[Path]
    clip_names: list[str]
    identities: list[Identity]
    backgrounds: list[np.ndarray]
    manifest: dict = field(default_factory=dict)
    _clips: dict = field(default_factory=dict)

    @classmethod
    def create(cls, spec: DatasetSpec, *, data_root: str | Path | None = None) -> "SequenceSource":
        root = Path(data_root) if data_root is not None else default_data_root()
        if spec.domain == "body":
            from motion2video.formats.manifest import read_manifest

            folder = root / "mocap"
            manifest_path = folder / "manifest.csv"
            if not manifest_path.is_file():
                raise InputError("no mocap manifest.csv here (give --data-root, the folder holding mocap/)",
                                 folder)
            manifest = read_manifest(manifest_path)
            names = [f for f in manifest if is_test_clip(f) == (spec.split == "test")]
        else:
            folder = root / "face"
            if not folder.is_dir():
                raise InputError("no face capture folder here (give --data-root, the folder holding face/)", folder)
            manifest = {}
            names = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*.csv")
                           if p.name != "manifest.csv")
            names = [f for f in names if is_test_face_clip(f) == (spec.split == "test")]
        if not names:
            raise InputError(f"no {spec.domain} clips for the {spec.split} split", folder)
        return cls(spec=spec, clip_paths=[folder / n for n in names], clip_names=names,
                   identities=identities(spec.split, spec.num_identities, seed=spec.seed),
                   backgrounds=background_images(), manifest=manifest)

    def clip(self, i: int):
        """The i-th clip, loaded once: a Motion (body) or a FaceMotion (face)."""
        if i not in self._clips:
            if self.spec.domain == "body":
                from motion2video.formats.mocap import load_mocap

                self._clips[i] = load_mocap(self.clip_paths[i], manifest=self.manifest[self.clip_names[i]])
            else:
                from motion2video.data.face_data import load_face_clip

                self._clips[i] = load_face_clip(self.clip_paths[i])
        return self._clips[i]

    def close(self) -> None:
        self._clips.clear()


def is_test_face_clip(name: str) -> bool:
    """Held-out face captures: one of the five Live Link Face takes (``S07-001``), fixed so both splits
    keep real captures (there are only six files)."""
    return Path(name).stem == "S07-001"


def window_times(rng: np.random.Generator, num_frames: int, fps: float, *, frames: int,
                 seconds: float) -> np.ndarray:
    """(frames,) increasing frame positions spread evenly over a random window of ``seconds`` (or the whole
    clip when shorter), rounded to source frames."""
    span = min(num_frames - 1, int(round(seconds * fps)))
    start = int(rng.integers(0, num_frames - span)) if num_frames - span > 0 else 0
    return np.round(start + np.linspace(0, span, frames)).astype(np.int64)


def light_jitter(rng: np.random.Generator) -> np.ndarray:
    """(3,) multiplicative light level and tint for the rendered person."""
    return rng.uniform(*LIGHT_GAIN) * rng.uniform(1.0 - LIGHT_TINT, 1.0 + LIGHT_TINT, 3)


def relight(frames: np.ndarray, masks: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """Scale the person's pixels (``masks``) by ``gain`` per channel: (T, H, W, 3) uint8 -> same."""
    out = frames.astype(np.float32)
    out[masks] *= gain
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def _rgb255(colour: tuple[float, float, float]) -> tuple[int, int, int]:
    return tuple(int(round(255 * c)) for c in colour)


def identity_vertex_colors(identity: Identity, palette: np.ndarray) -> np.ndarray | None:
    """(V, 3) float Anny vertex colours of an identity with patterned clothing (the body style's region
    colours ``palette`` (R, 3) uint8, with each pattern blended in by its region's weight), or None when
    its clothes are flat."""
    from renderers import anny_model

    if identity.top_pattern is None and identity.trousers_pattern is None:
        return None
    rest = anny_model.anny_rest(dict(identity.phenotype))
    weights = anny_model.region_weights(rest)  # (V, R)
    colours = weights @ (np.asarray(palette, np.float64) / 255.0)  # (V, 3)
    for region, pattern, base in ((anny_model.TOP, identity.top_pattern, identity.top),
                                  (anny_model.TROUSERS, identity.trousers_pattern, identity.trousers)):
        if pattern is None:
            continue
        w = weights[:, region] * pattern.weights(rest.vertices)  # (V,)
        colours += w[:, None] * (np.asarray(pattern.colour) - np.round(255 * np.asarray(base)) / 255.0)[None]
    return np.clip(colours, 0.0, 1.0)


def render_body_sequence(source: SequenceSource, rng: np.random.Generator, identity: Identity, *,
                         head: bool = False) -> tuple["BodyWindow", int, int]:
    """One body sequence as a :class:`BodyWindow` (with the mesh vertices when the spec asks for them, the head
    masks when ``head``), its clip index and start."""
    from motion2video.core.motion import Motion

    spec = source.spec
    ci = int(rng.integers(len(source.clip_paths)))
    clip = source.clip(ci)
    times = window_times(rng, clip.num_frames, clip.fps, frames=spec.frames_per_sequence,
                         seconds=spec.window_seconds)
    motion = Motion(clip.joints[times], clip.fps, source=clip.source)
    window = render_body_window(motion, identity, rng, source.backgrounds, spec.image_size, head=head,
                                vertices=spec.vertices)
    return window, ci, int(times[0])


@dataclass
class BodyWindow:
    """A rendered body window: images (T, S, S, 3) uint8, points (T, 17, 2) float32 projected joints,
    masks (T, S, S) bool silhouettes, head_masks (T, S, S) bool visible head or None; vertex_uv (T, V, 2)
    float32 and vertex_visible (T, V) bool the mesh vertices' pixels and front-surface flags, or None."""

    images: np.ndarray
    points: np.ndarray
    masks: np.ndarray
    head_masks: np.ndarray | None = None
    vertex_uv: np.ndarray | None = None
    vertex_visible: np.ndarray | None = None


def render_body_window(motion, identity: Identity, rng: np.random.Generator, backgrounds: list[np.ndarray],
                       size: int, *, head: bool = False, vertices: bool = False) -> BodyWindow:
    """Render the frames of ``motion`` (canonical 3D) as ``identity`` the way the training data is made: a
    background crop, camera yaw and elevation and a light level drawn from ``rng`` (in that order), the
    camera fitted over the window; ``head`` also renders the visible head masks, ``vertices`` keeps the mesh
    vertices' pixels and visibility (the mesh generator's correspondence)."""
    from motion2video.core.camera import project
    from renderers.body import BodyStyle
    from renderers.registry import renderer_for

    look = dict(
        phenotype=dict(identity.phenotype),
        skin=_rgb255(identity.skin), top=_rgb255(identity.top), trousers=_rgb255(identity.trousers),
        shoes=_rgb255(identity.shoes), hair=_rgb255(identity.hair),
        background=background_crop(rng, backgrounds, size),
        azimuth_deg=float(rng.uniform(*BODY_AZIMUTH_DEG)),
        elevation_deg=float(rng.uniform(*BODY_ELEVATION_DEG)),
    )
    look["vertex_colors"] = identity_vertex_colors(identity, BodyStyle(size=(size, size), **look).region_colors())
    gain = light_jitter(rng)
    with renderer_for("body3d", "mesh", size=size, **look) as renderer:
        out = renderer.renderer.render_with_masks(motion, head=head, vertices=vertices)
    images = relight(out.frames, out.masks, gain)
    points = project(motion.joints, out.camera)[..., :2].astype(np.float32)  # (T, 17, 2)
    return BodyWindow(images, points, out.masks, out.head_masks, out.vertex_uv, out.vertex_visible)


def render_shard(source: SequenceSource, shard: int, *, heads: bool = False,
                 on_sequence: Callable[[int], object] | None = None) -> tuple[FrameSequences, np.ndarray | None]:
    """Render the sequences of shard ``shard`` of ``source.spec``: the sequences, and with ``heads`` (body
    splits) the visible head of every frame, (N, T, S, S) bool (else None). The frames are the same either
    way: the head masks come from a second, depth-only pass."""
    spec = source.spec
    if heads and spec.domain != "body":
        raise ValueError("head masks are rendered for body splits only")
    first = shard * spec.sequences_per_shard
    last = min(spec.num_sequences, first + spec.sequences_per_shard)
    if first >= last:
        raise ValueError(f"shard {shard} is past the end of the split ({spec.num_shards} shards)")
    images, points, structs, ident, clips, starts, masks, uvs, seen, head_masks = ([] for _ in range(10))
    for i in range(first, last):
        rng = np.random.default_rng([spec.seed, 1 + ("train", "test").index(spec.split), i])
        ident_index = i % spec.num_identities
        identity = source.identities[ident_index]
        if spec.domain == "body":
            window, ci, start = render_body_sequence(source, rng, identity, head=heads)
            im, pts, mk = window.images, window.points, window.masks
            if spec.vertices:
                uvs.append(window.vertex_uv.astype(np.float16))
                seen.append(window.vertex_visible)
            if heads:
                head_masks.append(window.head_masks)
        else:
            im, pts, st, mk, ci, start, mesh = render_face_sequence(source, rng, identity)
            structs.append(st)
            if spec.vertices:
                uvs.append(mesh[0].astype(np.float16))
                seen.append(mesh[1])
        images.append(im)
        masks.append(mk)
        points.append(pts)
        ident.append(ident_index)
        clips.append(source.clip_names[ci])
        starts.append(start)
        if on_sequence is not None:
            on_sequence(1)
    seqs = FrameSequences(
        domain=spec.domain, images=np.stack(images), points=np.stack(points),
        structure_images=np.stack(structs) if structs else None,
        identity=np.asarray(ident, np.int64), clip=np.asarray(clips), start=np.asarray(starts, np.int64),
        masks=np.stack(masks),
        vertex_uv=np.stack(uvs) if uvs else None, vertex_visible=np.stack(seen) if seen else None,
    )
    return seqs, np.stack(head_masks) if heads else None


def farthest_point_subset(points: np.ndarray, count: int) -> np.ndarray:
    """(count,) indices of a well-spread subset of (N, 3) points (greedy farthest-point sampling, starting
    from the point with the smallest y, i.e. the front-most)."""
    count = min(count, len(points))
    chosen = [int(np.argmin(points[:, 1]))]
    dist = np.linalg.norm(points - points[chosen[0]], axis=1)
    for _ in range(count - 1):
        nxt = int(np.argmax(dist))
        chosen.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(points - points[nxt], axis=1))
    return np.asarray(chosen, np.int64)


def face_control_vertices(vertices: np.ndarray, *, count: int = FACE_CONTROL_POINTS) -> np.ndarray:
    """Indices of face-front vertices used as limb-warp control points, chosen on one frame's (K, 3) head
    sub-mesh vertices: the front half of the head (y below the head's median, the face looks along -y) in
    the upper 65 % of the drawn mesh's height range (head and chin, not the chest), spread by
    farthest-point sampling."""
    y, z = vertices[:, 1], vertices[:, 2]
    front = (y < np.median(y)) & (z > z.min() + 0.35 * (z.max() - z.min()))
    ids = np.flatnonzero(front)
    return ids[farthest_point_subset(vertices[ids], count)]


def yawed_camera(camera, azimuth_deg: float):
    """The camera turned about the vertical axis through its target by ``azimuth_deg``."""
    from motion2video.core.camera import PinholeCamera

    a = np.radians(azimuth_deg)
    rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    target = np.asarray(camera.target, np.float64)
    position = target + rot @ (np.asarray(camera.position, np.float64) - target)
    return PinholeCamera(tuple(float(v) for v in position), camera.target, camera.yfov, camera.width,
                         camera.height)


def render_face_sequence(source: SequenceSource, rng: np.random.Generator, identity: Identity):
    """One face sequence.

    Returns:
        images (T, S, S, 3) uint8, points (T, K, 2) float32 projected control vertices, structures
        (T, S, S) uint8 grey structure renders, masks (T, S, S) bool, clip index, first source frame, and
        (vertex_uv (T, V, 2) float32, vertex_visible (T, V) bool) of the head mesh when the spec keeps vertices,
        else None.
    """
    from motion2video.data.face_dynamics import head_pose_track
    from motion2video.core.motion import NUM_EXPRESSIONS, FaceMotion
    from renderers.registry import renderer_for

    spec = source.spec
    size = spec.image_size
    ci = int(rng.integers(len(source.clip_paths)))
    clip = source.clip(ci)
    times = window_times(rng, clip.num_frames, clip.fps, frames=spec.frames_per_sequence,
                         seconds=spec.window_seconds)
    params = clip.params[times].copy()  # (T, 58)
    if not np.any(params[:, NUM_EXPRESSIONS:]):  # the capture has no head pose: add a procedural track
        track = head_pose_track(clip.num_frames, clip.fps, int(rng.integers(2**31)), amplitude=FACE_HEAD_AMPLITUDE)
        params[:, NUM_EXPRESSIONS:] = track[times]
    face = FaceMotion(params, clip.fps, identity=dict(identity.phenotype), source=clip.source)
    background = background_crop(rng, source.backgrounds, size)
    appearance = dict(skin=_rgb255(identity.skin),  # FaceStyle's default "appearance" style
                      hair=_rgb255(identity.hair), iris=_rgb255(identity.iris),
                      lips=_rgb255(tuple(c * f for c, f in zip(identity.skin, (0.85, 0.6, 0.6)))),
                      top=_rgb255(identity.top), background=background)
    azimuth = float(rng.uniform(*FACE_AZIMUTH_DEG))
    gain = light_jitter(rng)
    with renderer_for("face", "face", size=size, **appearance) as drawer:
        renderer = drawer.renderer
        camera = yawed_camera(renderer.camera_for(face), azimuth)
        out = renderer.render_with_masks(face, camera=camera, vertices=spec.vertices)
        verts = np.concatenate([v for _, v in renderer.vertices(face)])  # (T, K, 3)
    with renderer_for("face", "structure", size=size) as drawer:
        grey = drawer.draw(face, camera=camera)  # (T, S, S, 3)
    images = relight(out.frames, out.masks, gain)
    control = face_control_vertices(verts[0])
    points = np.concatenate([out.landmarks, camera.project(verts[:, control])[..., :2]], axis=1)  # (T, 8+K, 2)
    points = points.astype(np.float32)
    structures = np.rint(grey.astype(np.float32).mean(axis=-1)).astype(np.uint8)  # (T, S, S)
    mesh = (out.vertex_uv, out.vertex_visible) if spec.vertices else None
    return images, points, structures, out.masks, ci, int(times[0]), mesh
