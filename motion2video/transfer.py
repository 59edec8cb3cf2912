"""Behaviour transfer (Blattmann et al., CVPR 2021): the behaviour of one clip re-enacted from another
clip's posture, flow-sampled new behaviours, the side-by-side videos, and the paper's Table 1 / Table 3
protocol.

Pipeline (``motion2video transfer``):

1. ``SOURCE[s : s + 1 + H]`` (its first frame is the source's own start posture x_t) is encoded exactly
   like a training behaviour sequence: the window's canonical frame is taken at its FIRST frame (the same
   anchor the training windows use, whose behaviour sequence starts at the last observed frame), then the
   checkpoint's normalisation. The behaviour encoder's posterior mean is z_beta (:func:`behavior_latents`).
2. ``TARGET[F]`` is encoded the same way (a one-frame sequence, anchored at itself); the decoder enacts
   z_beta from it for H frames (:meth:`BehaviorModel.transfer`).
3. The H generated frames are decoded back with the TARGET's window frame.

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

Protocol (:func:`evaluate_transfer`, for ``scripts/make_results_transfer.py``): on held-out windows, each
source behaviour x_beta is re-enacted from the start posture of a window of a DIFFERENT clip:
- TDE(T): mean squared error between re-enactment x_R and source x_beta at frame T (root-relative joints,
  cm^2 per coordinate); a copying model drives it to 0, a model ignoring z keeps it large;
- d_beta: Euclidean distance between z(x_beta) and z(x_R) (re-encoding the re-enactment from its own start);
- RE(T): mean squared error of a ridge regression from z(x_beta) to the posture x_beta[T] (fitted on
  training windows), i.e. how much posture the representation carries;
- realism (Table 3): accuracy of a real/fake classifier (:func:`motion2video.metrics.quality`) between
  held-out ground-truth sequences and reconstructions ("self"), transfers, prior samples and flow samples.
MT-VAE enters through analogy: z = E(obs_source, future_source), x_R = D(obs_target, z).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from motion2video import metrics as M
from motion2video.checkpoint import ModelBundle
from motion2video.core.rotations import heading_of
from motion2video.data import windows as W
from motion2video.data.dataset import WindowSet, decode_samples
from motion2video.errors import InputError
from motion2video.models.behavior import BehaviorModel
from motion2video.motion import FaceMotion, Motion
from motion2video.video import GREEN, RED, add_border, grid, label

STYLES = ("mesh", "frames", "skeleton")
TABLE1_TIMESTEPS = (1, 10, 20, 30, 40)
CM2 = 1.0e4  # m^2 -> cm^2

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


# --- loading --------------------------------------------------------------------------------------------


@dataclass
class LoadedClip:
    """A user clip at the model's frame rate.

    Attributes:
        data: (T, 17, 3) world joints (body models) or (T, 58) face parameters (face models), float32.
        fps: the model's frame rate (the rate of ``data``).
        source_fps: the file's own rate; source_frames: its number of frames.
        path: the file.
        identity: the face identity recorded in the file (empty for bodies and plain captures).
    """

    data: np.ndarray
    fps: float
    source_fps: float
    source_frames: int
    path: str
    identity: dict = field(default_factory=dict)

    @property
    def num_frames(self) -> int:
        return int(self.data.shape[0])


def load_clip(bundle: ModelBundle, path: str | Path) -> LoadedClip:
    """Read ``path`` for ``bundle``'s model: body models take 3D h36m-17 motion (BVH of any rig, motion
    npz, ...), face models take face captures; the clip is resampled to the model's rate.

    Raises:
        InputError: missing or malformed file, body motion for a face model or the reverse, a body clip of
        another skeleton or 2D joints.
    """
    from motion2video.io import load_motion

    cfg = bundle.data_config
    motion = load_motion(path)
    if cfg.layout == "face":
        if not isinstance(motion, FaceMotion):
            raise InputError(f"{bundle.name} is a face model, but this file holds body motion", path)
        data, identity = motion.params, dict(motion.identity)
    else:
        if isinstance(motion, FaceMotion):
            raise InputError(f"{bundle.name} is a body model, but this file holds face motion", path)
        if not isinstance(motion, Motion) or motion.skeleton != "h36m-17" or motion.dim != 3:
            raise InputError(f"body models need 3D h36m-17 joints (BVH, motion npz, ...), got skeleton "
                             f"{motion.skeleton} with D={motion.dim}", path)
        data, identity = motion.joints, {}
    resampled = W.resample(data, motion.fps, cfg.fps).astype(np.float32)
    if cfg.layout == "face":
        resampled[:, :52] = np.clip(resampled[:, :52], 0.0, 1.0)
    return LoadedClip(data=resampled, fps=cfg.fps, source_fps=float(motion.fps),
                      source_frames=int(data.shape[0]), path=str(path), identity=identity)


def model_frame(clip: LoadedClip, index: int, *, what: str) -> int:
    """Frame ``index`` of the file -> the nearest frame of the resampled clip; InputError when outside."""
    if not 0 <= index < clip.source_frames:
        raise InputError(f"{what} {index} is outside the clip (frames 0..{clip.source_frames - 1} at "
                         f"{clip.source_fps:g} fps)", clip.path)
    return min(int(np.floor(index * clip.fps / clip.source_fps + 0.5)), clip.num_frames - 1)  # half up


# --- features -------------------------------------------------------------------------------------------


def encode_sequences(bundle: ModelBundle, sequences: np.ndarray) -> tuple[np.ndarray, W.WindowFrame | None]:
    """Behaviour sequences -> normalised features, each anchored at its FIRST frame.

    Args:
        sequences: (N, T, 17, 3) world joints or (N, T, 58) face parameters, at the model's rate.
    Returns:
        (N, T, F) float32 normalised features and the window frames (None for faces).
    """
    cfg = bundle.data_config
    layout = cfg.feature_layout
    if layout.kind == "face":
        return bundle.stats.normalize(np.asarray(sequences, np.float64)), None
    raw, frame = W.body_window_features(np.asarray(sequences), layout=layout, anchor=0,
                                        canonical_heading=cfg.canonical_heading)
    return bundle.stats.normalize(raw), frame


def decode_sequences(bundle: ModelBundle, features: np.ndarray, frame: W.WindowFrame | None) -> np.ndarray:
    """Normalised features (N, K, T, F) -> display coordinates: (N, K, T, 17, 3) world joints, (N, K, T,
    17, 2) virtual-camera pixels (body2d) or (N, K, T, 58) face parameters."""
    return decode_samples(features, config=bundle.data_config, stats=bundle.stats, frame=frame)


def _tensor(x: np.ndarray, model: torch.nn.Module) -> torch.Tensor:
    device = next(model.parameters()).device
    return torch.from_numpy(np.ascontiguousarray(x, np.float32)).to(device)


def behavior_model(bundle: ModelBundle) -> BehaviorModel:
    """The bundle's model when it is a behaviour model; InputError otherwise."""
    if not isinstance(bundle.model, BehaviorModel):
        raise InputError(f"behaviour transfer needs a 'behavior' model (behaviour encoder + posture-conditioned "
                         f"decoder), but this checkpoint is a {bundle.name!r} model", bundle.path or bundle.name)
    return bundle.model


