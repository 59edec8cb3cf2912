"""Observed motion -> K sampled futures -> structure -> RGB frames -> videos (what ``synthesize`` does).

The stages are plain functions with typed results, so each can be called (and timed) alone:

1. :func:`motion2video.reference.load_reference`: the reference appearance image at the frame generator's size, and its pose.
2. :func:`sample_futures`: K futures of the observed clip from a motion model (:mod:`motion2video.forecast`).
3. :func:`render_structures`: where the person is in every frame, in the generator's structure conventions
   (the same functions that made its training pairs, :mod:`motion2video.frames.data`):

   - body: 2D joints in generator pixels; :func:`structure_maps` turns them into 17 Gaussian heatmaps + 16
     limb maps (:func:`motion2video.frames.data.body_structures`).
   - face: the Anny face rendered in the shaded grey ``"structure"`` style on black, in each frame's head
     pose and expression (:func:`motion2video.frames.data.face_structures`).
4. :func:`generate_frames`: the frame generator turns (reference image, reference structure, target
   structure) into the target frame, for the observed frames and every future, so the whole video is
   one consistent person.
5. :func:`compose_video`, :func:`structure_previews`, :func:`contact_sheet`: the grid video (every cell
   plays the observed frames framed green, then one future framed red, labelled), the same grid of
   structures, and a contact-sheet PNG.

:func:`synthesize` runs them all and writes ``OUT.mp4``, ``OUT-structure.mp4`` and ``OUT-sheet.png``, all
three or none.

The reference image and its pose (the reference structure) are loaded by :mod:`motion2video.reference`.

Placement
---------
- Body (3D models): the clip is turned about z so the person faces the camera (-y) at the first observed
  frame, and the camera *follows* the person on the ground: each frame's pelvis is moved to the same
  ground position (height, turning and limbs are kept). The generator's training sequences were short
  (1.2 s) with a fixed camera, so a person who walks several metres would leave its comfort zone (and the
  frame); following keeps the person at the reference's place and size. One camera (azimuth 0, elevation
  8 degrees, as the body renderer's default) is fitted to the observed frames (so the observed part does
  not depend on the samples), then one 2D similarity (scale + shift) maps the first observed frame's legs,
  spine and head onto the reference pose's; the futures share both.
- Body (2D models): the same, in the model's virtual-camera pixels (the pelvis keeps its first x).
- Face: one camera for the whole video, the camera of the reference image (from the pose file), else the
  Anny close-up camera of the first observed frame. The structure mesh uses the reference's identity.
"""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from motion2video.atomic import check_output_path
from motion2video.errors import InputError
from motion2video.reference import Reference, load_reference

DOMAIN_OF_LAYOUT = {"body3d": "body", "body2d": "body", "face": "face"}
MAX_SAMPLES = 64
STRUCTURE_SUFFIX = "-structure"
SHEET_SUFFIX = "-sheet"
BORDER = 4  # pixels of the green / red frame around each cell
SHEET_COLUMNS = 8
# Joints whose 2D positions align a placed body with the reference pose: pelvis, legs, spine, neck, head
# (not the arms, whose pose varies the most between a reference picture and a clip).
ALIGN_JOINTS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10)
BODY_ELEVATION_DEG = 8.0  # the body renderer's default camera
BODY_YFOV_DEG = 35.0
BODY_MARGIN = 0.12  # joints-only fits leave room for the mesh around the joints (head top, feet, hands)
GENERATE_CHUNK = 64  # target structures materialised at once (33 x 128 x 128 float32 = 2.2 MB each)


# --- small helpers ---------------------------------------------------------------------------------------

@contextlib.contextmanager
def torch_threads(count: int | None):
    """Run a block with ``torch.set_num_threads(count)`` (None: leave it), restoring the old value."""
    import torch

    if count is None:
        yield
        return
    before = torch.get_num_threads()
    torch.set_num_threads(max(1, int(count)))
    try:
        yield
    finally:
        torch.set_num_threads(before)


