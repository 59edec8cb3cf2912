"""``mixture``: futures drawn in turn from several trained samplers of the same windows (issue 24).

Why: the two best body samplers fail in different places. ``mtvae-add-dlow`` (recurrent decoder) is the better
one on dances and getting up; ``mixer-cvae-dlow`` (anchored DCT mixer decoder) keeps a walker walking, where the
recurrent one slows to a shuffle. A mixture with equal weights, p(future | obs) = sum_c w_c p_c(future | obs),
is itself a conditional generative model, and its K futures cover what either covers
(docs/results.md, "Two samplers in one").

Sampling: future k comes from component ``k mod C`` (so the first C futures show every component, and K = 50
gives each of two components 25). Component c draws its K_c futures (K_c = how many k < K have k mod C = c,
:meth:`Mixture.counts`) with its own rule (a DLow component: its first K_c maps of one shared noise); the components
draw in order from one ``generator``.

Nothing is trained: the components' weights are copied in, under ``components.<c>.``, so a mixture checkpoint
is self-contained (``python scripts/make_mixture.py``). The components must share the feature layout, the
windows and the normalisation statistics (those of the checkpoint), so their features are the same numbers.
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
    order futures are drawn from them."""

    feature_dim: int = 51
    components: tuple = field(default_factory=tuple)


@register_model("mixture", MixtureConfig, kind="stochastic")
class Mixture(LatentSampler, nn.Module):
    def __init__(self, config: MixtureConfig) -> None:
        super().__init__()
        if len(config.components) < 2:
            raise ValueError(f"a mixture needs at least two components, got {len(config.components)}")
        if any(c["model"] == "mixture" for c in config.components):
            raise ValueError("a mixture's component cannot be a mixture")
        self.config = config
        self.components = nn.ModuleList(build_model(c["model"], {**c["config"], "feature_dim": config.feature_dim})
                                        for c in config.components)

    @property
    def names(self) -> list[str]:
        """The components' labels, in drawing order."""
        return [c["name"] for c in self.config.components]

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        raise ValueError(NOT_TRAINED)

    def counts(self, num_samples: int) -> list[int]:
        """How many of ``num_samples`` futures each component draws (future k from component k mod C)."""
        size = len(self.components)
        return [len(range(c, num_samples, size)) for c in range(size)]

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """(B, To, F) -> (B, K, horizon, F): future k from component k mod C."""
        size = len(self.components)
        out = obs.new_empty(obs.shape[0], num_samples, horizon, obs.shape[-1])
        for c, (model, count) in enumerate(zip(self.components, self.counts(num_samples))):
            if count:
                out[:, c::size] = model.sample(obs, num_samples=count, horizon=horizon, generator=generator)
        return out
