"""Sample K futures of an observed clip: the one place a motion model's ``sample()`` is called.

:func:`sample_futures` is the batched call on normalised features (evaluation, the benchmark scripts);
:func:`forecast` encodes the observed frames of a clip exactly as training windows are encoded (canonical frame
from the last observed frame, the checkpoint's normalisation), draws K futures through :func:`sample_futures` and
decodes them back to the clip's own coordinates: world metres for body3d models, pixels of the layout's virtual
camera for body2d models, face parameters for face models. :func:`sample_forecast` is :func:`forecast` with the
sample-count limit and a torch thread count (``synthesize``).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np
import torch

from motion2video.models.checkpoint import ModelBundle
from motion2video.core.errors import InputError
from motion2video.data.dataset import DatasetConfig, decode_samples, encode_observation, observed_in_layout

MAX_SAMPLES = 64


@contextlib.contextmanager
def torch_threads(count: int | None):
    """Run a block with ``torch.set_num_threads(count)`` (None: leave it), restoring the old value."""
    if count is None:
        yield
        return
    before = torch.get_num_threads()
    torch.set_num_threads(max(1, int(count)))
    try:
        yield
    finally:
        torch.set_num_threads(before)


def as_model_input(x: np.ndarray, model: torch.nn.Module) -> torch.Tensor:
    """(...) array -> float32 tensor on the model's device."""
    params = list(model.parameters())
    device = params[0].device if params else torch.device("cpu")
    return torch.from_numpy(np.ascontiguousarray(x, np.float32)).to(device)


# The observed motion carried into a sampled future (:func:`continue_observed`): the decay time of the correction,
# in frames (0.64 s at the shipped models' 25 fps). Chosen on the validation split (mtvae-add and mtvae-add-dlow,
# best-of-50 ADE over actions): 4, 8, 16 and 32 frames all gave the first frame last-step's error; the ADE fell by
# 0.007 / 0.009 / 0.011 / 0.012 (ratio to zero-velocity) for mtvae-add-dlow, and 16 is the shortest within 0.001 of
# the best, so the model's own motion takes over after about half a second.
CONTINUE_FRAMES = 16.0


def continue_observed(samples: np.ndarray, obs: np.ndarray, *, frames: float = CONTINUE_FRAMES) -> np.ndarray:
    """Sampled futures that continue the observed motion: each future is shifted so that its first frame is the
    last observed frame plus the last observed step, the shift fading as ``exp(-t / frames)`` (t = 0 at the first
    future frame).

    The recurrent decoders start a future at about the last observed pose, whatever the velocity: on the held-out
    windows (``motion2video evaluate --raw-futures``) their first frame had zero-velocity's error (mtvae-add-dlow
    0.118 m best of 50, zero-velocity 0.118, last-step 0.058), and a video stalls for a moment where the observed
    frames end. With the shift the first frame has last-step's error and the best-of-50 ADE falls by 0.007-0.012 m.
    Features are positions (body: root-relative joints and the root; face: coefficients and head pose), and the
    shift commutes with the per-feature normalisation, so it is applied to normalised features as they are.

    Args:
        samples: (N, K, T, F) futures; obs: (N, To, F) the observed frames (To >= 2), in the same units.
    Returns:
        (N, K, T, F) float32.
    """
    if obs.shape[1] < 2 or samples.shape[2] == 0:
        return samples
    target = 2.0 * obs[:, -1] - obs[:, -2]  # (N, F)
    shift = target[:, None] - samples[:, :, 0]  # (N, K, F)
    fade = np.exp(-np.arange(samples.shape[2]) / float(frames))  # (T,)
    return (samples + shift[:, :, None] * fade[None, None, :, None]).astype(np.float32)


