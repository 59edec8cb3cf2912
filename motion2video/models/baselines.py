"""The MT-VAE paper's data-driven baselines: no parameters, no training.

- ``zero-velocity``: every future frame repeats the last observed frame.
- ``last-step``: constant velocity from the last step, ``x_{T+t} = x_T + t (x_T - x_{T-1})``.
- ``sequence-motion``: the mean velocity of the observed frames, ``x_{T+t} = x_T + t (x_T - x_1) / (To - 1)``.

They act on the normalised features directly. That is exact in joint space: every feature layout of
:mod:`motion2video.data.windows` is linear in the joints and normalisation is affine per feature, and
linear extrapolation commutes with affine maps, so extrapolating features and then decoding gives the same
joints as extrapolating the joints. (For faces, decoding clips the coefficients to [0, 1].)
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from motion2video.models.base import DeterministicSampler, LossOutput, register_model

BASELINES = ("zero-velocity", "last-step", "sequence-motion")
# The multi-future rules (models/periodic.py, models/settle.py): `sample` and `evaluate` take them by name beside the
# baselines, and a mixture may draw some of its futures from them (checkpoint.compose_mixture).
RULES = ("mirror-periodic", "settle")


@dataclass(frozen=True)
class BaselineConfig:
    feature_dim: int = 51


def extrapolate(obs: torch.Tensor, velocity: torch.Tensor, horizon: int) -> torch.Tensor:
    """obs (B, To, F), velocity (B, F) -> (B, horizon, F): x_T + t * velocity for t = 1 .. horizon."""
    steps = torch.arange(1, horizon + 1, dtype=obs.dtype, device=obs.device)  # (horizon,)
    return obs[:, -1:, :] + steps[None, :, None] * velocity[:, None, :]


class _Baseline(DeterministicSampler, nn.Module):
    """Shared plumbing: ``predict`` is the only thing a baseline defines."""

    is_baseline = True  # its futures are its rule's (stages.sampling.sample_futures adjusts learned models only)

    def __init__(self, config: BaselineConfig) -> None:
        super().__init__()
        self.config = config

    def velocity(self, obs: torch.Tensor) -> torch.Tensor:  # pragma: no cover - overridden
        raise NotImplementedError

    def predict(self, obs: torch.Tensor, *, horizon: int) -> torch.Tensor:
        """obs (B, To, F) -> (B, horizon, F)."""
        if obs.ndim != 3 or obs.shape[-1] != self.config.feature_dim:
            raise ValueError(f"obs must be (B, To, {self.config.feature_dim}), got {tuple(obs.shape)}")
        return extrapolate(obs, self.velocity(obs), horizon)

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        """The mean squared error of the prediction (nothing to train: ``total`` has no gradient)."""
        with torch.no_grad():
            mse = (self.predict(obs, horizon=future.shape[1]) - future).pow(2).mean()
        return LossOutput(total=mse, terms={"mse": float(mse)})



@register_model("zero-velocity", BaselineConfig, kind="baseline")
class ZeroVelocity(_Baseline):
    def velocity(self, obs: torch.Tensor) -> torch.Tensor:
        return torch.zeros_like(obs[:, -1])


@register_model("last-step", BaselineConfig, kind="baseline")
class LastStep(_Baseline):
    def velocity(self, obs: torch.Tensor) -> torch.Tensor:
        if obs.shape[1] < 2:
            raise ValueError("last-step needs at least two observed frames")
        return obs[:, -1] - obs[:, -2]


@register_model("sequence-motion", BaselineConfig, kind="baseline")
class SequenceMotion(_Baseline):
    def velocity(self, obs: torch.Tensor) -> torch.Tensor:
        if obs.shape[1] < 2:
            raise ValueError("sequence-motion needs at least two observed frames")
        return (obs[:, -1] - obs[:, 0]) / (obs.shape[1] - 1)
