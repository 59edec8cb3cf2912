"""What every motion model looks like from the outside.

Models work on normalised feature sequences ``(B, T, F)`` (the data module turns joints or face parameters
into features and back; a model never knows which). A model is a ``torch.nn.Module`` with a frozen dataclass
``config`` and these methods:

- ``loss(obs, future, *, step) -> LossOutput``: the training objective on one batch
  (obs ``(B, To, F)``, future ``(B, Tf, F)``); ``step`` drives annealing schedules.
- ``sample(obs, *, num_samples, horizon, generator=None) -> (B, K, horizon, F)``: K futures per context,
  batched (no Python loop over K); a deterministic model returns K identical copies.

Latent-variable models also expose
- ``encode(obs, future) -> LatentPosterior`` (mean and log-variance of q(z | obs, future)), and
- ``decode(obs, z, *, horizon) -> (B, horizon, F)`` (the future given a context and a latent),
which is what analogy and behaviour transfer use.

Models register themselves by name with :func:`register_model`; :func:`build_model` rebuilds one from its
name and config dict (the checkpoint loader uses it).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import torch


@dataclass
class LossOutput:
    """``total`` is the scalar to back-propagate; ``terms`` are detached floats for logging."""

    total: torch.Tensor
    terms: dict[str, float]


@dataclass
class LatentPosterior:
    """Diagonal Gaussian q(z | ...): ``mu`` and ``logvar`` are (B, Z)."""

    mu: torch.Tensor
    logvar: torch.Tensor


def check_sequences(obs: torch.Tensor, future: torch.Tensor | None, *, feature_dim: int) -> None:
    """Raise ValueError unless obs is (B, To, F) (and future (B, Tf, F)) with F == feature_dim."""
    if obs.ndim != 3 or obs.shape[-1] != feature_dim or obs.shape[1] < 1:
        raise ValueError(f"obs must have shape (B, To>=1, {feature_dim}), got {tuple(obs.shape)}")
    if future is not None:
        if future.ndim != 3 or future.shape[-1] != feature_dim or future.shape[1] < 1:
            raise ValueError(f"future must have shape (B, Tf>=1, {feature_dim}), got {tuple(future.shape)}")
        if future.shape[0] != obs.shape[0]:
            raise ValueError(f"obs and future batch sizes differ: {obs.shape[0]} vs {future.shape[0]}")


def check_sample_args(num_samples: int, horizon: int) -> None:
    if num_samples < 1:
        raise ValueError(f"num_samples must be >= 1, got {num_samples}")
    if horizon < 1:
        raise ValueError(f"horizon must be >= 1, got {horizon}")


def check_rule_input(name: str, obs: torch.Tensor, *, num_samples: int, horizon: int, feature_dim: int) -> None:
    """The checks of a multi-future rule's ``sample`` (``mirror-periodic``, ``settle``): K and the horizon, obs
    (B, To, F) with F == feature_dim, and the two observed frames a last step needs (ValueError otherwise)."""
    check_sample_args(num_samples, horizon)
    check_sequences(obs, None, feature_dim=feature_dim)
    if obs.shape[1] < 2:
        raise ValueError(f"{name} needs at least two observed frames")


class LatentSampler:
    """The one ``sample()`` of the latent models: checks, then ``sample_rows`` draws all B*K futures in one
    batched pass (a model supplies ``sample_rows`` and, when its context check differs, ``check_context``)."""

    @torch.no_grad()
    def sample(self, obs: torch.Tensor, *, num_samples: int, horizon: int,
               generator: torch.Generator | None = None, **options) -> torch.Tensor:
        """obs (B, To, F) -> (B, K, horizon, F): K futures per context."""
        check_sample_args(num_samples, horizon)
        self.check_context(obs, **options)
        out = self.sample_rows(obs, num_samples, horizon=horizon, generator=generator, **options)  # (B*K, ...)
        return out.view(obs.shape[0], num_samples, horizon, -1)

    def check_context(self, obs: torch.Tensor, **options) -> None:
        check_sequences(obs, None, feature_dim=self.config.feature_dim)

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None, **options) -> torch.Tensor:
        """(B, To, F) -> (B*K, horizon, F), rows ordered context-major (row b*K + k)."""
        raise NotImplementedError


class DeterministicSampler:
    """``sample()`` of a deterministic model: K identical copies of ``predict(obs, horizon=...)``."""

    @torch.no_grad()
    def sample(self, obs: torch.Tensor, *, num_samples: int, horizon: int,
               generator: torch.Generator | None = None) -> torch.Tensor:
        """(B, To, F) -> (B, K, horizon, F): K identical copies of the one prediction (generator unused)."""
        check_sample_args(num_samples, horizon)
        pred = self.predict(obs, horizon=horizon)  # (B, horizon, F)
        return pred[:, None].expand(-1, num_samples, -1, -1).contiguous()


@dataclass(frozen=True)
class ModelEntry:
    name: str
    config_cls: type
    model_cls: type
    kind: str  # "deterministic" | "stochastic" | "baseline"


MODEL_REGISTRY: dict[str, ModelEntry] = {}


def register_model(name: str, config_cls: type, *, kind: str) -> Callable[[type], type]:
    """Class decorator: ``@register_model("mtvae-add", MTVAEConfig, kind="stochastic")``."""

    def wrap(model_cls: type) -> type:
        if name in MODEL_REGISTRY:
            raise ValueError(f"model {name!r} registered twice")
        MODEL_REGISTRY[name] = ModelEntry(name, config_cls, model_cls, kind)
        return model_cls

    return wrap


def build_model(name: str, config: dict | None = None) -> torch.nn.Module:
    """Instantiate a registered model from its name and a (partial) config dict."""
    if name not in MODEL_REGISTRY:
        raise KeyError(f"unknown model {name!r}; known: {', '.join(sorted(MODEL_REGISTRY))}")
    entry = MODEL_REGISTRY[name]
    fields = {f.name for f in dataclasses.fields(entry.config_cls)}
    unknown = set(config or {}) - fields
    if unknown:
        raise KeyError(f"model {name!r} has no config field(s) {sorted(unknown)}")
    return entry.model_cls(entry.config_cls(**(config or {})))
