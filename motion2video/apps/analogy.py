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

The known-answer protocol is :mod:`motion2video.evaluation.analogy_benchmark`; :func:`analogy_to_files` is the
``analogy`` command's work.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.errors import InputError
from motion2video.formats.bvh_write import write_bvh_files
from motion2video.formats.video import VideoWriter
from motion2video.models.baselines import BASELINES
from motion2video.models.checkpoint import ModelBundle, load_model
from motion2video.stages.clips import LoadedClip, load_clip, model_frame
from motion2video.stages.latents import analogy_model, analogy_windows, stitch_after, window_config
from motion2video.stages.structure import (
    ALT_FACE_COLOURS,
    ALT_FACE_IDENTITY,
    SOURCE_LOOK,
    TARGET_LOOK,
    iter_sequence,
)
from motion2video.stages.layout import check_bvh_output, check_cell_size, check_video_and_npz, iter_mark_segments
from motion2video.formats.video import GREEN, RED, iter_grid
from renderers.registry import check_style

STYLES = ("skeleton", "mesh")


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
        a, b, c: clips loaded for the model (:func:`motion2video.stages.clips.load_clip`).
        a_start, c_start: first frame of A's and C's windows.
        b_start: first frame of B's window; None: right after A's window when B is A's file, else 0.
        observed: frames of A and C (default: the model's).
        horizon: frames of B and D (default: the model's).
    """
    analogy_model(bundle)
    cfg = bundle.data_config
    observed = cfg.observed if observed is None else int(observed)
    horizon = cfg.future if horizon is None else int(horizon)
    window_config(bundle, observed)
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
    return Path(path).stem




@dataclass(frozen=True)
class AnalogySettings:
    """One ``analogy`` run: A : B :: C : D from three clip files, drawn as a video.

    Attributes:
        model: a latent model's checkpoint path or shipped name.
        a, b, c: the clips of A, B and C (B often A's file).
        output: the video (.mp4 or .gif).
        a_start, b_start, c_start: first frames of A, B (None: right after A when B is A's file, else 0) and C.
        observed, horizon: frames of A and C, of B and D (None: the model's).
        style: ``skeleton`` or ``mesh`` (3D body models). size: cell width and height in pixels.
        npz: also write A->B, C->D and z here, or None.
        character, input_fps, rig_map: how the clips are read (:func:`motion2video.stages.clips.load_clip`).
        bvh: also write C then the generated D as a BVH file into this folder, or None.
    """

    model: str | Path
    a: str | Path
    b: str | Path
    c: str | Path
    output: str | Path
    a_start: int = 0
    b_start: int | None = None
    c_start: int = 0
    observed: int | None = None
    horizon: int | None = None
    style: str = "skeleton"
    size: int = 256
    npz: str | Path | None = None
    character: str | Path | None = None
    input_fps: float | None = None
    rig_map: str | Path | None = None
    bvh: str | Path | None = None


@dataclass
class AnalogyFiles:
    """What :func:`analogy_to_files` wrote: the analogy, the model's label, the video and its frame size, the npz
    (or None) and the BVH files (empty without a folder)."""

    result: AnalogyResult
    label: str
    video: Path
    width: int
    height: int
    npz: Path | None = None
    bvh: list[Path] = field(default_factory=list)


def analogy_to_files(settings: AnalogySettings) -> AnalogyFiles:
    """Load the model and the clips, make D and write the video (and the npz and BVH files asked for). The outputs,
    the cell size, the model's kind and the style are checked before any clip is read (InputError)."""
    s = settings
    check_cell_size(s.size)
    out = check_video_and_npz(s.output, s.npz)
    if s.model in BASELINES:
        raise InputError(f"analogy needs a latent-variable model (mtvae-add, ...); {s.model!r} is a baseline "
                         "without a latent space")
    bundle = load_model(s.model)
    check_bvh_output(s.bvh, bundle.data_config.layout)
    analogy_model(bundle)  # the wrong kind of model fails before any clip is read
    check_style(bundle.data_config.layout, s.style)  # mesh needs a 3D body model
    options = {"character": s.character, "fps": s.input_fps, "rig_map": s.rig_map}
    a = load_clip(bundle, s.a, **options)
    b = a if s.b == s.a else load_clip(bundle, s.b, **options)
    c = load_clip(bundle, s.c, **options)
    result = analogy(bundle, a, b, c, a_start=s.a_start, b_start=s.b_start, c_start=s.c_start,
                     observed=s.observed, horizon=s.horizon)
    chunks = iter_analogy(result, style=s.style, size=s.size)
    with VideoWriter(out, result.fps) as writer:
        for chunk in chunks:
            writer.write(chunk)
    files = AnalogyFiles(result, bundle.label, out, writer.width, writer.height)
    if s.npz:
        files.npz = save_npz(s.npz, {"ab": result.ab, "cd": result.cd, "z": result.z,
                                     "observed": np.int64(result.observed), "fps": np.float64(result.fps),
                                     "layout": np.str_(result.layout), "model": np.str_(bundle.name)})
    if s.bvh:
        files.bvh = write_bvh_files(s.bvh, "analogy", result.cd[None], result.fps)
    return files