@torch.no_grad()
def behavior_latents(model: BehaviorModel, features: np.ndarray) -> np.ndarray:
    """Posterior means z_beta of normalised behaviour sequences (N, T, F) -> (N, Z) float32."""
    model.eval()
    return model.behavior_latent(_tensor(features, model)).cpu().numpy()


@torch.no_grad()
def reenact(model: BehaviorModel, z: np.ndarray, start: np.ndarray, *, horizon: int) -> np.ndarray:
    """Enact behaviours z (N, Z) from normalised start postures (N, F): (N, horizon, F) float32."""
    model.eval()
    return model.transfer(_tensor(z, model), _tensor(start, model), horizon).cpu().numpy()


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
                      target_frame: int = 0, horizon: int | None = None) -> TransferResult:
    """Re-enact the behaviour of ``source`` (from its file frame ``source_start``, 1 + horizon frames) from
    the posture of ``target`` at file frame ``target_frame``.

    Raises:
        InputError: not a behaviour model, a frame outside a clip, or a source too short for the horizon.
    """
    model = behavior_model(bundle)
    horizon = _check_horizon(bundle, horizon)
    s = model_frame(source, source_start, what="--behavior-start")
    if s + 1 + horizon > source.num_frames:
        raise InputError(f"the behaviour source needs {1 + horizon} frames from frame {source_start} at "
                         f"{source.fps:g} fps, but only {source.num_frames - s} remain (shorten --horizon or "
                         f"start earlier)", source.path)
    src_feats, src_frame = encode_sequences(bundle, source.data[None, s:s + 1 + horizon])  # (1, 1+H, F)
    tgt_feats, tgt_frame = _target_start(bundle, target, target_frame)  # (1, 1, F)
    z = behavior_latents(model, src_feats)  # (1, Z)
    gen = reenact(model, z, tgt_feats[:, 0], horizon=horizon)  # (1, H, F)
    seq = np.concatenate([tgt_feats, gen], axis=1)  # (1, 1+H, F)
    reenacted = decode_sequences(bundle, seq[:, None], tgt_frame)[0]  # (1, 1+H, ...)
    shown_source = decode_sequences(bundle, src_feats[:, None], src_frame)[0, 0]  # (1+H, ...)
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
        out = model.transfer(z, _tensor(np.repeat(tgt_feats[:, 0], num_samples, axis=0), model), horizon)
    seq = np.concatenate([np.repeat(tgt_feats, num_samples, axis=0), out.cpu().numpy()], axis=1)  # (K, 1+H, F)
    reenacted = decode_sequences(bundle, seq[None], tgt_frame)[0]  # (K, 1+H, ...)
    return TransferResult(source=None, reenacted=reenacted.astype(np.float32), z=z.cpu().numpy(),
                          fps=bundle.data_config.fps, layout=bundle.data_config.layout, source_name=None,
                          target_name=target.path, target_frame=int(target_frame),
                          target_identity=target.identity)


