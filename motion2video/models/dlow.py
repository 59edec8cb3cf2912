"""``dlow``: a diversity-promoting sampler on top of a trained latent-variable model (Yuan & Kitani, ECCV 2020,
"DLow: Diversifying Latent Flows for Diverse Human Motion Prediction").

A trained stochastic model (here ``mtvae-add``) samples K futures by decoding K independent draws
z ~ N(0, I). Independent draws waste samples: several land on the same mode. DLow keeps the trained model
frozen and learns, per context, K affine maps of ONE shared noise,

    eps ~ N(0, I)   (B, Z),        z_k = a_k(obs) * eps + b_k(obs)   k = 1..K,

so that the K decoded futures together cover the modes. The maps come from a small network on the
observation (GRU -> MLP -> K x (log a_k, b_k)). Training objective on a batch (futures y_k decoded from z_k by
the frozen base model, all in the base model's normalised feature units):

- best-of-K reconstruction: min_k sum_{t,f} (y_k - y)^2 (the DLow paper's "reconstruction" term);
- KL(N(b_k, a_k^2) || N(0, I)), averaged over k: each z_k stays a plausible latent of the base prior;
- diversity: mean over pairs j != k of exp(-D^2_jk / ``div_scale``), with D^2_jk the mean squared feature
  difference of futures j and k, weighted by ``lambda_div``.

Initialisation: the maps start as a stratified copy of the base prior: b_k are fixed, seeded N(0, 0.8^2)
points and a_k = 0.6, so z_k = 0.6 eps + b_k has the prior's unit marginal variance and the K samples start
distinct (identical maps would have zero diversity gradient).

Base models with a learned conditional prior (LCP-VAE's ``condition_posterior(obs)``: N(mu_c, sigma_c^2),
what that model samples from) get the maps in the prior's standardised coordinates,
z_k = mu_c + sigma_c * (a_k * eps + b_k), so the KL term and the initialisation keep z_k a plausible sample of
*that* prior; other bases use N(0, I).

The base model is rebuilt from ``base_model`` / ``base_config`` and its weights live in this model's state dict
under ``base.``, so a DLow checkpoint is self-contained. ``num_samples`` is K; sampling more than K futures
draws another shared noise per K.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import torch
from torch import nn

from motion2video.models.base import LatentSampler, LossOutput, build_model, register_model
from motion2video.models.blocks import GRUEncoder, randn
from motion2video.models.base import check_sequences


@dataclass(frozen=True)
class DLowConfig:
    """``base_model`` / ``base_config``: the frozen model DLow samples from (name and config dict)."""

    feature_dim: int = 51
    base_model: str = "mtvae-add"
    base_config: dict = field(default_factory=dict)
    num_samples: int = 50  # K
    hidden_dim: int = 256
    lambda_kl: float = 1.0
    lambda_div: float = 200.0
    div_scale: float = 0.25
    init_offset_std: float = 0.8
    init_seed: int = 0


def pairwise_diversity(futures: torch.Tensor, *, scale: float) -> torch.Tensor:
    """Mean over ordered pairs j != k of exp(-D^2_jk / scale); futures (B, K, T, F) -> scalar.

    D^2_jk is the mean squared difference of futures j and k over frames and features."""
    B, K = futures.shape[:2]
    flat = futures.reshape(B, K, -1)  # (B, K, T*F)
    d2 = torch.cdist(flat, flat).pow(2) / flat.shape[-1]  # (B, K, K)
    off = ~torch.eye(K, dtype=torch.bool, device=futures.device)
    return torch.exp(-d2 / scale)[:, off].mean()


def best_of_k_sse(futures: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Mean over the batch of min_k sum_{t,f} (futures_k - target)^2; (B, K, T, F), (B, T, F) -> scalar."""
    sse = (futures - target[:, None]).pow(2).sum(dim=(2, 3))  # (B, K)
    return sse.min(dim=1).values.mean()


