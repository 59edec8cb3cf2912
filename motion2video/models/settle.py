"""``settle``: futures that come to rest, each at its own pace.

A person who waves, raises a hand or bows mostly stands: their root-relative joints barely move, and the learned
samplers, which draw walks, dances and turns, move the whole body in every future. On Bandai-Namco's waves and
raised hands the shipped mixture's best of 50 futures was further from the truth than standing still
(docs/results.md, "The subject split with Bandai-Namco"). This rule gives such futures: the last observed step
continued with a velocity that decays to zero,

    x_{T+t} = x_T + (x_T - x_{T-1}) * sum_{s=0}^{t} exp(-s / tau),   t = 0, ..., horizon - 1,

between the MT-VAE paper's baselines ``last-step`` (tau -> infinity) and ``zero-velocity`` (the step repeated
once, then nothing). Future k takes the k-th of K decay times spread geometrically over [``min_decay``,
``max_decay``] frames (1-16 frames: a stop within 0.04-0.64 s at 25 fps); a single future takes their geometric
mean. The first future frame is the last observed frame plus its last step, as every learned model's future is
(:func:`motion2video.stages.sampling.continue_observed`), so the continuation shift leaves it as it is.

The rule is linear in the features, so it acts on normalised features directly (normalisation is affine per
feature, as for :mod:`motion2video.models.baselines`). It has no parameters and nothing to train; a mixture draws a
few of its futures from it (:mod:`motion2video.models.mixture`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from motion2video.models.base import LossOutput, check_rule_input, register_model

NOT_TRAINED = "settle is a rule with no parameters: there is nothing to train"


@dataclass(frozen=True)
class SettleConfig:
    """Decay times of the velocity in frames at the windows' frame rate (25 fps: 1-16 frames = 0.04-0.64 s)."""

    feature_dim: int = 51
    min_decay: float = 1.0
    max_decay: float = 16.0


def decay_times(config: SettleConfig, count: int) -> np.ndarray:
    """(count,) the decay times of futures 0 .. count-1: geometric steps over the configured range (one future:
    the range's geometric mean)."""
    if count == 1:
        return np.array([np.sqrt(config.min_decay * config.max_decay)])
    return np.geomspace(config.min_decay, config.max_decay, count)


def settle_futures(obs: torch.Tensor, taus: np.ndarray, horizon: int) -> torch.Tensor:
    """obs (B, To >= 2, F) -> (B, K, horizon, F): one future per decay time in ``taus`` (K,), in obs's units.

    Future k at frame t is ``x_T + step * sum_{s <= t} exp(-s / taus[k])``, ``step = x_T - x_{T-1}``.
    """
    t = torch.arange(horizon, dtype=torch.float64)
    tau = torch.as_tensor(np.asarray(taus, np.float64))
    travel = torch.cumsum(torch.exp(-t[None, :] / tau[:, None]), dim=1)  # (K, horizon), in steps
    last = obs[:, -1].double()
    step = last - obs[:, -2].double()
    futures = last[:, None, None] + step[:, None, None] * travel[None, :, :, None]  # (B, K, horizon, F)
    return futures.to(obs.dtype)


@register_model("settle", SettleConfig, kind="baseline")
class Settle(nn.Module):
    """K futures, each the last step continued with a velocity decaying at its own pace (module docstring)."""

    is_baseline = True  # its futures already continue the observed motion (stages.sampling leaves them)

    def __init__(self, config: SettleConfig) -> None:
        super().__init__()
        if not 0.0 < config.min_decay <= config.max_decay:
            raise ValueError(f"need 0 < min_decay <= max_decay, got {config.min_decay}, {config.max_decay}")
        self.config = config

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        raise ValueError(NOT_TRAINED)

    @torch.no_grad()
    def sample(self, obs: torch.Tensor, *, num_samples: int, horizon: int,
               generator: torch.Generator | None = None) -> torch.Tensor:
        """obs (B, To, F) -> (B, K, horizon, F), any affine normalisation; ``generator`` is unused (a rule)."""
        check_rule_input("settle", obs, num_samples=num_samples, horizon=horizon, feature_dim=self.config.feature_dim)
        return settle_futures(obs, decay_times(self.config, num_samples), horizon)