# --- rendering ------------------------------------------------------------------------------------------


def body_style(look: dict, size: int):
    """A :class:`renderers.body.BodyStyle` of ``size`` x ``size`` pixels with ``look``'s phenotype and colours."""
    from renderers.body import BodyStyle

    return BodyStyle(size=(size, size), **look)


def render_sequence(seq: np.ndarray, *, layout: str, style: str, size: int, fps: float,
                    look: dict | None = None, identity: dict | None = None,
                    face_colours: dict | None = None) -> np.ndarray:
    """Draw one sequence with its own fixed camera, fitted over the whole sequence; 3D bodies are seen from
    the front of their FIRST frame (camera azimuth = the start heading), so every cell shows its person's
    start posture from the front and the motion relative to it.

    Args:
        seq: (T, 17, 3) world joints, (T, 17, 2) pixels (body2d) or (T, 58) face parameters.
        layout: ``body3d``, ``body2d`` or ``face``.
        style: ``skeleton`` or ``mesh`` (body3d); faces are always drawn with the Anny face renderer.
        look: BodyStyle fields (phenotype, colours) for ``mesh``.
        identity, face_colours: the face's Anny identity and FaceStyle colours.
    Returns:
        (T, size, size, 3) uint8.
    """
    if layout == "face":
        from renderers.face import FaceRenderer, FaceStyle

        with FaceRenderer(FaceStyle(size=(size, size), **(face_colours or {}))) as r:
            return r.render(FaceMotion(seq, fps, dict(identity or {})))
    azimuth = float(np.degrees(heading_of(seq[0]))) if layout == "body3d" else 0.0
    if style == "mesh":
        if layout != "body3d":
            raise InputError("--style mesh needs a 3D body model; this model predicts 2D keypoints")
        from renderers.body import BodyRenderer

        with BodyRenderer(body_style({**(look or {}), "azimuth_deg": azimuth}, size)) as r:
            return r.render(Motion(seq, fps))
    if style != "skeleton":
        raise InputError(f"unknown style {style!r}; choose one of {', '.join(STYLES)}")
    from motion2video.core.camera import fit_camera
    from renderers.skeleton import SkeletonRenderer, SkeletonStyle

    camera = fit_camera(seq.reshape(-1, 3), size, size, azimuth_deg=azimuth) if layout == "body3d" else None
    with SkeletonRenderer(style=SkeletonStyle(size=(size, size))) as r:
        return r.render(seq, camera=camera)


