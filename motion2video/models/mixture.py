"""``mixture``: futures drawn in turn from several trained samplers (and multi-future rules) of the same windows.

Why: the two best body samplers fail in different places. ``mtvae-add-dlow`` (recurrent decoder) is the better
one on dances and getting up; ``mixer-cvae-dlow`` (anchored DCT mixer decoder) keeps a walker walking, where the
recurrent one slows to a shuffle. A mixture with equal weights, p(future | obs) = sum_c w_c p_c(future | obs),
is itself a conditional generative model, and its K futures cover what either covers
(docs/results.md, "Forecasting body motion"). ``mixture-periodic`` adds the ``mirror-periodic`` rule, which keeps a
walker's gait, at a share of 12 in 50 (docs/results.md, "Forecasting body motion").

Sampling: with equal shares (the default), future k comes from component ``k mod C`` (so the first C futures show
every component, and K = 50 gives each of two components 25). With ``shares`` w_c, future k comes from the
component furthest behind its share, ``argmax_c (k + 1) w_c - n_c`` (n_c: futures it drew so far, ties to the
first), which is ``k mod C`` for equal shares and keeps every prefix of the K futures within one future of the
shares (:meth:`Mixture.order`). Component c draws its K_c futures (:meth:`Mixture.counts`) with its own rule (a DLow
component: its first K_c maps of one shared noise; ``mirror-periodic``: K_c half-periods); the components draw in
order from one ``generator``.

Nothing is trained: the components' weights (and a rule's statistics) are copied in, under ``components.<c>.``,
so a mixture checkpoint is self-contained (``python scripts/make_mixture.py``). The components must share the
feature layout, the windows and the normalisation statistics (those of the checkpoint), so their features are the
same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import torch
from torch import nn

from motion2video.models.base import LatentSampler, LossOutput, build_model, register_model

NOT_TRAINED = ("a mixture is composed from trained samplers, not trained: "
               "python scripts/make_mixture.py MODEL MODEL -o OUT.safetensors")


@dataclass(frozen=True)
class MixtureConfig:
    """``components``: each ``{"name": label, "model": registry name, "config": its config dict}``, in the
    order futures are drawn from them; ``shares``: one positive weight per component (empty: equal shares)."""

    feature_dim: int = 51
    components: tuple = field(default_factory=tuple)
    shares: tuple = field(default_factory=tuple)


@register_model("mixture", MixtureConfig, kind="stochastic")
class Mixture(LatentSampler, nn.Module):
    def __init__(self, config: MixtureConfig) -> None:
        super().__init__()
        if len(config.components) < 2:
            raise ValueError(f"a mixture needs at least two components, got {len(config.components)}")
        if any(c["model"] == "mixture" for c in config.components):
            raise ValueError("a mixture's component cannot be a mixture")
        if config.shares and (len(config.shares) != len(config.components) or min(config.shares) <= 0):
            raise ValueError(f"a mixture needs one positive share per component ({len(config.components)}), "
                             f"got {list(config.shares)}")
        self.config = config
        self.components = nn.ModuleList(build_model(c["model"], {**c["config"], "feature_dim": config.feature_dim})
                                        for c in config.components)

    @property
    def names(self) -> list[str]:
        """The components' labels, in drawing order."""
        return [c["name"] for c in self.config.components]

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        raise ValueError(NOT_TRAINED)

    @property
    def shares(self) -> list[float]:
        """The components' shares of the futures, summing to 1."""
        raw = list(self.config.shares) or [1.0] * len(self.components)
        return [float(w) / sum(raw) for w in raw]

    def order(self, num_samples: int) -> list[int]:
        """The component of each of ``num_samples`` futures: the one furthest behind its share (module docstring)."""
        shares, drawn, order = self.shares, [0] * len(self.components), []
        for k in range(num_samples):
            lag = [(k + 1) * w - n for w, n in zip(shares, drawn)]
            c = lag.index(max(lag))
            drawn[c] += 1
            order.append(c)
        return order

    def counts(self, num_samples: int) -> list[int]:
        """How many of ``num_samples`` futures each component draws."""
        order = self.order(num_samples)
        return [order.count(c) for c in range(len(self.components))]

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """(B, To, F) -> (B, K, horizon, F): future k from component ``order(K)[k]``."""
        order = torch.tensor(self.order(num_samples))
        out = obs.new_empty(obs.shape[0], num_samples, horizon, obs.shape[-1])
        for c, model in enumerate(self.components):
            rows = torch.nonzero(order == c).flatten()
            if len(rows):
                out[:, rows] = model.sample(obs, num_samples=len(rows), horizon=horizon, generator=generator)
        return out