def default_generator_threads() -> int:
    """Half the CPU cores, 1 to 4. On the 2-core machines this was built on, two threads were slower than
    one whenever anything else ran (OpenMP threads wait on each other); see ``scripts/bench_pipeline.py``."""
    return max(1, min(4, (os.cpu_count() or 1) // 2))


def output_paths(video: str | Path) -> tuple[Path, Path, Path]:
    """``OUT.mp4`` -> (``OUT.mp4``, ``OUT-structure.mp4``, ``OUT-sheet.png``)."""
    video = Path(video)
    return (video, video.with_name(video.stem + STRUCTURE_SUFFIX + video.suffix),
            video.with_name(video.stem + SHEET_SUFFIX + ".png"))


# --- sampling ----------------------------------------------------------------------------------------------

def sample_futures(bundle, clip: np.ndarray, *, samples: int, observed: int | None = None,
                   horizon: int | None = None, start: int = 0, seed: int = 0, threads: int | None = 1,
                   source: str | None = None):
    """K futures of ``clip[start:start + observed]`` from a motion model.

    Args:
        bundle: a :class:`~motion2video.checkpoint.ModelBundle`.
        clip: (T, 17, 3) world joints or (T, 58) face parameters at the model's rate
            (:func:`motion2video.forecast.load_clip_for`).
        samples: K >= 1.
        threads: torch threads while sampling (1 is fastest for the small recurrent models here).
    Returns:
        A :class:`motion2video.forecast.Forecast`: observed (To, ...) and futures (K, Tf, ...).
    """
    from motion2video.forecast import forecast

    if not 1 <= int(samples) <= MAX_SAMPLES:
        raise InputError(f"the number of samples must be in 1..{MAX_SAMPLES}, got {samples}")
    with torch_threads(threads):
        return forecast(bundle, clip, num_samples=int(samples), observed=observed, horizon=horizon, start=start,
                        seed=seed, source=source)


# --- placement and structures ------------------------------------------------------------------------------

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
    """

    observed: np.ndarray
    futures: np.ndarray
    reference: np.ndarray
    world_observed: np.ndarray | None = None
    world_futures: np.ndarray | None = None
    camera: object | None = None


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
    from renderers.camera import fit_camera, fit_image_framing, project

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
        world_futures=None if world is None else world[to:].reshape(k, tf, 17, 3), camera=camera)


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
    """

    domain: str
    size: int
    observed: int
    samples: int
    horizon: int
    points: np.ndarray | None = None
    images: np.ndarray | None = None
    placement: BodyPlacement | None = None

    @property
    def num_targets(self) -> int:
        """Frames to generate: To + K * Tf."""
        return self.observed + self.samples * self.horizon


def structure_maps(structures: Structures, rows: slice | np.ndarray) -> np.ndarray:
    """Generator input maps for some rows of :class:`Structures` (0 = reference, then the targets).

    Returns:
        (R, C, S, S) float32: body 17 heatmaps + 16 limb maps, face 1 grey channel.
    """
    from motion2video.frames.data import body_structures, face_structures

    if structures.domain == "body":
        return body_structures(structures.points[rows], structures.size)
    return face_structures(structures.images[rows])


def render_structures(forecast, *, domain: str, size: int, reference: Reference) -> Structures:
    """Place the observed frames and the futures in the generator's pixels (body) or render the face
    structure (face) with the conventions of the generator's training data.

    Args:
        forecast: the :class:`motion2video.forecast.Forecast` from :func:`sample_futures`.
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
    return Structures("face", size, to, k, tf, images=_render_face_structures(forecast, size, reference))


def _render_face_structures(forecast, size: int, reference: Reference) -> np.ndarray:
    """(1 + To + K*Tf, S, S) uint8 grey structure renders: reference, observed, futures."""
    from motion2video.motion import FaceMotion
    from renderers.face import FaceRenderer, FaceStyle

    k, tf = forecast.futures.shape[:2]
    pose = reference.pose
    identity = dict(pose.identity) if pose is not None else {}
    ref_params = pose.face if pose is not None else forecast.observed[0]
    params = np.concatenate([np.asarray(ref_params, np.float32)[None], forecast.observed,
                             forecast.futures.reshape(k * tf, -1)]).astype(np.float32)
    style = FaceStyle(size=(size, size), style="structure", background=(0, 0, 0))
    with FaceRenderer(style) as renderer:
        if pose is not None:
            camera = pose.camera
        else:  # the close-up camera a single-frame render of the first observed frame uses
            camera = renderer.camera_for(FaceMotion(params[1:2], forecast.fps, identity=identity))
        grey = renderer.render(FaceMotion(params, forecast.fps, identity=identity), camera=camera)
    return np.rint(grey.astype(np.float32).mean(axis=-1)).astype(np.uint8)  # as the training data


# --- generation --------------------------------------------------------------------------------------------

def generate_frames(model, reference_image: np.ndarray, reference_structure: np.ndarray,
                    target_structures: np.ndarray, *, batch_size: int = 4,
                    channels_last: bool = True) -> np.ndarray:
    """Frames of one reference appearance in many target structures.

    Computes exactly what :class:`~motion2video.frames.model.FrameGenerator` computes for each target,
    ``decoder(enc_img(x_ref) + enc_pose(p_tgt) - enc_pose(p_ref))`` (+ ``x_ref`` for residual models), but
    encodes the reference image and structure once instead of once per target (the reference is the
    same for the whole video), under ``torch.inference_mode``.

    Args:
        model: a FrameGenerator (or a loaded frame model with ``.model``).
        reference_image: (S, S, 3) uint8.
        reference_structure: (C, S, S) float32.
        target_structures: (N, C, S, S) float32.
        batch_size: targets per forward pass.
        channels_last: run the convolutions in channels-last memory format.
    Returns:
        (N, S, S, 3) uint8.
    """
    import torch

    from motion2video.frames.model import images_to_tensor, tensor_to_images

    net = getattr(model, "model", model)
    cfg = net.config
    size, channels = cfg.image_size, cfg.structure_channels
    if reference_image.shape != (size, size, 3):
        raise ValueError(f"reference_image must be ({size}, {size}, 3), got {reference_image.shape}")
    if reference_structure.shape != (channels, size, size):
        raise ValueError(f"reference_structure must be ({channels}, {size}, {size}), got {reference_structure.shape}")
    if target_structures.ndim != 4 or target_structures.shape[1:] != (channels, size, size):
        raise ValueError(f"target_structures must be (N, {channels}, {size}, {size}), got {target_structures.shape}")
    if batch_size < 1:
        raise ValueError(f"batch_size must be >= 1, got {batch_size}")
    fmt = torch.channels_last if channels_last else torch.contiguous_format
    net.eval()
    net.to(memory_format=fmt)
    out = np.empty((len(target_structures), size, size, 3), np.uint8)
    with torch.inference_mode():
        x_ref = images_to_tensor(reference_image[None]).contiguous(memory_format=fmt)  # (1, 3, S, S)
        p_ref = torch.from_numpy(np.ascontiguousarray(reference_structure[None], np.float32))
        img_feats = net.image_encoder(x_ref * 2.0 - 1.0)
        ref_feats = net.pose_encoder(p_ref.contiguous(memory_format=fmt))
        base = [fi - fp for fi, fp in zip(img_feats, ref_feats)]  # per level (1, C_l, H_l, W_l)
        for start in range(0, len(target_structures), batch_size):
            p_tgt = torch.from_numpy(np.ascontiguousarray(target_structures[start:start + batch_size], np.float32))
            tgt_feats = net.pose_encoder(p_tgt.contiguous(memory_format=fmt))
            y = net.decoder([b + t for b, t in zip(base, tgt_feats)])  # (B, 3, S, S)
            y = torch.sigmoid(y) if cfg.output == "direct" else x_ref + y
            out[start:start + len(p_tgt)] = tensor_to_images(y)
    return out


@dataclass(frozen=True)
class GeneratedFrames:
    """Generated frames. observed: (To, S, S, 3) uint8. futures: (K, Tf, S, S, 3) uint8."""

    observed: np.ndarray
    futures: np.ndarray


def generate_video_frames(model, reference: Reference, structures: Structures, *, batch_size: int = 4,
                          threads: int | None = None, channels_last: bool = True) -> GeneratedFrames:
    """Run :func:`generate_frames` over every observed and future frame of :class:`Structures`, building
    the structure maps a chunk at a time (so a long video never holds all of them). A warp generator
    (:class:`~motion2video.frames.warp.WarpGenerator`) goes through its ``encode_reference`` / ``decode``
    at the structures' size instead (the person generated at the model's size, pasted into the reference)."""
    from motion2video.frames.warp import WarpGenerator

    net = getattr(model, "model", model)
    if isinstance(net, WarpGenerator):
        return _generate_warp_frames(net, reference, structures, batch_size=batch_size, threads=threads)
    size = net.config.image_size
    if structures.size != size:
        raise ValueError(f"structures are {structures.size} px but the generator makes {size} px frames")
    ref_structure = structure_maps(structures, slice(0, 1))[0]
    n = structures.num_targets
    frames = np.empty((n, size, size, 3), np.uint8)
    with torch_threads(threads):
        for start in range(0, n, GENERATE_CHUNK):
            stop = min(n, start + GENERATE_CHUNK)
            maps = structure_maps(structures, slice(1 + start, 1 + stop))
            frames[start:stop] = generate_frames(net, reference.image, ref_structure, maps, batch_size=batch_size,
                                                 channels_last=channels_last)
    to, k, tf = structures.observed, structures.samples, structures.horizon
    return GeneratedFrames(observed=frames[:to], futures=frames[to:].reshape(k, tf, size, size, 3))


def _generate_warp_frames(net, reference: Reference, structures: Structures, *, batch_size: int,
                          threads: int | None) -> GeneratedFrames:
    """Every target of :class:`Structures` from one reference state, one person crop for the whole video."""
    size = structures.size
    if reference.image.shape[:2] != (size, size):
        raise ValueError(f"the reference is {reference.image.shape[:2]} px but the structures are {size} px")
    with torch_threads(threads):
        state = net.encode_reference(reference.image, structures.points[0])
        frames = net.decode(state, structures.points[1:], batch_size=batch_size)
    to, k, tf = structures.observed, structures.samples, structures.horizon
    return GeneratedFrames(observed=frames[:to], futures=frames[to:].reshape(k, tf, size, size, 3))


# --- layouts -----------------------------------------------------------------------------------------------

def compose_video(observed: np.ndarray, futures: np.ndarray, *, border: int = BORDER) -> np.ndarray:
    """The grid video: every cell plays the observed frames framed green (labelled ``observed``), then one
    future framed red (labelled ``sample k``).

    Args:
        observed: (To, H, W, 3) uint8. futures: (K, Tf, H, W, 3) uint8.
    Returns:
        (To + Tf, H', W', 3) uint8.
    """
    from motion2video.video import label, observed_future_video

    obs = label(observed, "observed", inset=border)
    futs = [label(f, f"sample {k + 1}", inset=border) for k, f in enumerate(futures)]
    return observed_future_video(obs, futs, None, border=border)


def structure_previews(structures: Structures) -> np.ndarray:
    """RGB pictures of the structures: (1 + To + K*Tf, S, S, 3) uint8 (reference row first).

    Body: the skeleton drawn with the left/right palette; face: the grey structure render.
    """
    size = structures.size
    if structures.domain == "face":
        return np.repeat(structures.images[..., None], 3, axis=-1)
    from motion2video.skeletons import H36M_17
    from renderers.skeleton import SkeletonStyle, draw_skeleton

    style = SkeletonStyle(size=(size, size), thickness=max(1, round(size / 64)), joint_radius=size / 96)
    canvas = np.zeros((size, size, 3), np.uint8)
    return np.stack([draw_skeleton(canvas, p, H36M_17, style) for p in structures.points.astype(np.float64)])


def split_rows(rows: np.ndarray, structures: Structures) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(1 + To + K*Tf, ...) rows -> reference (...), observed (To, ...), futures (K, Tf, ...)."""
    to, k, tf = structures.observed, structures.samples, structures.horizon
    return rows[0], rows[1:1 + to], rows[1 + to:].reshape(k, tf, *rows.shape[1:])


def contact_sheet(observed: np.ndarray, futures: np.ndarray, *, header: tuple = (),
                  columns: int = SHEET_COLUMNS, border: int = BORDER) -> np.ndarray:
    """One picture of the result.

    Row 0: the ``header`` pictures (e.g. the reference image and its structure), then evenly spaced
    observed frames (green); one row per sample: evenly spaced future frames (red). Cells are labelled.

    Args:
        observed: (To, H, W, 3) uint8. futures: (K, Tf, H, W, 3) uint8.
        header: (image (H, W, 3) uint8, label) pairs shown first, unframed.
    Returns:
        (H', W', 3) uint8.
    """
    from motion2video.video import GREEN, RED, add_border, grid

    to, tf = observed.shape[0], futures.shape[1]
    cells = [image for image, _ in header]
    labels = [text for _, text in header]
    for t in _spread(to, columns - len(cells)):
        cells.append(add_border(observed[t], GREEN, border))
        labels.append(f"observed {t}")
    blank = np.zeros_like(observed[0])
    cells += [blank] * (columns - len(cells))
    labels += [""] * (columns - len(labels))
    for k, future in enumerate(futures):
        index = _spread(tf, columns)
        for t in index:
            cells.append(add_border(future[t], RED, border))
            labels.append(f"s{k + 1} +{t + 1}")
        cells += [blank] * (columns - len(index))
        labels += [""] * (columns - len(index))
    return grid([c[None] for c in cells], labels, columns)[0]


def _spread(length: int, count: int) -> list[int]:
    """Up to ``count`` distinct, evenly spaced indices into ``range(length)`` (first and last included)."""
    if length <= count:
        return list(range(length))
    return sorted({int(round(i)) for i in np.linspace(0, length - 1, count)})


# --- the whole pipeline ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class SynthesisConfig:
    """Options of :func:`synthesize`.

    Attributes:
        samples: K futures (1..64).
        observed: observed frames (None: the motion model's training value).
        horizon: future frames (None: the motion model's training value).
        start: first observed frame of the clip.
        seed: sampling seed (the same seed gives the same frames).
        batch_size: generator frames per forward pass (4 was fastest at 128 px on 2 cores, with channels_last).
        motion_threads: torch threads while sampling (1: the small recurrent models are fastest so).
        generator_threads: torch threads while generating (None: :func:`default_generator_threads`).
        crf, preset: x264 settings of the two videos.
        size: output frame size (None: the generator's size); another size needs a warp generator, which
            keeps the reference's background at this size and generates the person at its own size.
    """

    samples: int = 5
    observed: int | None = None
    horizon: int | None = None
    start: int = 0
    seed: int = 0
    batch_size: int = 4
    motion_threads: int | None = 1
    generator_threads: int | None = None
    crf: int = 18
    preset: str = "medium"
    size: int | None = None


@dataclass
class SynthesisResult:
    """What :func:`synthesize` wrote and how long each stage took.

    Attributes:
        video, structure_video, sheet: the written files.
        frames: (T, H, W, 3) shape of the grid video.
        samples, observed, horizon: K, To, Tf.
        fps: frame rate of the videos.
        domain: ``"body"`` or ``"face"``.
        notes: conversions and assumptions (one line each).
        timings: seconds per stage: load, sampling, structures, generation, compose, encoding, total.
        forecast: the sampled motion (:class:`motion2video.forecast.Forecast`).
        structures: the :class:`Structures` used.
    """

    video: Path
    structure_video: Path
    sheet: Path
    frames: tuple[int, ...]
    samples: int
    observed: int
    horizon: int
    fps: float
    domain: str
    notes: tuple[str, ...]
    timings: dict[str, float]
    forecast: object = field(repr=False)
    structures: Structures = field(repr=False)


def check_output(path: str | Path) -> tuple[Path, Path, Path]:
    """Validate ``OUT.mp4`` before any work: extension and an existing, writable folder.

    Returns:
        :func:`output_paths` of it.
    """
    path = check_output_path(path, (".mp4",))
    for p in output_paths(path):
        if p.is_dir():
            raise InputError("the output path is a directory", p)
    return output_paths(path)


def write_outputs(paths: tuple[Path, Path, Path], video: np.ndarray, structure_video: np.ndarray,
                  sheet: np.ndarray, *, fps: float, crf: int = 18, preset: str = "medium") -> None:
    """Write the video, the structure video and the sheet, all three or none: each is written to a
    temporary name beside its destination and the three are renamed only when all succeeded."""
    from motion2video.video import write_image, write_video

    temps = [p.with_name(f".{p.stem}.{os.getpid()}.partial{p.suffix}") for p in paths]
    try:
        write_video(temps[0], video, fps, crf=crf, preset=preset)
        write_video(temps[1], structure_video, fps, crf=crf, preset=preset)
        write_image(temps[2], sheet)
        for tmp, final in zip(temps, paths):
            os.replace(tmp, final)
    finally:
        for tmp in temps:
            tmp.unlink(missing_ok=True)


def synthesize(*, motion_model, frame_model, input_path: str | Path, reference: str | Path,
               output: str | Path, config: SynthesisConfig = SynthesisConfig(),
               reference_pose: str | Path | None = None) -> SynthesisResult:
    """Observed clip + reference image -> K futures as RGB videos: ``OUT.mp4``, ``OUT-structure.mp4`` and
    ``OUT-sheet.png`` (see the module docstring).

    Args:
        motion_model: a checkpoint path / shipped name, or a loaded ModelBundle.
        frame_model: a checkpoint path / shipped name, or a loaded frame model (LoadedFrameModel).
        input_path: the observed clip (.bvh / body .npz for body models; FaceMotion .npz / .csv for face).
        reference: the reference appearance image.
        output: ``OUT.mp4``.
        config: the options.
        reference_pose: the reference pose file (default: ``IMAGE.pose.npz`` when it exists).
    Returns:
        A :class:`SynthesisResult`.
    Raises:
        InputError: any user-fixable problem, before anything is written.
    """
    from motion2video.checkpoint import load_model
    from motion2video.forecast import load_clip_for
    from motion2video.frames.checkpoint import load_frame_model

    timings: dict[str, float] = {}
    t_all = t0 = time.perf_counter()
    paths = check_output(output)
    bundle = load_model(motion_model) if isinstance(motion_model, (str, Path)) else motion_model
    frames_model = load_frame_model(frame_model) if isinstance(frame_model, (str, Path)) else frame_model
    gen_config = frames_model.model.config
    domain = gen_config.domain
    layout_domain = DOMAIN_OF_LAYOUT[bundle.data_config.layout]
    if layout_domain != domain:
        raise InputError(f"the frame model makes {domain} frames but the motion model {bundle.name} predicts "
                         f"{layout_domain} motion: give a {layout_domain} frame model (frames-{layout_domain}-128)")
    size = gen_config.image_size if config.size is None else int(config.size)
    if size != gen_config.image_size and getattr(frames_model, "kind", "analogy") != "warp":
        raise InputError(f"--size {size} needs a warp frame model (this {domain} generator makes "
                         f"{gen_config.image_size} px frames only)")
    clip = load_clip_for(bundle, input_path)
    ref = load_reference(reference, size=size, domain=domain, pose_path=reference_pose)
    if domain == "body" and ref.pose is not None:
        from motion2video.frames.warp import check_reference_points
        from motion2video.reference import reference_pose_path

        check_reference_points(ref.pose.points, width=size, height=size,
                               path=reference_pose if reference_pose is not None else reference_pose_path(reference))
    timings["load"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    fc = sample_futures(bundle, clip, samples=config.samples, observed=config.observed, horizon=config.horizon,
                        start=config.start, seed=config.seed, threads=config.motion_threads, source=str(input_path))
    timings["sampling"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    structures = render_structures(fc, domain=domain, size=size, reference=ref)
    timings["structures"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    threads = config.generator_threads or default_generator_threads()
    generated = generate_video_frames(frames_model, ref, structures, batch_size=config.batch_size, threads=threads)
    timings["generation"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    video = compose_video(generated.observed, generated.futures)
    ref_preview, obs_preview, fut_preview = split_rows(structure_previews(structures), structures)
    structure_video = compose_video(obs_preview, fut_preview)
    sheet = contact_sheet(generated.observed, generated.futures,
                          header=((ref.image, "reference"), (ref_preview, "ref. structure")))
    timings["compose"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    write_outputs(paths, video, structure_video, sheet, fps=fc.fps, crf=config.crf, preset=config.preset)
    timings["encoding"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_all
    return SynthesisResult(video=paths[0], structure_video=paths[1], sheet=paths[2], frames=tuple(video.shape),
                           samples=structures.samples, observed=structures.observed, horizon=structures.horizon,
                           fps=float(fc.fps), domain=domain, notes=ref.notes, timings=timings, forecast=fc,
                           structures=structures)


# --- the Anny mesh path of the same futures ---------------------------------------------------------------

def render_mesh_frames(structures: Structures, *, size: int = 256, fps: float = 25.0) -> GeneratedFrames:
    """The Anny body in the same placed poses as the structures (the followed, front-facing 3D joints and
    the camera they were placed with), one body fit for all frames so every cell shows the same body.

    Args:
        structures: body structures from a 3D body model (:func:`render_structures`).
        size: frame size in pixels.
    Returns:
        :class:`GeneratedFrames`: observed (To, size, size, 3) and futures (K, Tf, size, size, 3) uint8.
    """
    from motion2video.motion import Motion
    from renderers.body import BodyRenderer, BodyStyle

    placement = structures.placement
    if placement is None or placement.world_observed is None:
        raise InputError("the mesh video needs a 3D body model (this forecast has no 3D joints)")
    k, tf = placement.world_futures.shape[:2]
    to = placement.world_observed.shape[0]
    every = np.concatenate([placement.world_observed, placement.world_futures.reshape(k * tf, 17, 3)])
    camera = placement.camera.with_size(size, size)
    with BodyRenderer(BodyStyle(size=(size, size))) as renderer:
        frames = renderer.render(Motion(every.astype(np.float32), fps), camera=camera)
    return GeneratedFrames(observed=frames[:to], futures=frames[to:].reshape(k, tf, size, size, 3))
