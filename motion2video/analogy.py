"""Analogy-based motion transfer (MT-VAE, Yan et al. ECCV 2018, Sec. 4.2): A is to B as C is to D.

Given a window A (``observed`` frames), the window B that follows it (``horizon`` frames) and another
window C, the transformation latent is the posterior MEAN of the transition A -> B, z = E(A, B) (the paper
sets the encoder's sigma to zero for analogies), and D = decode(C, z, horizon): C's future under A -> B's
transformation. Works for any latent model with ``encode`` / ``decode`` (mtvae-add, mtvae-concat, cvae,
lcpvae, behavior), on body (3D or 2D layout) and face motion.

A and B from one file at consecutive frames are encoded as the one window they are. When B comes from
another file (or a non-adjacent part of the same one) it is first placed after A (:func:`stitch_after`):
rotated about the vertical so its first frame has A's last heading and translated so its root continues
A's last root step; face parameters are simply concatenated (head pose is absolute).

Known answer (:func:`procedural_analogy_case`, :func:`known_answer_labels`): A -> B is a procedural clip
in which mode X turns into mode Y at B's first frame; C is another instance of X (another speed range and
body height); the nearest-template mode classifier of :mod:`motion2video.data.multimodal` labels D.
:func:`procedural_transition_dataset` is the matching training data (the multimodal benchmark's
context -> future transitions).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Iterator

import numpy as np
import torch

from motion2video.checkpoint import ModelBundle
from motion2video.data import windows as W
from motion2video.data.dataset import (
    MULTIMODAL_SOURCE,
    DatasetConfig,
    MotionDataset,
    build_dataset,
    encode_windows,
    multimodal_clips,
)
from motion2video.data.multimodal import MultimodalBenchmark, default_classifier
from motion2video.data.procedural import BodyParams, ModeSpec, generate
from motion2video.errors import InputError
from motion2video.transfer import (
    ALT_FACE_COLOURS,
    ALT_FACE_IDENTITY,
    SOURCE_LOOK,
    TARGET_LOOK,
    LoadedClip,
    decode_sequences,
    iter_mark_segments,
    iter_sequence,
    model_frame,
)
from motion2video.video import GREEN, RED, iter_grid

STYLES = ("skeleton", "mesh")


def analogy_model(bundle: ModelBundle) -> torch.nn.Module:
    """The bundle's model when it has a latent transformation space (encode + decode); InputError otherwise."""
    model = bundle.model
    if bundle.kind in ("deterministic", "baseline") or not (hasattr(model, "encode") and hasattr(model, "decode")):
        raise InputError(f"analogy needs a latent-variable model with a transformation encoder (mtvae-add, "
                         f"mtvae-concat, cvae, lcpvae, behavior), but {bundle.name!r} is a {bundle.kind} model "
                         "without one", bundle.path or bundle.name)
    return model