@register_model("dlow", DLowConfig, kind="stochastic")
class DLow(LatentSampler, nn.Module):
    def __init__(self, config: DLowConfig) -> None:
        super().__init__()
        if config.num_samples < 2:
            raise ValueError(f"num_samples (K) must be >= 2, got {config.num_samples}")
        if config.base_model == "dlow":
            raise ValueError("the base model of dlow cannot be dlow")
        self.config = config
        base_config = {**config.base_config, "feature_dim": config.feature_dim}
        self.base = build_model(config.base_model, base_config)
        if not hasattr(self.base, "decode"):
            raise ValueError(f"base model {config.base_model!r} has no decode(obs, z): DLow needs a latent model")
        for p in self.base.parameters():
            p.requires_grad_(False)
        self.latent_dim = int(self.base.config.latent_dim)
        K, Z, H = config.num_samples, self.latent_dim, config.hidden_dim
        self.obs_encoder = GRUEncoder(config.feature_dim, H)
        self.head = nn.Sequential(nn.Linear(H, H), nn.ReLU(), nn.Linear(H, 2 * K * Z))
        # stratified start: zero weights, biases = (log a_k, b_k) of a prior-matching set of maps
        gen = torch.Generator().manual_seed(config.init_seed)
        offsets = torch.randn(K, Z, generator=gen) * config.init_offset_std
        log_a = torch.full((K, Z), 0.5 * math.log(max(1.0 - config.init_offset_std ** 2, 1e-4)))
        with torch.no_grad():
            self.head[-1].weight.zero_()
            self.head[-1].bias.copy_(torch.cat([log_a, offsets], dim=1).reshape(-1))

    def parameter_groups(self) -> dict[str, list[nn.Parameter]]:
        """Only the maps train; the base model stays frozen."""
        return {"main": [p for n, p in self.named_parameters() if not n.startswith("base.")]}

    def train(self, mode: bool = True) -> "DLow":
        super().train(mode)
        self.base.eval()  # frozen: always in evaluation mode
        return self

    def maps(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(a, b), each (B, K, Z), the affine maps for contexts obs (B, To, F)."""
        B, K, Z = obs.shape[0], self.config.num_samples, self.latent_dim
        out = self.head(self.obs_encoder(obs)).view(B, K, 2, Z)
        return torch.exp(out[:, :, 0].clamp(-8.0, 4.0)), out[:, :, 1]

    def base_prior(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor] | None:
        """(mean, std) (B, Z) of the base model's conditional prior, or None for a N(0, I) prior."""
        if not hasattr(self.base, "condition_posterior"):
            return None
        with torch.no_grad():
            cond, _ = self.base.condition_posterior(obs)
        return cond.mu, torch.exp(0.5 * cond.logvar)

    def latents(self, obs: torch.Tensor, a: torch.Tensor, b: torch.Tensor, eps: torch.Tensor) -> torch.Tensor:
        """z (B, K, Z) from the maps a, b (B, K, Z) and shared noise eps (B, 1, Z) (or (B, R, 1, Z) with a and b
        given as (B, 1, K, Z)), in the base prior's coordinates."""
        z = a * eps + b
        prior = self.base_prior(obs)
        if prior is None:
            return z
        mean, std = prior
        shape = (obs.shape[0],) + (1,) * (z.dim() - 2) + (mean.shape[-1],)
        return mean.view(shape) + std.view(shape) * z

    def _decode_all(self, obs: torch.Tensor, z: torch.Tensor, horizon: int) -> torch.Tensor:
        """Decode z (B, K, Z) for contexts obs (B, To, F) -> (B, K, horizon, F) in one base pass."""
        B, K = z.shape[:2]
        obs_k = obs[:, None].expand(B, K, *obs.shape[1:]).reshape(B * K, *obs.shape[1:])
        return self.base.decode(obs_k, z.reshape(B * K, -1), horizon=horizon).view(B, K, horizon, -1)

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        c = self.config
        check_sequences(obs, future, feature_dim=c.feature_dim)
        a, b = self.maps(obs)  # (B, K, Z)
        eps = torch.randn(obs.shape[0], 1, self.latent_dim, dtype=obs.dtype, device=obs.device)
        z = self.latents(obs, a, b, eps)  # (B, K, Z)
        futures = self._decode_all(obs, z, future.shape[1])  # (B, K, Tf, F)
        recon = best_of_k_sse(futures, future)
        kl = 0.5 * (a.pow(2) + b.pow(2) - 1.0 - 2.0 * torch.log(a)).sum(-1).mean()
        div = pairwise_diversity(futures, scale=c.div_scale)
        total = recon + c.lambda_kl * kl + c.lambda_div * div
        return LossOutput(total=total, terms={"recon": float(recon.detach()), "kl": float(kl.detach()),
                                              "diversity": float(div.detach())})

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """The first ``num_samples`` maps of one shared noise (another noise per further K): (B, num_samples,
        horizon, F), context-major like the B*K rows of :class:`~motion2video.models.base.LatentSampler`."""
        B, K = obs.shape[0], self.config.num_samples
        a, b = self.maps(obs)
        rounds = math.ceil(num_samples / K)
        eps = randn((B, rounds, 1, self.latent_dim), like=obs, generator=generator)  # (B, R, 1, Z)
        z = self.latents(obs, a[:, None], b[:, None], eps).reshape(B, rounds * K, -1)[:, :num_samples]
        return self._decode_all(obs, z, horizon)
