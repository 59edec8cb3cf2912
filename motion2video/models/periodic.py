"""``mirror-periodic``: futures that repeat the observed motion every half gait cycle, mirrored.

A walk or a run is periodic, and its second half-cycle is the first one mirrored: the left leg does what the right
leg did half a cycle before. The 16 observed frames (0.64 s at 25 fps) hold more than half a gait cycle of most
runs and walks (cycles of 0.6-1.3 s; the slowest walks take longer, docs/results.md), so the future can be read off
the past:

    x_t = mirror(x_{t - tau}),   t = To, ..., To + horizon - 1,

where ``mirror`` swaps the left and right joints and negates the lateral axis of the window's canonical frame (at
the last observed frame the hips point along +x, so the body's plane of symmetry is x = 0), and ``tau`` is the
half-period in frames (fractional tau interpolates between frames). Frames earlier generated are read for
t - tau >= To, so the motion repeats for the whole horizon. The root is rebuilt from its mirrored steps (the
walker keeps travelling at the observed pace), its height repeats as it is. Where the motion is not periodic with
2 tau, a repeated frame jumps at every seam (t = To + n tau); a Gaussian along time (``smooth_frames``, with the
observed frames before it) spreads those jumps, which raw gave the futures 2.3 times the truth's acceleration.

The half-period is not known: future k takes the k-th of K half-periods spread evenly over
[``min_half_period``, ``max_half_period``], which covers what a best-of-K measure rewards. A single future (K = 1)
takes the whole half-period that best fits the observed frames instead (:func:`fitted_half_period`), the closer one
future on held-out walks (docs/results.md, "Forecasting body motion"). Like the learned models'
futures (:func:`motion2video.stages.sampling.continue_observed`), each future is then shifted to start at the last
observed frame plus the last observed step, the shift fading over ``decay_frames``.

It has no parameters and nothing to train: a rule, as the MT-VAE paper's baselines are, but with K different
futures. Anchor: "History Repeats Itself" (Mao, Liu, Salzmann, ECCV 2020) predicts by attending to the observed
sub-sequences that resemble the last one; this rule takes that idea at its simplest for a 16-frame past. It needs
metres and the lateral axis, so it keeps the normalisation statistics of the features it is given as buffers
(identity until :meth:`MirrorPeriodic.use_stats`), and works on the ``body3d`` layout only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from scipy.ndimage import gaussian_filter1d
from torch import nn

from motion2video.core.skeletons import H36M_17
from motion2video.models.base import LossOutput, check_rule_input, register_model

BODY3D_FEATURES = 51  # 16 root-relative joints x 3, then the root (x, y, z)
NOT_TRAINED = "mirror-periodic is a rule with no parameters: there is nothing to train"


@dataclass(frozen=True)
class PeriodicConfig:
    """Half-periods in frames at the windows' frame rate (25 fps: 8-16 frames = 0.32-0.64 s, gait cycles of
    0.64-1.28 s); ``smooth_frames``: the Gaussian's standard deviation over the seams (0: none); ``decay_frames``
    as in :func:`motion2video.stages.sampling.continue_observed`."""

    feature_dim: int = BODY3D_FEATURES
    min_half_period: float = 8.0
    max_half_period: float = 16.0
    smooth_frames: float = 1.5
    decay_frames: float = 16.0


def feature_mirror() -> tuple[np.ndarray, np.ndarray]:
    """The left/right mirror of body3d features as a permutation and a sign: ``mirrored = x[..., perm] * sign``.

    Returns:
        perm (51,) int and sign (51,) float: the root-relative joints swap left and right names and negate x;
        the root keeps its place and negates x.
    """
    joints = H36M_17.mirror_permutation()[1:] - 1  # the 16 non-root joints, in feature order
    perm = np.concatenate([(3 * joints[:, None] + np.arange(3)).ravel(), np.arange(48, 51)])
    sign = np.tile([-1.0, 1.0, 1.0], H36M_17.num_joints)  # 16 joints, then the root
    return perm, sign


def half_periods(config: PeriodicConfig, count: int) -> np.ndarray:
    """(count,) the half-periods of futures 0 .. count-1: spread evenly over the configured range."""
    if count == 1:
        return np.array([0.5 * (config.min_half_period + config.max_half_period)])
    return np.linspace(config.min_half_period, config.max_half_period, count)


def fitted_half_period(joints: np.ndarray, config: PeriodicConfig) -> float:
    """The whole half-period in the configured range, short enough to be checked on the observed frames (at most
    To - 1), whose mirror best repeats them: argmin over tau of the mean over t in [tau, To) of
    |x_t - mirror(x_{t - tau})| over the root-relative joints. The middle of the range when none can be checked.

    Args:
        joints: (To, 51) un-normalised body3d features of the observed frames.
    """
    perm, sign = feature_mirror()
    x = np.asarray(joints, np.float64)
    rel = slice(0, 48)
    lo, hi = int(np.ceil(config.min_half_period)), min(int(np.floor(config.max_half_period)), len(x) - 1)
    if lo > hi:
        return float(half_periods(config, 1)[0])
    errors = [np.linalg.norm(x[tau:, rel] - (x[:-tau, perm] * sign)[:, rel], axis=1).mean() for tau in range(lo, hi + 1)]
    return float(lo + int(np.argmin(errors)))


def repeat_mirrored(obs: torch.Tensor, taus: np.ndarray, horizon: int, perm: torch.Tensor,
                    sign: torch.Tensor) -> torch.Tensor:
    """The mirrored repetition in metres: obs (B, To, 51) un-normalised -> (B, K, horizon, 51), one future per
    half-period in ``taus`` (K,), before the continuation shift.

    Joints repeat as positions; the root's x, y are summed from repeated steps, its height repeats as a position.
    The step into the first observed frame is unknown and taken to be the next one (read only at tau = To).
    """
    batch, observed, feat = obs.shape
    if float(np.max(taus)) > observed or float(np.min(taus)) < 1.0:
        raise ValueError(f"half-periods must lie in [1, {observed}] observed frames, got {taus.min()}..{taus.max()}")
    steps = obs.clone()  # (B, To, F): the root's x, y as steps, all else as positions
    steps[:, 1:, 48:50] = obs[:, 1:, 48:50] - obs[:, :-1, 48:50]
    steps[:, 0, 48:50] = steps[:, 1, 48:50]
    out = []
    for tau in taus:
        seq = torch.cat([steps, steps.new_zeros(batch, horizon, feat)], dim=1)  # (B, To + horizon, F)
        lo = int(np.floor(tau))
        w = float(tau - lo)
        for t in range(observed, observed + horizon):
            src = seq[:, t - lo] if w == 0.0 else (1.0 - w) * seq[:, t - lo] + w * seq[:, t - lo - 1]
            seq[:, t] = src[:, perm] * sign
        future = seq[:, observed:].clone()
        future[..., 48:50] = obs[:, -1:, 48:50] + torch.cumsum(future[..., 48:50], dim=1)
        out.append(future)
    return torch.stack(out, dim=1)


def smooth_seams(obs: torch.Tensor, futures: torch.Tensor, sigma: float) -> torch.Tensor:
    """A Gaussian of ``sigma`` frames along time over observed + future: obs (B, To, F), futures (B, K, T, F) ->
    (B, K, T, F), the future part (the observed frames only pad the start; the end repeats the last frame)."""
    batch, count = futures.shape[:2]
    past = obs[:, None].expand(-1, count, -1, -1)
    whole = torch.cat([past, futures], dim=2).cpu().numpy()
    smooth = gaussian_filter1d(whole, sigma, axis=2, mode="nearest")[:, :, obs.shape[1]:]
    return torch.from_numpy(np.ascontiguousarray(smooth)).to(futures)


@register_model("mirror-periodic", PeriodicConfig, kind="baseline")
class MirrorPeriodic(nn.Module):
    """K futures, each the observed motion repeated every half-period, mirrored (module docstring)."""

    is_baseline = True  # its futures already continue the observed motion (stages.sampling leaves them)

    def __init__(self, config: PeriodicConfig) -> None:
        super().__init__()
        if config.feature_dim != BODY3D_FEATURES:
            raise ValueError(f"mirror-periodic works on the body3d layout ({BODY3D_FEATURES} features), "
                             f"not {config.feature_dim}")
        if not 1.0 <= config.min_half_period <= config.max_half_period:
            raise ValueError(f"need 1 <= min_half_period <= max_half_period, got "
                             f"{config.min_half_period}, {config.max_half_period}")
        self.config = config
        perm, sign = feature_mirror()
        self.register_buffer("perm", torch.from_numpy(perm), persistent=False)
        self.register_buffer("sign", torch.from_numpy(sign).float(), persistent=False)
        self.register_buffer("mean", torch.zeros(config.feature_dim))
        self.register_buffer("std", torch.ones(config.feature_dim))

    def use_stats(self, mean: np.ndarray, std: np.ndarray) -> "MirrorPeriodic":
        """Work on features normalised with these (F,) statistics (the checkpoint's): the rule needs metres."""
        self.mean.copy_(torch.as_tensor(np.asarray(mean), dtype=torch.float32))
        self.std.copy_(torch.as_tensor(np.asarray(std), dtype=torch.float32))
        return self

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        raise ValueError(NOT_TRAINED)

    @torch.no_grad()
    def sample(self, obs: torch.Tensor, *, num_samples: int, horizon: int,
               generator: torch.Generator | None = None) -> torch.Tensor:
        """obs (B, To, 51) normalised -> (B, K, horizon, 51) normalised; ``generator`` is unused (a rule)."""
        check_rule_input("mirror-periodic", obs, num_samples=num_samples, horizon=horizon,
                         feature_dim=self.config.feature_dim)
        metres = obs.double() * self.std.double() + self.mean.double()
        sign = self.sign.double()
        if num_samples == 1:  # one future: each window's own best-fitting half-period
            futures = torch.cat([repeat_mirrored(m[None], np.array([fitted_half_period(m.numpy(), self.config)]),
                                                 horizon, self.perm, sign) for m in metres])
        else:
            taus = np.clip(half_periods(self.config, num_samples), 1.0, obs.shape[1])
            futures = repeat_mirrored(metres, taus, horizon, self.perm, sign)  # (B, K, horizon, F)
        if self.config.smooth_frames > 0:
            futures = smooth_seams(metres, futures, self.config.smooth_frames)
        target = 2.0 * metres[:, -1] - metres[:, -2]  # (B, F): the last observed step continued
        fade = torch.exp(-torch.arange(horizon, dtype=torch.float64) / self.config.decay_frames)
        futures = futures + (target[:, None] - futures[:, :, 0])[:, :, None] * fade[None, None, :, None]
        return ((futures - self.mean.double()) / self.std.double()).to(obs.dtype)