def stitch_after(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Place body window ``b`` right after window ``a``.

    Args:
        a: (To >= 2, 17, 3) world joints; b: (Tf, 17, 3) world joints (anywhere, any heading).
    Returns:
        (Tf, 17, 3) float64: ``b`` rotated about z so its first frame's heading is ``a``'s last, and moved so
        its first root continues ``a``'s last root step (heights unchanged).
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    frame_a = W.canonical_frame(a[None], anchor=a.shape[0] - 1)
    frame_b = W.canonical_frame(b[None], anchor=0)
    placed = W.from_canonical(W.to_canonical(b[None], frame_b), frame_a)[0]  # b[0]'s root on a[-1]'s root
    placed[..., :2] += a[-1, 0, :2] - a[-2, 0, :2]
    return placed


def _window_config(bundle: ModelBundle, observed: int) -> DatasetConfig:
    if observed < 2:
        raise InputError(f"--observed must be >= 2 frames, got {observed}")
    return dataclasses.replace(bundle.data_config, observed=int(observed))


@torch.no_grad()
def analogy_windows(bundle: ModelBundle, ab: np.ndarray, c: np.ndarray, *, observed: int,
                    horizon: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Batched analogy on raw windows.

    Args:
        ab: (N, observed + Tf, 17, 3) world joints or (N, observed + Tf, 58) face parameters: A then B.
        c: (N, observed, ...) the C windows.
        horizon: frames of D.
    Returns:
        z (N, Z) posterior means of A -> B; D (N, horizon, ...) in C's coordinates; A -> B and C -> D in
        display coordinates, (N, observed + Tf, ...) and (N, observed + horizon, ...).
    """
    model = analogy_model(bundle)
    model.eval()
    cfg = _window_config(bundle, observed)
    raw_ab, frame_ab = encode_windows(np.asarray(ab), config=cfg)  # anchored at A's last frame
    raw_c, frame_c = encode_windows(np.asarray(c), config=cfg)  # anchored at C's last frame
    f_ab, f_c = bundle.stats.normalize(raw_ab), bundle.stats.normalize(raw_c)
    device = next(model.parameters()).device
    t_ab, t_c = torch.from_numpy(f_ab).to(device), torch.from_numpy(f_c).to(device)
    z = model.encode(t_ab[:, :observed], t_ab[:, observed:]).mu  # (N, Z)
    d = model.decode(t_c, z, horizon=horizon).cpu().numpy()  # (N, H, F)
    cd = np.concatenate([f_c, d], axis=1)  # (N, To + H, F)
    shown_ab = decode_sequences(bundle, f_ab[:, None], frame_ab)[:, 0]
    shown_cd = decode_sequences(bundle, cd[:, None], frame_c)[:, 0]
    return z.cpu().numpy(), shown_cd[:, observed:], shown_ab, shown_cd


@dataclass
class AnalogyResult:
    """A : B :: C : D, in display coordinates.

    Attributes:
        ab: (observed + horizon, ...) A's window then B's (placed after A when not consecutive).
        cd: (observed + horizon, ...) C's window then the generated D.
        observed: frames of A and C.
        z: (Z,) the transformation latent (posterior mean of A -> B).
        fps: frame rate; layout: the model's feature layout.
        names: the A, B, C files; consecutive: whether A and B were one window of one file.
        a_identity, c_identity: face identities of A and C (faces only).
    """

    ab: np.ndarray
    cd: np.ndarray
    observed: int
    z: np.ndarray
    fps: float
    layout: str
    names: tuple[str, str, str]
    consecutive: bool
    a_identity: dict = field(default_factory=dict)
    c_identity: dict = field(default_factory=dict)


def _window(clip: LoadedClip, start: int, length: int, *, what: str) -> np.ndarray:
    s = model_frame(clip, start, what=what)
    if s + length > clip.num_frames:
        raise InputError(f"{what} {start} leaves {clip.num_frames - s} frames at {clip.fps:g} fps, but the window "
                         f"needs {length}", clip.path)
    return clip.data[s:s + length]


def analogy(bundle: ModelBundle, a: LoadedClip, b: LoadedClip, c: LoadedClip, *, a_start: int = 0,
            b_start: int | None = None, c_start: int = 0, observed: int | None = None,
            horizon: int | None = None) -> AnalogyResult:
    """D = decode(C, E(A, B)) for user clips (frame starts in each file's own numbering).

    Args:
        a, b, c: clips loaded for the model (:func:`motion2video.transfer.load_clip`).
        a_start, c_start: first frame of A's and C's windows.
        b_start: first frame of B's window; None: right after A's window when B is A's file, else 0.
        observed: frames of A and C (default: the model's).
        horizon: frames of B and D (default: the model's).
    """
    analogy_model(bundle)
    cfg = bundle.data_config
    observed = cfg.observed if observed is None else int(observed)
    horizon = cfg.future if horizon is None else int(horizon)
    _window_config(bundle, observed)
    if horizon < 1:
        raise InputError(f"--horizon must be >= 1 frame, got {horizon}")
    same_file = a.path == b.path
    a_win = _window(a, a_start, observed, what="the A start frame")
    consecutive = False
    if same_file and b_start is None:
        ab = _window(a, a_start, observed + horizon, what="the A start frame (A and B from one file)")
        consecutive = True
    else:
        b_win = _window(b, 0 if b_start is None else b_start, horizon, what="the B start frame")
        a_end = model_frame(a, a_start, what="the A start frame") + observed
        if same_file and model_frame(b, b_start, what="the B start frame") == a_end:
            ab, consecutive = np.concatenate([a_win, b_win]), True
        elif cfg.layout == "face":
            ab = np.concatenate([a_win, b_win])
        else:
            ab = np.concatenate([a_win, stitch_after(a_win, b_win).astype(np.float32)])
    c_win = _window(c, c_start, observed, what="the C start frame")
    z, _, shown_ab, shown_cd = analogy_windows(bundle, ab[None], c_win[None], observed=observed, horizon=horizon)
    return AnalogyResult(ab=shown_ab[0].astype(np.float32), cd=shown_cd[0].astype(np.float32), observed=observed,
                         z=z[0], fps=cfg.fps, layout=cfg.layout, names=(a.path, b.path, c.path),
                         consecutive=consecutive, a_identity=a.identity, c_identity=c.identity)


def render_analogy(result: AnalogyResult, *, style: str = "skeleton", size: int = 256) -> np.ndarray:
    """Two cells side by side: A (green) then B (green) | C (green) then the generated D (red). Bodies: each
    cell has its own camera; ``mesh`` draws A -> B with the source look and C -> D with the target look.
    Faces: the Anny face with A's and C's identities (C's replaced by another identity when they are the same,
    so the transfer shows on another face).

    Returns:
        (observed + horizon, H, W, 3) uint8.
    """
    return np.concatenate(list(iter_analogy(result, style=style, size=size)))


def iter_analogy(result: AnalogyResult, *, style: str = "skeleton", size: int = 256) -> Iterator[np.ndarray]:
    """:func:`render_analogy` as a stream of (t, H, W, 3) uint8 chunks (both cells drawn lazily)."""
    if style not in STYLES:
        raise InputError(f"unknown style {style!r}; choose one of {', '.join(STYLES)}")
    names = [_stem(n) for n in result.names]
    same_face = result.layout == "face" and result.a_identity == result.c_identity
    left = iter_sequence(result.ab, layout=result.layout, style=style, size=size, fps=result.fps,
                         look=SOURCE_LOOK, identity=result.a_identity)
    right = iter_sequence(result.cd, layout=result.layout, style=style, size=size, fps=result.fps,
                          look=TARGET_LOOK, identity=ALT_FACE_IDENTITY if same_face else result.c_identity,
                          face_colours=ALT_FACE_COLOURS if same_face else None)
    to, h = result.observed, result.ab.shape[0] - result.observed
    left = iter_mark_segments(left, [(to, GREEN, f"A: {names[0]}"), (h, GREEN, f"B: {names[1]}")])
    right = iter_mark_segments(right, [(to, GREEN, f"C: {names[2]}"),
                                       (result.cd.shape[0] - to, RED, "D = C + (B - A)")])
    return iter_grid([left, right], None, 2)


def _stem(path: str) -> str:
    from pathlib import Path

    return Path(path).stem


# --- the known-answer analogy -------------------------------------------------------------------------------


def procedural_analogy_case(x: str, y: str, *, seed: int, fps: float = 25.0, observed: int = 16,
                            future: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """One known-answer analogy: A -> B where mode X turns into mode Y, and another instance C of mode X.

    A/B use speed in [0.85, 1.0] and body height in [1.55, 1.72] m; C uses speed in [1.0, 1.15] and height
    in [1.72, 1.9] m, with its own phase, so C is never the same instance.

    Returns:
        ab (observed + future, 17, 3) and c (observed, 17, 3) float32 world joints.
    """
    rng = np.random.default_rng(seed)
    s_ab, s_c = rng.uniform(0.85, 1.0), rng.uniform(1.0, 1.15)
    h_ab, h_c = rng.uniform(1.55, 1.72), rng.uniform(1.72, 1.9)
    obs_s, fut_s = observed / fps, future / fps
    ab = generate([ModeSpec(x, obs_s, speed=s_ab, phase=rng.uniform()),
                   ModeSpec(y, fut_s, speed=s_ab, phase=rng.uniform(0.0, 0.15))],
                  fps=fps, params=BodyParams(height=h_ab), variation=0.0).joints
    c = generate([ModeSpec(x, obs_s, speed=s_c, phase=rng.uniform())], fps=fps, params=BodyParams(height=h_c),
                 variation=0.0).joints
    return ab[:observed + future], c[:observed]


def procedural_transition_dataset(num_sequences: int, *, seed: int) -> MotionDataset:
    """Training data for the known-answer analogy: ``num_sequences`` sequences of the multimodal benchmark
    (:func:`motion2video.data.dataset.multimodal_clips`: a context mode, then a future mode from the first
    future frame; 16 + 48 frames at 25 fps) drawn and split with ``seed``, one window each, no speed
    augmentation (it would move the transition inside the window)."""
    config = DatasetConfig(observed=16, future=48, stride=64, speed=0.0, val_fraction=0.05, test_fraction=0.05,
                           split_seed=seed)
    return build_dataset(MULTIMODAL_SOURCE, config, clips=multimodal_clips(config, count=num_sequences))


def known_answer_labels(bundle: ModelBundle, x: str, y: str, *, seeds,
                        benchmark: MultimodalBenchmark = MultimodalBenchmark()) -> np.ndarray:
    """Mode-classifier labels of D for :func:`procedural_analogy_case` (X -> Y) at every seed: (len(seeds),) str."""
    cases = [procedural_analogy_case(x, y, seed=int(s), fps=benchmark.fps, observed=benchmark.observed_frames,
                                     future=benchmark.future_frames) for s in seeds]
    ab = np.stack([a for a, _ in cases])
    c = np.stack([c for _, c in cases])
    _, d, _, _ = analogy_windows(bundle, ab, c, observed=benchmark.observed_frames,
                                 horizon=benchmark.future_frames)
    return default_classifier(benchmark).predict(d)
