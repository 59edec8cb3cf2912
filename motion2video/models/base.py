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