def mark_segments(frames: np.ndarray, segments: list[tuple[int, tuple[int, int, int], str]], *,
                  border: int = 4) -> np.ndarray:
    """Frame consecutive segments of a clip with their own border colour and label.

    Args:
        frames: (T, H, W, 3) uint8.
        segments: (number of frames, RGB border colour, text) per segment; the counts must sum to T.
    """
    if sum(n for n, _, _ in segments) != frames.shape[0]:
        raise ValueError(f"segments cover {sum(n for n, _, _ in segments)} frames, the clip has {frames.shape[0]}")
    parts, start = [], 0
    for n, colour, text in segments:
        part = add_border(frames[start:start + n], colour, border)
        parts.append(label(part, text, inset=border))
        start += n
    return np.concatenate(parts, axis=0)


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
    if style not in STYLES:
        raise InputError(f"unknown style {style!r}; choose one of {', '.join(STYLES)}")
    n = result.reenacted.shape[1]
    face_alt = result.layout == "face" and result.target_identity == result.source_identity
    target_identity = ALT_FACE_IDENTITY if face_alt else result.target_identity
    target_colours = ALT_FACE_COLOURS if face_alt else None
    cells = []
    if result.source is not None:
        src = render_sequence(result.source, layout=result.layout, style="skeleton" if style == "frames" else style,
                              size=size, fps=result.fps, look=SOURCE_LOOK, identity=result.source_identity)
        cells.append(mark_segments(src, [(n, GREEN, f"behaviour: {_short(result.source_name)}")]))
    if style == "frames":
        drawn = render_with_frame_model(result, frame_model, size=size, reference=reference)
    else:
        drawn = [render_sequence(seq, layout=result.layout, style=style, size=size, fps=result.fps, look=TARGET_LOOK,
                                 identity=target_identity, face_colours=target_colours) for seq in result.reenacted]
    for k, frames in enumerate(drawn):
        text = (f"{_short(result.target_name)} @{result.target_frame} re-enacts" if result.source is not None
                else f"flow behaviour {k + 1}")
        cells.append(mark_segments(frames, [(1, GREEN, text), (n - 1, RED, text)]))
    return grid(cells, None, 2 if result.source is not None else None)


def render_with_frame_model(result: TransferResult, frame_model, *, size: int, reference=None) -> list[np.ndarray]:
    """Draw the re-enactments with the keypoint-conditioned frame generator, through the ``synthesize``
    pipeline's conventions (:mod:`motion2video.pipeline`): the target's start posture plays the observed
    frame, each re-enactment a future; bodies are turned to face the camera at the start posture, followed
    on the ground, and aligned to the reference image's pose (its ``.pose.npz`` when there is one, else the
    start posture as a single-frame render frames it).

    Args:
        frame_model: a loaded frame generator (:func:`motion2video.frames.checkpoint.load_frame_model`).
        reference: a :class:`motion2video.reference.Reference` (:func:`motion2video.reference.load_reference`),
            or None for 3D body models: the start posture rendered with the target's Anny look (and its
            exact pose) becomes the reference.
    Returns:
        K arrays (1 + H, size, size, 3) uint8.
    """
    import cv2

    from motion2video.forecast import Forecast
    from motion2video.pipeline import DOMAIN_OF_LAYOUT, generate_video_frames, render_structures

    if frame_model is None:
        raise InputError("--style frames needs a frame generator (--frame-model)")
    cfg = frame_model.model.config
    if DOMAIN_OF_LAYOUT[result.layout] != cfg.domain:
        raise InputError(f"the frame model makes {cfg.domain} frames, but the behaviour model moves a "
                         f"{DOMAIN_OF_LAYOUT[result.layout]}", getattr(frame_model, "path", None))
    s = cfg.image_size
    fc = Forecast(observed=result.reenacted[0, :1], futures=result.reenacted[:, 1:], fps=result.fps,
                  layout=result.layout, model="behavior", seed=0)
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
        if s != size:
            frames = np.stack([cv2.resize(f, (size, size), interpolation=cv2.INTER_LINEAR) for f in frames])
        out.append(frames)
    return out


