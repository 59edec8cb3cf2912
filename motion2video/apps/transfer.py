"""Behaviour transfer (Blattmann et al., CVPR 2021): the behaviour of one clip re-enacted from another
clip's posture, flow-sampled new behaviours, the side-by-side videos, and the paper's Table 1 / Table 3
protocol.

Pipeline (``motion2video transfer``):

1. ``SOURCE[s : s + 1 + H]`` (its first frame is the source's own start posture x_t) is encoded exactly
   like a training behaviour sequence: the window's canonical frame is taken at its FIRST frame (the same
   anchor the training windows use, whose behaviour sequence starts at the last observed frame), then the
   checkpoint's normalisation. The behaviour encoder's posterior mean is z_beta (:func:`behavior_latents`).
2. ``TARGET[F]`` is encoded the same way (a one-frame sequence, anchored at itself); the decoder enacts
   z_beta from it for H frames (:meth:`BehaviorModel.transfer`); a model with ``root_trajectory`` enacts it
   along the source's root path. Before that the decoder is fitted (``--adapt-steps``) to the source's motion
   retargeted onto the target: the source's root-relative limb directions on the target's bones, starting at the
   target's posture and blending into the source's over 0.4 s (:func:`~motion2video.stages.latents.reenact_source`).
3. The H generated frames are decoded back with the TARGET's window frame; 3D bodies then get the bone
   lengths of the target's start posture in every frame (:func:`~motion2video.stages.latents.rigid_bones`).

Root trajectory: the body layouts carry the root as features (x, y relative to the start posture in its
heading-aligned canonical frame; z = height above the floor), so the model generates the root motion along
with the pose. Decoding with the target's frame puts the re-enactment's first frame exactly at the target's
start position and heading, and the root then moves as the behaviour dictates *relative to the target's
heading*: a source that walks two metres forward makes the target walk two metres in the direction it
faces, wherever the source walked in its own world. Root height is absolute (above the floor). Face models
have no root: head pose is part of the 58 parameters and is generated like the expression.

Frame indices given by the user (``--target-frame``, ``--behavior-start``) count frames of the FILE at its
own rate; clips are resampled to the model's rate (25 fps by default) and indices converted
(:func:`model_frame`).

The Table 1 / Table 3 protocol is :mod:`motion2video.evaluation.transfer_protocol`; :func:`transfer_to_files` is the
``transfer`` command's work.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator

import cv2
import numpy as np
import torch

from motion2video.core.atomic import save_npz
from motion2video.core.camera import fit_camera
from motion2video.core.errors import InputError
from motion2video.data import windows as W
from motion2video.formats.bvh_write import write_bvh_files
from motion2video.formats.video import VideoWriter
from motion2video.generator.checkpoint import load_frame_model
from motion2video.models.baselines import BASELINES
from motion2video.models.checkpoint import ModelBundle, load_model
from motion2video.stages.clips import LoadedClip, load_clip, model_frame
from motion2video.stages.generation import generate_video_frames
from motion2video.stages.reference import Reference, ReferencePose, cut_to_view, load_reference
from motion2video.stages.latents import (
    ADAPT_STEPS,
    behavior_model,
    decode_sequences,
    encode_sequences,
    reenact_source,
    rigid_bones,
)
from motion2video.stages.sampling import Forecast, as_model_input
from motion2video.stages.structure import (
    ALT_FACE_COLOURS,
    ALT_FACE_IDENTITY,
    BODY_ELEVATION_DEG,
    BODY_MARGIN,
    BODY_YFOV_DEG,
    DOMAIN_OF_LAYOUT,
    SOURCE_LOOK,
    TARGET_LOOK,
    iter_sequence,
    place_body,
    reference_in_view,
    render_structures,
)
from motion2video.stages.layout import check_bvh_output, check_cell_size, check_video_and_npz, iter_mark_segments
from motion2video.formats.video import GREEN, RED, iter_chunks, iter_grid
from renderers.registry import renderer_for

STYLES = ("mesh", "frames", "skeleton")

# --- transfer and sampling ----------------------------------------------------------------------------------


@dataclass
class TransferResult:
    """A behaviour transfer (or flow samples) in display coordinates.

    Attributes:
        source: (1 + H, ...) the behaviour source x_beta (its start posture, then H frames), or None for
            flow samples.
        reenacted: (K, 1 + H, ...) the target's start posture followed by H generated frames, per
            behaviour (K = 1 for a source clip, N for flow samples).
        z: (K, Z) the behaviour representations used.
        fps: frame rate of both.
        layout: the model's feature layout (``body3d``, ``body2d`` or ``face``).
        source_name, target_name: the files (for labels).
        target_frame: the start frame in the target file's own frame numbering.
        source_identity, target_identity: face identities (faces only).
    """
    source: np.ndarray | None
    reenacted: np.ndarray
    z: np.ndarray
    fps: float
    layout: str
    source_name: str | None
    target_name: str
    target_frame: int
    source_identity: dict = field(default_factory=dict)
    target_identity: dict = field(default_factory=dict)


def _check_horizon(bundle: ModelBundle, horizon: int | None) -> int:
    horizon = bundle.data_config.future if horizon is None else int(horizon)
    if horizon < 1:
        raise InputError(f"the horizon must be >= 1 frame, got {horizon}")
    return horizon


def _target_start(bundle: ModelBundle, target: LoadedClip, target_frame: int
                  ) -> tuple[np.ndarray, W.WindowFrame | None]:
    start = model_frame(target, target_frame, what="--target-frame")
    return encode_sequences(bundle, target.data[None, start:start + 1])  # (1, 1, F)


def transfer_behavior(bundle: ModelBundle, source: LoadedClip, target: LoadedClip, *, source_start: int = 0,
                      target_frame: int = 0, horizon: int | None = None,
                      adapt_steps: int = ADAPT_STEPS) -> TransferResult:
    """Re-enact the behaviour of ``source`` (from its file frame ``source_start``, 1 + horizon frames) from
    the posture of ``target`` at file frame ``target_frame``. The decoder is first fitted for ``adapt_steps``
    steps to the source retargeted onto the target's posture and body
    (:func:`motion2video.stages.latents.reenact_source`; 0: the model as trained).

    Raises:
        InputError: not a behaviour model, a frame outside a clip, or a source too short for the horizon.
    """
    behavior_model(bundle)  # the wrong kind of model fails before the frames are checked
    horizon = _check_horizon(bundle, horizon)
    s = model_frame(source, source_start, what="--behavior-start")
    if s + 1 + horizon > source.num_frames:
        raise InputError(f"the behaviour source needs {1 + horizon} frames from frame {source_start} at "
                         f"{source.fps:g} fps, but only {source.num_frames - s} remain (shorten --horizon or "
                         f"start earlier)", source.path)
    start = model_frame(target, target_frame, what="--target-frame")
    z, reenacted, shown_source = reenact_source(bundle, source.data[s:s + 1 + horizon], target.data[start],
                                                adapt_steps=adapt_steps)
    return TransferResult(source=shown_source.astype(np.float32), reenacted=reenacted.astype(np.float32),
                          z=z, fps=bundle.data_config.fps, layout=bundle.data_config.layout,
                          source_name=source.path, target_name=target.path, target_frame=int(target_frame),
                          source_identity=source.identity, target_identity=target.identity)


def sample_behaviors(bundle: ModelBundle, target: LoadedClip, *, num_samples: int, target_frame: int = 0,
                     horizon: int | None = None, seed: int = 0) -> TransferResult:
    """``num_samples`` new behaviours z = T^-1(u), u ~ N(0, I) through the fitted normalizing flow, each
    enacted from the target's posture at file frame ``target_frame``. The same seed gives the same samples.

    Raises:
        InputError: not a behaviour model, a flow that was never fitted, num_samples < 1, a bad frame.
    """
    model = behavior_model(bundle)
    horizon = _check_horizon(bundle, horizon)
    if num_samples < 1:
        raise InputError(f"--sample must be >= 1, got {num_samples}")
    if not bool(model.flow_fitted):
        raise InputError("this behaviour checkpoint has no fitted normalizing flow to sample behaviours from "
                         "(train it with motion2video train, which fits the flow at the end)",
                         bundle.path or bundle.name)
    tgt_feats, tgt_frame = _target_start(bundle, target, target_frame)  # (1, 1, F)
    model.eval()
    gen = torch.Generator().manual_seed(int(seed))
    with torch.no_grad():
        u = torch.randn((num_samples, model.config.latent_dim), generator=gen)
        z = model.flow.inverse(u.to(next(model.parameters()).device))  # (K, Z)
        out = model.transfer(z, as_model_input(np.repeat(tgt_feats[:, 0], num_samples, axis=0), model), horizon)
    seq = np.concatenate([np.repeat(tgt_feats, num_samples, axis=0), out.cpu().numpy()], axis=1)  # (K, 1+H, F)
    reenacted = rigid_bones(bundle.data_config.layout, decode_sequences(bundle, seq[None], tgt_frame)[0])
    return TransferResult(source=None, reenacted=reenacted.astype(np.float32), z=z.cpu().numpy(),
                          fps=bundle.data_config.fps, layout=bundle.data_config.layout, source_name=None,
                          target_name=target.path, target_frame=int(target_frame),
                          target_identity=target.identity)


# --- the video's style (what the command asks; Python callers get the same defaults and checks) ----------------


def requested_style(style: str | None, reference: str | Path | None) -> str | None:
    """The style asked for, before the model is known: ``frames`` when only a reference image is given.

    Raises:
        InputError: a reference image with another style.
    """
    style = style or ("frames" if reference else None)
    if reference and style != "frames":
        raise InputError(f"--reference is only used with --style frames (got --style {style})", reference)
    return style


def style_for(layout: str, style: str | None) -> str:
    """The style for a model's layout: ``style``, by default ``mesh`` (``skeleton`` for 2D body models).

    Raises:
        InputError: ``mesh`` for a 2D body model.
    """
    style = style or ("skeleton" if layout == "body2d" else "mesh")
    if style == "mesh" and layout == "body2d":
        raise InputError("--style mesh needs a 3D body model; this model predicts 2D keypoints")
    return style


def frame_style_inputs(bundle: ModelBundle, *, frame_model: str | None = None, reference: str | Path | None = None,
                       reference_pose: str | Path | None = None, crop_person: bool = False):
    """The frame generator (default ``frames-<domain>-128`` for the model's domain) and the reference for
    ``style="frames"``.

    Returns:
        (loaded frame model, :class:`~motion2video.stages.reference.Reference` or None: the start posture rendered
        as an Anny body becomes the reference of a 3D body model).
    Raises:
        InputError: a frame generator of the other domain, or no reference for a model that cannot render one.
    """
    layout = bundle.data_config.layout
    frame_name = frame_model or f"frames-{DOMAIN_OF_LAYOUT[layout]}-128"
    loaded = load_frame_model(frame_name)
    domain = loaded.config.domain
    if domain != DOMAIN_OF_LAYOUT[layout]:
        raise InputError(f"this frame generator makes {domain} frames, but {bundle.label} moves a "
                         f"{DOMAIN_OF_LAYOUT[layout]}", frame_name)
    if reference:
        return loaded, load_reference(reference, size=loaded.config.image_size, domain=domain,
                                      pose_path=reference_pose, crop_person=crop_person,
                                      keep_framing=getattr(loaded, "kind", "analogy") in ("warp", "mesh"))
    if layout != "body3d":
        raise InputError("--style frames needs --reference for this model (only 3D body models can render "
                         "their own reference)")
    return loaded, None


# --- rendering ------------------------------------------------------------------------------------------


def _short(path: str | None) -> str:
    return Path(path).stem if path else "?"


def render_transfer(result: TransferResult, *, style: str = "mesh", size: int = 256,
                    frame_model=None, reference=None) -> np.ndarray:
    """The transfer video.

    Source clip: two cells side by side, ``source`` (framed green, the source's look) | the target's start
    posture (green) re-enacting the behaviour (red), with the target's look. Flow samples: a grid of the K
    re-enactments. ``style="frames"`` draws the re-enactments with the keypoint-conditioned frame generator
    ``frame_model`` from ``reference`` (see :func:`render_with_frame_model`); the source cell is then a
    skeleton.

    Returns:
        (1 + H, H', W', 3) uint8.
    """
    return np.concatenate(list(iter_transfer(result, style=style, size=size, frame_model=frame_model,
                                             reference=reference)))


def iter_transfer(result: TransferResult, *, style: str = "mesh", size: int = 256,
                  frame_model=None, reference=None) -> Iterator[np.ndarray]:
    """:func:`render_transfer` as a stream of (t, H', W', 3) uint8 chunks: every cell is drawn lazily as the
    grid consumes it (the frame generator's re-enactments, ``style="frames"``, are generated first)."""
    if style not in STYLES:
        raise InputError(f"unknown style {style!r}; choose one of {', '.join(STYLES)}")
    n = result.reenacted.shape[1]
    face_alt = result.layout == "face" and result.target_identity == result.source_identity
    target_identity = ALT_FACE_IDENTITY if face_alt else result.target_identity
    target_colours = ALT_FACE_COLOURS if face_alt else None
    cells = []
    if result.source is not None:
        src = iter_sequence(result.source, layout=result.layout, style="skeleton" if style == "frames" else style,
                            size=size, fps=result.fps, look=SOURCE_LOOK, identity=result.source_identity)
        cells.append(iter_mark_segments(src, [(n, GREEN, f"behaviour: {_short(result.source_name)}")]))
    if style == "frames":
        drawn = render_with_frame_model(result, frame_model, size=size, reference=reference)
    else:
        drawn = [iter_sequence(seq, layout=result.layout, style=style, size=size, fps=result.fps, look=TARGET_LOOK,
                               identity=target_identity, face_colours=target_colours) for seq in result.reenacted]
    for k, frames in enumerate(drawn):
        text = (f"{_short(result.target_name)} @{result.target_frame} re-enacts" if result.source is not None
                else f"flow behaviour {k + 1}")
        # A reference picture's person fills its frame: a jump's head reaches the top, where the label would hide it.
        corner = "bottom-left" if style == "frames" else "top-left"
        cells.append(iter_mark_segments(iter_chunks(frames), [(1, GREEN, text), (n - 1, RED, text)], corner=corner))
    return iter_grid(cells, None, 2 if result.source is not None else None)


def transfer_forecast(result: TransferResult):
    """The re-enactments as a :class:`motion2video.stages.sampling.Forecast`: the target's start posture is the one
    observed frame, each re-enactment a future (what the frame generator's structures are placed from)."""
    return Forecast(observed=result.reenacted[0, :1], futures=result.reenacted[:, 1:], fps=result.fps,
                    layout=result.layout, model="behavior", seed=0)


def render_with_frame_model(result: TransferResult, frame_model, *, size: int, reference=None) -> list[np.ndarray]:
    """Draw the re-enactments with the keypoint-conditioned frame generator, through the ``synthesize``
    pipeline's conventions (:mod:`motion2video.stages.structure`, :mod:`motion2video.stages.generation`): the target's start posture plays the observed
    frame, each re-enactment a future; bodies are turned to face the camera at the start posture, followed
    on the ground, and aligned to the reference image's pose (its ``.pose.npz`` when there is one, else the
    start posture as a single-frame render frames it).

    Args:
        frame_model: a loaded frame generator (:func:`motion2video.generator.checkpoint.load_frame_model`).
        reference: a :class:`motion2video.stages.reference.Reference` (:func:`motion2video.stages.reference.load_reference`),
            or None for 3D body models: the start posture rendered with the target's Anny look (and its
            exact pose) becomes the reference.
    Returns:
        K arrays (1 + H, size, size, 3) uint8.
    """
    if frame_model is None:
        raise InputError("--style frames needs a frame generator (--frame-model)")
    cfg = frame_model.model.config
    if DOMAIN_OF_LAYOUT[result.layout] != cfg.domain:
        raise InputError(f"the frame model makes {cfg.domain} frames, but the behaviour model moves a "
                         f"{DOMAIN_OF_LAYOUT[result.layout]}", getattr(frame_model, "path", None))
    s = cfg.image_size if reference is None else reference.image.shape[0]  # larger when its framing is kept
    fc = transfer_forecast(result)
    if reference is None:
        if result.layout != "body3d":
            raise InputError("--style frames needs --reference for this model (only 3D body models can render "
                             "their own reference)")
        reference = rendered_reference(fc, s)
    structures = render_structures(fc, domain=cfg.domain, size=s, reference=reference)
    generated = generate_video_frames(frame_model, reference, structures)
    out = []
    for future in generated.futures:  # (H, s, s, 3)
        frames = np.concatenate([generated.observed, future])
        if reference.view is not None:
            frames = cut_to_view(frames, reference.view, size)
        elif s != size:
            frames = np.stack([cv2.resize(f, (size, size), interpolation=cv2.INTER_LINEAR) for f in frames])
        out.append(frames)
    return out


def rendered_reference(fc, size: int):
    """A reference for the frame generator made from the start posture (``fc.observed[0]``): the target's Anny
    look rendered through the camera a single-frame placement uses, with that exact 2D pose."""
    placement = place_body(fc.observed, fc.futures, size=size)
    start = placement.world_observed[0]  # (17, 3) front-facing start posture
    camera = fit_camera(start, size, size, elevation_deg=BODY_ELEVATION_DEG, yfov_deg=BODY_YFOV_DEG,
                        margin=BODY_MARGIN)
    with renderer_for("body3d", "mesh", size=size, **TARGET_LOOK) as r:
        image = r.draw(start[None].astype(np.float32), fc.fps, camera=camera)[0]
    pose = ReferencePose("body", size, size, points=placement.reference)
    return Reference(image=image, pose=pose, notes=("no --reference: the target's start posture rendered as an "
                                                    "Anny body is the reference",), path=Path("(rendered)"))



# --- the command's work ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TransferSettings:
    """One ``transfer`` run: a behaviour re-enacted from a target's posture, drawn as a video.

    Attributes:
        model: a behaviour model's checkpoint path or shipped name.
        target: the clip whose posture re-enacts the behaviour; target_frame: its start frame (file frames).
        output: the video (.mp4 or .gif).
        behavior: the clip whose behaviour is transferred, or None with ``sample``.
        sample: draw this many new behaviours through the flow instead (None with ``behavior``).
        behavior_start: the source's first frame. horizon: generated frames (None: the model's).
        adapt_steps: steps fitting the decoder to the source first (None: :data:`ADAPT_STEPS`; ``behavior`` only).
        style: ``mesh``, ``frames`` or ``skeleton`` (None: :func:`requested_style` and :func:`style_for`).
        reference, reference_pose, crop_person, fit_view, frame_model: ``frames`` only: the target person's picture,
            its pose file, cutting it to its person, zooming it out to keep every body in view, the frame generator.
        seed: the flow samples' seed. size: cell width and height in pixels.
        npz: also write source, re-enactments and latents here, or None.
        character, input_fps, rig_map: how the clips are read (:func:`motion2video.stages.clips.load_clip`).
        bvh: also write each re-enactment as a BVH file into this folder, or None.
    """

    model: str | Path
    target: str | Path
    output: str | Path
    behavior: str | Path | None = None
    sample: int | None = None
    target_frame: int = 0
    behavior_start: int = 0
    horizon: int | None = None
    adapt_steps: int | None = None
    style: str | None = None
    reference: str | Path | None = None
    reference_pose: str | Path | None = None
    crop_person: bool = False
    fit_view: bool = False
    frame_model: str | Path | None = None
    seed: int = 0
    size: int = 256
    npz: str | Path | None = None
    character: str | Path | None = None
    input_fps: float | None = None
    rig_map: str | Path | None = None
    bvh: str | Path | None = None


@dataclass
class TransferFiles:
    """What :func:`transfer_to_files` wrote: the transfer, the style drawn, the video and its frame size, the npz
    (or None) and the BVH files (empty without a folder)."""

    result: TransferResult
    style: str
    video: Path
    width: int
    height: int
    npz: Path | None = None
    bvh: list[Path] = field(default_factory=list)


def transfer_to_files(settings: TransferSettings, *, note: Callable[[str], None] | None = None) -> TransferFiles:
    """Load the model and the clips, transfer (or sample) the behaviour and write the video (and the npz and BVH
    files asked for); ``note`` hears what the reference's framing changed. The outputs, the model's kind, the style
    and its options are checked before any clip is read (InputError)."""
    s = settings
    check_cell_size(s.size)
    out = check_video_and_npz(s.output, s.npz)
    if (s.behavior is None) == (s.sample is None):
        raise InputError("give a behaviour source (--behavior) or a number of flow samples (--sample), not both")
    if s.adapt_steps is not None:
        if s.adapt_steps < 0:
            raise InputError(f"--adapt-steps must be >= 0, got {s.adapt_steps}")
        if s.sample is not None:
            raise InputError("--adapt-steps fits the decoder to a --behavior source; --sample has none")
    style = requested_style(s.style, s.reference)
    if s.model in BASELINES:
        raise InputError(f"behaviour transfer needs a 'behavior' model; {s.model!r} is a baseline")
    bundle = load_model(s.model)
    check_bvh_output(s.bvh, bundle.data_config.layout)
    behavior_model(bundle)  # the wrong kind of model fails before any clip is read
    style = style_for(bundle.data_config.layout, style)
    frame_model = reference = None
    if style == "frames":
        frame_model, reference = frame_style_inputs(bundle, frame_model=s.frame_model, reference=s.reference,
                                                    reference_pose=s.reference_pose, crop_person=s.crop_person)
    elif s.reference_pose or s.frame_model or s.crop_person or s.fit_view:
        raise InputError("--frame-model, --reference-pose, --crop-person and --fit-view are only used with --style "
                         "frames")
    target = load_clip(bundle, s.target, character=s.character, fps=s.input_fps, rig_map=s.rig_map)
    if s.behavior is not None:
        source = load_clip(bundle, s.behavior, character=s.character, fps=s.input_fps,
                           rig_map=s.rig_map)
        result = transfer_behavior(bundle, source, target, source_start=s.behavior_start,
                                   target_frame=s.target_frame, horizon=s.horizon,
                                   adapt_steps=ADAPT_STEPS if s.adapt_steps is None else s.adapt_steps)
    else:
        result = sample_behaviors(bundle, target, num_samples=s.sample, target_frame=s.target_frame,
                                  horizon=s.horizon, seed=s.seed)
    if reference is not None:
        reference = reference_in_view(transfer_forecast(result), reference, size=reference.image.shape[0],
                                      fit_view=s.fit_view)
    chunks = iter_transfer(result, style=style, size=s.size, frame_model=frame_model, reference=reference)
    for line in (reference.notes if reference is not None and note is not None else ()):
        note(line)
    with VideoWriter(out, result.fps) as writer:
        for chunk in chunks:
            writer.write(chunk)
    files = TransferFiles(result, style, out, writer.width, writer.height)
    if s.npz:
        arrays = {"reenacted": result.reenacted, "z": result.z, "fps": np.float64(result.fps),
                  "layout": np.str_(result.layout), "model": np.str_(bundle.name),
                  "target_frame": np.int64(result.target_frame)}
        if result.source is not None:
            arrays["source"] = result.source
        files.npz = save_npz(s.npz, arrays)
    if s.bvh:
        files.bvh = write_bvh_files(s.bvh, "reenacted", result.reenacted, result.fps)
    return files
