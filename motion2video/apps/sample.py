"""K sampled futures of one observed clip, as motion and as a grid video (the ``sample`` command's work:
:func:`sample_to_files`).

:func:`forecast` encodes the observed frames of a clip exactly as training windows are encoded
(canonical frame from the last observed frame, the checkpoint's normalisation), draws K futures from the
model in one batched call and decodes them back to the clip's own coordinates: world metres for body3d
models, pixels of the layout's virtual camera for body2d models, face parameters for face models.
:func:`render_forecast` draws the papers' layout (observed frames framed green, each future framed red).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.camera import fit_camera, fit_image_framing
from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion
from motion2video.data.dataset import DatasetConfig
from motion2video.formats.bvh_write import write_bvh_files
from motion2video.formats.video import VideoWriter, iter_observed_future
from motion2video.models.baselines import BASELINES, RULES
from motion2video.models.checkpoint import ModelBundle, baseline_bundle, load_model
from motion2video.stages.clips import load_clip
from motion2video.stages.sampling import Forecast, forecast
from motion2video.stages.layout import check_bvh_output, check_cell_size, check_video_and_npz
from renderers.registry import check_style, renderer_for

STYLES = ("skeleton", "mesh")


def load_clip_for(bundle: ModelBundle, path: str | Path, *, character: str | Path | None = None,
                  rig_map: str | Path | None = None,
                  fps: float | None = None) -> np.ndarray:
    """The clip at ``path`` as the model's data at its frame rate (:func:`motion2video.stages.clips.load_clip`):
    (T, 17, 3) world joints for body models, (T, 58) face parameters for face models. ``character``, ``rig_map``
    and ``fps`` as in ``load_clip``."""
    return load_clip(bundle, path, character=character, fps=fps, rig_map=rig_map).data


def render_forecast(fc: Forecast, *, style: str = "skeleton", size: int = 256) -> np.ndarray:
    """The grid video: every cell plays the observed frames framed green, then one future framed red.

    Body motion is drawn with one camera (or 2D framing) fitted to the observed frames and all futures,
    so the cells are comparable; ``style="mesh"`` poses the Anny body (3D body models only). Face models
    are drawn with the Anny face renderer. All frames in memory: :func:`iter_forecast` streams them.

    Returns:
        (To + horizon, H, W, 3) uint8.
    """
    return np.concatenate(list(iter_forecast(fc, style=style, size=size)))


def iter_forecast(fc: Forecast, *, style: str = "skeleton", size: int = 256) -> Iterator[np.ndarray]:
    """:func:`render_forecast` as a stream of (t, H, W, 3) uint8 chunks.

    The style is checked at once (InputError); the observed frames are drawn once, each future is drawn
    lazily chunk by chunk as the grid (:func:`motion2video.formats.video.iter_observed_future`) consumes it.
    """
    if style not in STYLES:
        raise InputError(f"unknown style {style!r}; choose one of {', '.join(STYLES)}")
    check_style(fc.layout, style)
    return _iter_forecast(fc, style, size)


def _iter_forecast(fc: Forecast, style: str, size: int) -> Iterator[np.ndarray]:
    labels = [f"sample {k + 1}" for k in range(len(fc.futures))]
    with renderer_for(fc.layout, style, size=size) as r:
        placement = _shared_placement(fc, r, size)
        cells = [r.iter_draw(f, fc.fps, **placement) for f in fc.futures]
        yield from iter_observed_future(r.draw(fc.observed, fc.fps, **placement), cells, labels)


def _shared_placement(fc: Forecast, r, size: int) -> dict:
    """One camera (3D bodies), 2D framing (2D bodies) or close-up face camera for every cell, fitted to the
    observed frames and all futures (faces: to the observed frames)."""
    if fc.layout == "face":
        return {"camera": r.renderer.camera_for(FaceMotion(fc.observed, fc.fps))}
    if fc.layout == "body2d":
        points = np.concatenate([fc.observed.reshape(-1, 2), fc.futures.reshape(-1, 2)])
        return {"framing": fit_image_framing(points, size, size)}
    points = np.concatenate([fc.observed.reshape(-1, 3), fc.futures.reshape(-1, 3)])
    return {"camera": fit_camera(points, size, size, margin=0.1)}


def save_forecast_npz(fc: Forecast, path: str | Path) -> Path:
    """Write ``observed``, ``futures``, ``fps``, ``layout``, ``model``, ``seed``, ``rigid_bones`` (and
    ``skeleton`` for body layouts) to an .npz, atomically."""
    arrays = {"observed": fc.observed, "futures": fc.futures, "fps": np.float64(fc.fps),
              "layout": np.str_(fc.layout), "model": np.str_(fc.model), "seed": np.int64(fc.seed),
              "rigid_bones": np.bool_(fc.rigid_bones)}
    if fc.layout != "face":
        arrays["skeleton"] = np.str_("h36m-17")
    return save_npz(path, arrays)


@dataclass(frozen=True)
class SampleSettings:
    """One ``sample`` run: K futures of a clip, drawn as a grid video.

    Attributes:
        model: checkpoint path, shipped model name, or a baseline or rule name (zero-velocity, mirror-periodic, ...).
        input: the observed clip (a motion file or a video of a person; face models: a face capture).
        output: the grid video (.mp4 or .gif).
        samples: K futures.
        observed, horizon: observed and future frames (None: the model's).
        start: first observed frame of the clip. seed: the sampling seed.
        rigid_bones: every future frame keeps the last observed frame's bone lengths.
        npz: also write observed + futures here (:func:`save_forecast_npz`), or None.
        style: ``skeleton`` or ``mesh`` (3D body models). size: cell width and height in pixels.
        character, input_fps, rig_map: how the clip is read (:func:`motion2video.stages.clips.load_clip`).
        bvh: also write each future (after the observed frames) as a BVH file into this folder, or None.
    """

    model: str | Path
    input: str | Path
    output: str | Path
    samples: int
    observed: int | None = None
    horizon: int | None = None
    start: int = 0
    seed: int = 0
    rigid_bones: bool = False
    npz: str | Path | None = None
    style: str = "skeleton"
    size: int = 256
    character: str | Path | None = None
    input_fps: float | None = None
    rig_map: str | Path | None = None
    bvh: str | Path | None = None


@dataclass
class SampleFiles:
    """What :func:`sample_to_files` wrote: the forecast, the video and its frame size, the npz (or None) and the
    BVH files (empty without a folder)."""

    forecast: Forecast
    video: Path
    width: int
    height: int
    npz: Path | None = None
    bvh: list[Path] = field(default_factory=list)


def sample_to_files(settings: SampleSettings) -> SampleFiles:
    """Sample ``settings.samples`` futures of the clip and write the grid video (and the npz and BVH files asked
    for). Every output path, the cell size and the model are checked before the clip is read (InputError)."""
    s = settings
    check_cell_size(s.size)
    out = check_video_and_npz(s.output, s.npz)
    bundle = baseline_bundle(s.model, DatasetConfig()) if s.model in BASELINES + RULES else load_model(s.model)
    check_bvh_output(s.bvh, bundle.data_config.layout)
    clip = load_clip_for(bundle, s.input, character=s.character, fps=s.input_fps, rig_map=s.rig_map)
    fc = forecast(bundle, clip, num_samples=s.samples, observed=s.observed, horizon=s.horizon, start=s.start,
                  seed=s.seed, source=s.input, rigid_bones=s.rigid_bones)
    chunks = iter_forecast(fc, style=s.style, size=s.size)
    with VideoWriter(out, fc.fps) as writer:
        for chunk in chunks:
            writer.write(chunk)
    result = SampleFiles(fc, out, writer.width, writer.height)
    if s.npz:
        result.npz = save_forecast_npz(fc, s.npz)
    if s.bvh:
        clips = np.concatenate([np.broadcast_to(fc.observed, (len(fc.futures),) + fc.observed.shape), fc.futures],
                               axis=1)  # (K, To + Tf, 17, 3)
        result.bvh = write_bvh_files(s.bvh, "sample", clips, fc.fps)
    return result