def rendered_reference(fc, size: int):
    """A reference for the frame generator made from the start posture (``fc.observed[0]``): the target's Anny
    look rendered through the camera a single-frame placement uses, with that exact 2D pose."""
    from motion2video.pipeline import BODY_ELEVATION_DEG, BODY_MARGIN, BODY_YFOV_DEG, place_body
    from motion2video.reference import Reference, ReferencePose
    from renderers.body import BodyRenderer
    from motion2video.core.camera import fit_camera

    placement = place_body(fc.observed, fc.futures, size=size)
    start = placement.world_observed[0]  # (17, 3) front-facing start posture
    camera = fit_camera(start, size, size, elevation_deg=BODY_ELEVATION_DEG, yfov_deg=BODY_YFOV_DEG,
                        margin=BODY_MARGIN)
    with BodyRenderer(body_style(TARGET_LOOK, size)) as r:
        image = r.render(Motion(start[None].astype(np.float32), fc.fps), camera=camera)[0]
    pose = ReferencePose("body", size, size, points=placement.reference)
    return Reference(image=image, pose=pose, notes=("no --reference: the target's start posture rendered as an "
                                                    "Anny body is the reference",), path=Path("(rendered)"))


# --- the Table 1 / Table 3 protocol -------------------------------------------------------------------------


def transfer_pairs(clip_names: tuple[str, ...], *, seed: int) -> np.ndarray:
    """For each window, the index of a target window from a DIFFERENT clip (uniform, seeded): (N,) int.

    Raises ValueError when all windows come from one clip.
    """
    names = np.asarray(clip_names)
    if len(set(names.tolist())) < 2:
        raise ValueError("behaviour transfer pairs need windows from at least two clips")
    rng = np.random.default_rng(seed)
    out = np.empty(len(names), np.int64)
    for i, name in enumerate(names):
        others = np.flatnonzero(names != name)
        out[i] = others[rng.integers(len(others))]
    return out


@dataclass
class TransferScores:
    """Table 1 and Table 3 numbers of one model.

    Attributes:
        tde: T -> transfer displacement error (cm^2 per coordinate, root-relative joints).
        re: T -> posture-regression error from z (cm^2 per coordinate), held-out windows.
        tde_se, re_se: T -> standard error of those means over the windows.
        d_beta: mean and standard deviation of ||z(x_beta) - z(x_R)||.
        d_random: the same between z(x_beta) and the behaviour of the target window the posture came from
            (an unrelated behaviour): the scale d_beta is read against (d_beta / d_random < 1 when the
            re-enactment kept the source's behaviour better than an unrelated clip's).
        realism: origin (``self``, ``transfer``, ``prior``, ``flow``) -> real/fake classifier accuracy
            (0.5 = indistinguishable from real, 1 = always told apart) on :func:`metrics.sequence_descriptor`
            (poses, mean absolute velocity and acceleration, standard deviations).
        realism_poses: the same classifier on poses alone (:func:`pose_descriptor`).
        motion: ``real`` and every origin -> (mean |velocity|, mean |acceleration|) of the feature vector per
            frame (metres per frame, per frame^2): how lively the motion is.
        windows: number of held-out windows.
    """

    tde: dict[int, float]
    re: dict[int, float]
    tde_se: dict[int, float]
    re_se: dict[int, float]
    d_beta: M.MeanStd
    d_random: M.MeanStd
    realism: dict[str, float]
    realism_poses: dict[str, float]
    motion: dict[str, tuple[float, float]]
    windows: int

    def to_json(self) -> dict:
        return {"tde_cm2": self.tde, "re_cm2": self.re, "tde_se_cm2": self.tde_se, "re_se_cm2": self.re_se,
                "d_beta": dataclasses.asdict(self.d_beta),
                "d_random": dataclasses.asdict(self.d_random), "realism_accuracy": self.realism,
                "realism_accuracy_poses": self.realism_poses, "motion_per_frame": self.motion,
                "windows": self.windows}