@torch.no_grad()
def sample_futures(model: torch.nn.Module, obs: np.ndarray, *, num_samples: int, horizon: int, seed: int,
                   batch_size: int = 32, continue_motion: bool = True) -> np.ndarray:
    """K futures per observation: obs (N, To, F) normalised -> (N, K, horizon, F) normalised (float32).

    ``continue_motion``: a learned model's futures continue the observed motion (:func:`continue_observed`); a
    baseline's (``is_baseline``) are left as its rule makes them.
    """
    model.eval()
    gen = torch.Generator().manual_seed(seed)
    out = []
    for i in range(0, len(obs), batch_size):
        s = model.sample(as_model_input(obs[i:i + batch_size], model), num_samples=num_samples, horizon=horizon,
                         generator=gen)
        out.append(s.float().cpu().numpy())
    if not out:
        return np.zeros((0, num_samples, horizon, obs.shape[-1]), np.float32)
    samples = np.concatenate(out)
    if continue_motion and not getattr(model, "is_baseline", False):
        samples = continue_observed(samples, np.asarray(obs, np.float32))
    return samples


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
        rigid_bones: whether the futures were given the observed bone lengths (:func:`keep_bone_lengths`).
    """

    observed: np.ndarray
    futures: np.ndarray
    fps: float
    layout: str
    model: str
    seed: int
    rigid_bones: bool = False


def forecast(bundle: ModelBundle, clip: np.ndarray, *, num_samples: int, observed: int | None = None,
             horizon: int | None = None, start: int = 0, seed: int = 0, source: str | None = None,
             rigid_bones: bool = False) -> Forecast:
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
        rigid_bones: 3D body models: every future frame's bones rescaled along their own directions to the
            last observed frame's lengths (:func:`keep_bone_lengths`). The models predict joint positions, and
            their futures' bones vary by 5-15% (they shrink limbs where unsure); rigid futures look like the
            observed person but are about 3% further from the truth (best-of-50 ADE, docs/results.md).
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
    samples = sample_futures(bundle.model, features, num_samples=num_samples, horizon=horizon,
                             seed=int(seed))  # (1, K, horizon, F)
    futures = decode_samples(samples, config=cfg, stats=bundle.stats, frame=frame)[0]
    rigid = bool(rigid_bones) and cfg.layout == "body3d"
    if rigid:
        futures = keep_bone_lengths(futures, np.asarray(obs[-1]))
    return Forecast(observed=observed_in_layout(obs, config=cfg).astype(np.float32),
                    futures=futures.astype(np.float32), fps=cfg.fps, layout=cfg.layout, model=bundle.name,
                    seed=int(seed), rigid_bones=rigid)


def keep_bone_lengths(futures: np.ndarray, posture: np.ndarray) -> np.ndarray:
    """Joints (..., 17, 3) (futures (K, T, 17, 3), or one sequence (T, 17, 3)) with every frame's bones rescaled
    along their own directions to the lengths of ``posture`` (17, 3), the pelvis kept where it is
    (:func:`motion2video.core.skeletons.with_bone_lengths`), float64."""
    from motion2video.core.skeletons import bone_lengths, with_bone_lengths

    return with_bone_lengths(futures, bone_lengths(posture))


def sample_forecast(bundle, clip: np.ndarray, *, samples: int, observed: int | None = None,
                    horizon: int | None = None, start: int = 0, seed: int = 0, threads: int | None = 1,
                    source: str | None = None, rigid_bones: bool = False) -> "Forecast":
    """K futures of ``clip[start:start + observed]`` from a motion model.

    Args:
        bundle: a :class:`~motion2video.models.checkpoint.ModelBundle`.
        clip: (T, 17, 3) world joints or (T, 58) face parameters at the model's rate
            (:func:`motion2video.stages.clips.load_clip`).
        samples: K >= 1.
        threads: torch threads while sampling (1 is fastest for the small recurrent models here).
        rigid_bones: keep the observed bone lengths in the futures (3D body models; see :func:`forecast`).
    Returns:
        A :class:`Forecast`: observed (To, ...) and futures (K, Tf, ...).
    """
    if not 1 <= int(samples) <= MAX_SAMPLES:
        raise InputError(f"the number of samples must be in 1..{MAX_SAMPLES}, got {samples}")
    with torch_threads(threads):
        return forecast(bundle, clip, num_samples=int(samples), observed=observed, horizon=horizon, start=start,
                        seed=seed, source=source, rigid_bones=rigid_bones)
