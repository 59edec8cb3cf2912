"""K sampled futures of one observed clip, as motion and as a grid video (the ``sample`` command's work).

:func:`forecast` encodes the observed frames of a clip exactly as training windows are encoded
(canonical frame from the last observed frame, the checkpoint's normalisation), draws K futures from the
model in one batched call and decodes them back to the clip's own coordinates: world metres for body3d
models, pixels of the layout's virtual camera for body2d models, face parameters for face models.
:func:`render_forecast` draws the papers' layout (observed frames framed green, each future framed red).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from motion2video.atomic import save_npz
from motion2video.checkpoint import ModelBundle
from motion2video.data.dataset import (
    DatasetConfig,
    decode_samples,
    encode_observation,
    load_clips,
    observed_in_layout,
)
from motion2video.errors import InputError
from motion2video.motion import FaceMotion, Motion

STYLES = ("skeleton", "mesh")


@dataclass
class Forecast:
    """Observed frames and K sampled futures in the same coordinates.

    Attributes:
        observed: (To, 17, 3) world joints, (To, 17, 2) pixels (body2d) or (To, 58) face parameters.
        futures: (K, horizon, ...) the same per frame.
        fps: frame rate of both.
        layout: the model's feature layout.
        model: the model's registry name.
        seed: the sampling seed.
    """

    observed: np.ndarray
    futures: np.ndarray
    fps: float
    layout: str
    model: str
    seed: int


def load_clip_for(bundle: ModelBundle, path: str | Path) -> np.ndarray:
    """The clip at ``path`` as the model's data at its frame rate, loaded exactly as its training data was
    (:func:`motion2video.data.dataset.load_clips`): (T, 17, 3) world joints for body models (any body
    format :func:`motion2video.io.load_motion` reads), (T, 58) face parameters for face models."""
    path = Path(path)
    if path.is_dir():
        raise InputError("sample takes one clip file, not a folder", path)
    return load_clips(path, config=bundle.data_config)[0].data


def forecast(bundle: ModelBundle, clip: np.ndarray, *, num_samples: int, observed: int | None = None,
             horizon: int | None = None, start: int = 0, seed: int = 0, source: str | None = None) -> Forecast:
    """Sample K futures of ``clip[start:start + observed]``.

    Args:
        bundle: the model.
        clip: (T, 17, 3) world joints or (T, 58) face parameters at the model's frame rate.
        num_samples: K >= 1.
        observed: observed frames (default: the model's training value).
        horizon: future frames (default: the model's training value).
        start: first observed frame.
        seed: sampling seed (the same seed gives the same futures).
        source: the clip's path, for error messages.
    Returns:
        A :class:`Forecast`.
    """
    cfg: DatasetConfig = bundle.data_config
    observed = cfg.observed if observed is None else int(observed)
    horizon = cfg.future if horizon is None else int(horizon)
    if num_samples < 1:
        raise InputError(f"the number of samples must be >= 1, got {num_samples}")
    if observed < 2:
        raise InputError(f"at least 2 observed frames are needed, got {observed}")
    if horizon < 1:
        raise InputError(f"the horizon must be >= 1 frame, got {horizon}")
    if start < 0:
        raise InputError(f"the start frame must be >= 0, got {start}")
    if clip.shape[0] < start + observed:
        raise InputError(f"the clip has {clip.shape[0]} frames at {cfg.fps:g} fps, shorter than the observed "
                         f"window ({start} + {observed} frames)", source)
    obs = clip[start:start + observed]
    features, frame = encode_observation(obs, config=cfg, stats=bundle.stats)  # (1, To, F)
    params = list(bundle.model.parameters())
    device = params[0].device if params else torch.device("cpu")
    gen = torch.Generator().manual_seed(int(seed))
    with torch.no_grad():
        samples = bundle.model.sample(torch.from_numpy(features).to(device), num_samples=num_samples,
                                      horizon=horizon, generator=gen)  # (1, K, horizon, F)
    futures = decode_samples(samples.float().cpu().numpy(), config=cfg, stats=bundle.stats, frame=frame)[0]
    return Forecast(observed=observed_in_layout(obs, config=cfg).astype(np.float32),
                    futures=futures.astype(np.float32), fps=cfg.fps, layout=cfg.layout, model=bundle.name,
                    seed=int(seed))


def render_forecast(fc: Forecast, *, style: str = "skeleton", size: int = 256) -> np.ndarray:
    """The grid video: every cell plays the observed frames framed green, then one future framed red.

    Body motion is drawn with one camera (or 2D framing) fitted to the observed frames and all futures,
    so the cells are comparable; ``style="mesh"`` poses the Anny body (3D body models only). Face models
    are drawn with the Anny face renderer.

    Returns:
        (To + horizon, H, W, 3) uint8.
    """
    from motion2video.video import observed_future_video

    if style not in STYLES:
        raise InputError(f"unknown style {style!r}; choose one of {', '.join(STYLES)}")
    labels = [f"sample {k + 1}" for k in range(len(fc.futures))]
    if fc.layout == "face":
        obs_frames, fut_frames = _render_faces(fc, size)
    elif fc.layout == "body2d":
        if style == "mesh":
            raise InputError("--style mesh needs a 3D body model; this model predicts 2D keypoints")
        obs_frames, fut_frames = _render_skeleton_2d(fc, size)
    elif style == "mesh":
        obs_frames, fut_frames = _render_mesh(fc, size)
    else:
        obs_frames, fut_frames = _render_skeleton_3d(fc, size)
    return observed_future_video(obs_frames, fut_frames, labels)


def _shared_camera(fc: Forecast, size: int):
    from motion2video.core.camera import fit_camera

    points = np.concatenate([fc.observed.reshape(-1, 3), fc.futures.reshape(-1, 3)])
    return fit_camera(points, size, size, margin=0.1)


def _render_skeleton_3d(fc: Forecast, size: int) -> tuple[np.ndarray, list[np.ndarray]]:
    from renderers.skeleton import SkeletonRenderer, SkeletonStyle

    camera = _shared_camera(fc, size)
    with SkeletonRenderer(style=SkeletonStyle(size=(size, size))) as r:
        return r.render(fc.observed, camera=camera), [r.render(f, camera=camera) for f in fc.futures]


def _render_skeleton_2d(fc: Forecast, size: int) -> tuple[np.ndarray, list[np.ndarray]]:
    from motion2video.core.camera import fit_image_framing
    from renderers.skeleton import SkeletonRenderer, SkeletonStyle

    points = np.concatenate([fc.observed.reshape(-1, 2), fc.futures.reshape(-1, 2)])
    framing = fit_image_framing(points, size, size)
    with SkeletonRenderer(style=SkeletonStyle(size=(size, size))) as r:
        return r.render(fc.observed, framing=framing), [r.render(f, framing=framing) for f in fc.futures]


def _render_mesh(fc: Forecast, size: int) -> tuple[np.ndarray, list[np.ndarray]]:
    from renderers.body import BodyRenderer, BodyStyle

    camera = _shared_camera(fc, size)
    with BodyRenderer(BodyStyle(size=(size, size))) as r:
        obs = r.render(Motion(fc.observed, fc.fps), camera=camera)
        return obs, [r.render(Motion(f, fc.fps), camera=camera) for f in fc.futures]


def _render_faces(fc: Forecast, size: int) -> tuple[np.ndarray, list[np.ndarray]]:
    from renderers.face import FaceRenderer, FaceStyle

    with FaceRenderer(FaceStyle(size=(size, size))) as r:
        observed = FaceMotion(fc.observed, fc.fps)
        camera = r.camera_for(observed)  # one close-up camera for every cell
        obs = r.render(observed, camera=camera)
        return obs, [r.render(FaceMotion(f, fc.fps), camera=camera) for f in fc.futures]


def save_forecast_npz(fc: Forecast, path: str | Path) -> Path:
    """Write ``observed``, ``futures``, ``fps``, ``layout``, ``model``, ``seed`` (and ``skeleton`` for body
    layouts) to an .npz, atomically."""
    arrays = {"observed": fc.observed, "futures": fc.futures, "fps": np.float64(fc.fps),
              "layout": np.str_(fc.layout), "model": np.str_(fc.model), "seed": np.int64(fc.seed)}
    if fc.layout != "face":
        arrays["skeleton"] = np.str_("h36m-17")
    return save_npz(path, arrays)