def pose_descriptor(seq: np.ndarray) -> np.ndarray:
    """Poses only: every 4th frame of (N, T, F) sequences, flattened -> (N, ceil(T / 4) * F)."""
    s = np.asarray(seq, np.float64)
    return s[:, ::4].reshape(len(s), -1)


def classifier_accuracy(real: np.ndarray, fake: np.ndarray, *, l2: float = 1.0) -> float:
    """Test accuracy of a ridge real/fake classifier on descriptors (N, P) and (M, P); even items train, odd
    items test (as :func:`motion2video.metrics.quality`, on any descriptor)."""
    x = np.concatenate([real, fake])
    y = np.concatenate([np.ones(len(real), np.int64), np.zeros(len(fake), np.int64)])
    train = np.concatenate([np.arange(len(real)) % 2 == 0, np.arange(len(fake)) % 2 == 0])
    clf = M.fit_ridge_classifier(x[train], y[train], l2=l2)
    return float(np.mean(clf.predict(x[~train]) == y[~train]))


def motion_liveliness(seq: np.ndarray) -> tuple[float, float]:
    """(mean |velocity|, mean |acceleration|) over every feature of (N, T, F) sequences, per frame."""
    s = np.asarray(seq, np.float64)
    return float(np.abs(np.diff(s, 1, axis=1)).mean()), float(np.abs(np.diff(s, 2, axis=1)).mean())


def _posture(bundle: ModelBundle, features: np.ndarray) -> np.ndarray:
    """Normalised features (..., F) -> root-relative posture vectors (..., M), metres."""
    return W.metric_vectors(bundle.stats.denormalize(features), bundle.layout)


def regression_errors(z_train: np.ndarray, posture_train: np.ndarray, z_test: np.ndarray,
                      posture_test: np.ndarray, *, l2: float = 1.0) -> np.ndarray:
    """Per test item, the mean squared error (per coordinate) of a ridge regression z -> posture fitted on the
    training pairs (standardised z, closed form). z: (N, Z); posture: (N, M). Returns (N_test,)."""
    zt, zs = np.asarray(z_train, np.float64), np.asarray(z_test, np.float64)
    mean, scale = zt.mean(0), zt.std(0) + 1e-8
    a = np.concatenate([(zt - mean) / scale, np.ones((len(zt), 1))], axis=1)  # (N, Z + 1)
    reg = l2 * np.eye(a.shape[1])
    reg[-1, -1] = 0.0
    w = np.linalg.solve(a.T @ a + reg, a.T @ np.asarray(posture_train, np.float64))  # (Z + 1, M)
    pred = np.concatenate([(zs - mean) / scale, np.ones((len(zs), 1))], axis=1) @ w
    return ((pred - posture_test) ** 2).mean(axis=1)


def regression_error(z_train: np.ndarray, posture_train: np.ndarray, z_test: np.ndarray,
                     posture_test: np.ndarray, *, l2: float = 1.0) -> float:
    """RE: the mean of :func:`regression_errors` over the test items."""
    return float(regression_errors(z_train, posture_train, z_test, posture_test, l2=l2).mean())


def _mean_se(x: np.ndarray) -> tuple[float, float]:
    """Mean and standard error of the mean of (N,) values."""
    x = np.asarray(x, np.float64)
    return float(x.mean()), float(x.std(ddof=1) / np.sqrt(len(x))) if len(x) > 1 else 0.0


@torch.no_grad()
def _latents_and_transfers(bundle: ModelBundle, obs: np.ndarray, fut: np.ndarray, target_obs: np.ndarray,
                           *, batch: int = 256) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """z(x_beta), the self-reconstruction, the transfer x_R and z(x_R), batched.

    Behaviour models: z from [x_t, x_beta] and re-enactment from the target's last observed posture;
    other latent models (MT-VAE analogy): z = E(obs, future) and x_R = D(target obs, z).
    """
    model = bundle.model
    model.eval()
    horizon = fut.shape[1]
    zs, selfs, trans, zr = [], [], [], []
    for i in range(0, len(obs), batch):
        o, f, t = (_tensor(x[i:i + batch], model) for x in (obs, fut, target_obs))
        z = model.encode(o, f).mu
        rec = model.decode(o, z, horizon=horizon)
        x_r = model.decode(t, z, horizon=horizon)
        z_r = model.encode(t, x_r).mu
        for acc, v in ((zs, z), (selfs, rec), (trans, x_r), (zr, z_r)):
            acc.append(v.cpu().numpy())
    return tuple(np.concatenate(a) for a in (zs, selfs, trans, zr))


def evaluate_transfer(bundle: ModelBundle, test: WindowSet, train: WindowSet, *, pairs: np.ndarray,
                      timesteps: tuple[int, ...] = TABLE1_TIMESTEPS, seed: int = 0) -> TransferScores:
    """The behaviour-transfer protocol (module docstring) for one latent model on held-out windows.

    Args:
        bundle: a ``behavior`` model (z from the behaviour sequence, re-enacted from a posture) or another
            latent model with ``encode`` / ``decode`` (MT-VAE: analogy from the target's observed window).
        test: held-out windows; train: training windows (fit the RE regressor).
        pairs: (N,) target window per test window (:func:`transfer_pairs`).
        timesteps: 1-based frames of the generated future at which TDE and RE are measured.
        seed: seeds the prior / flow samples.
    """
    if not (hasattr(bundle.model, "encode") and hasattr(bundle.model, "decode")):
        raise InputError(f"{bundle.name!r} has no latent space (encode / decode) to transfer with")
    to = test.observed
    horizon = test.features.shape[1] - to
    if max(timesteps) > horizon:
        raise ValueError(f"timestep {max(timesteps)} is beyond the {horizon}-frame future")
    idx = np.asarray(timesteps) - 1
    obs, fut = test.obs, test.future
    z, rec, x_r, z_r = _latents_and_transfers(bundle, obs, fut, obs[pairs])
    gt = _posture(bundle, fut)  # (N, Tf, M)
    pred = _posture(bundle, x_r)
    tde = M.transfer_displacement_error(pred, gt, timesteps=idx) * CM2
    tde_se = {t: _mean_se(((pred[:, t - 1] - gt[:, t - 1]) ** 2).mean(axis=1) * CM2)[1] for t in timesteps}
    z_train = _latents_and_transfers(bundle, train.obs, train.future, train.obs)[0]
    gt_train = _posture(bundle, train.future)
    re_stats = {t: _mean_se(regression_errors(z_train, gt_train[:, t - 1], z, gt[:, t - 1]) * CM2) for t in timesteps}
    real = bundle.stats.denormalize(fut)  # (N, Tf, F) whole features: pose and root trajectory
    fakes = {"self": rec, "transfer": x_r}
    gen = torch.Generator().manual_seed(int(seed))
    model = bundle.model
    with torch.no_grad():
        o = _tensor(obs, model)
        if isinstance(model, BehaviorModel):
            fakes["prior"] = model.sample(o, num_samples=1, horizon=horizon, generator=gen,
                                          use_flow=False)[:, 0].cpu().numpy()
            if bool(model.flow_fitted):
                fakes["flow"] = model.sample(o, num_samples=1, horizon=horizon, generator=gen,
                                             use_flow=True)[:, 0].cpu().numpy()
        else:
            fakes["prior"] = model.sample(o, num_samples=1, horizon=horizon, generator=gen)[:, 0].cpu().numpy()
    fakes = {k: bundle.stats.denormalize(v) for k, v in fakes.items()}
    realism = {k: M.quality(real, v) for k, v in fakes.items()}
    realism_poses = {k: classifier_accuracy(pose_descriptor(real), pose_descriptor(v)) for k, v in fakes.items()}
    motion = {"real": motion_liveliness(real), **{k: motion_liveliness(v) for k, v in fakes.items()}}
    return TransferScores(tde={t: float(v) for t, v in zip(timesteps, tde)},
                          re={t: m for t, (m, _) in re_stats.items()}, tde_se=tde_se,
                          re_se={t: se for t, (_, se) in re_stats.items()},
                          d_beta=M.latent_distance(z, z_r), d_random=M.latent_distance(z, z[pairs]),
                          realism=realism, realism_poses=realism_poses, motion=motion, windows=len(obs))
