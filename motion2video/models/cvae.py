"""``cvae``: the vanilla conditional VAE baseline of MT-VAE (Sec. 3.1, Fig. 2b, Eq. 1).

- recognition model q(z | obs, future): an LSTM over the whole sequence [obs, future], a linear Gaussian head;
- prior p(z) = N(0, I);
- generator p(future | obs, z): the obs feature e_A = f(obs) (LSTM) and z, concatenated, condition the
  residual LSTM decoder that starts from the last observed frame.

Loss: L1 reconstruction (summed over the sequence) + w(step) * KL(q || N(0, I)), with w annealed linearly
from 0 to ``kl_weight`` over ``kl_anneal_steps`` (KL annealing, as in MT-VAE's experiments).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from motion2video.models.base import LatentPosterior, LatentSampler, LossOutput, register_model
from motion2video.models.blocks import (
    GaussianHead, LSTMDecoder, LSTMEncoder, kl_std_normal, linear_ramp, randn, reconstruction_l1, repeat_batch,
    reparameterize,
)
from motion2video.models.base import check_sequences


@dataclass(frozen=True)
class CVAEConfig:
    feature_dim: int = 51
    hidden_dim: int = 128
    latent_dim: int = 32
    layer_norm: bool = True
    kl_weight: float = 1.0  # final weight of the KL term
    kl_anneal_steps: int = 1000  # linear 0 -> kl_weight


@register_model("cvae", CVAEConfig, kind="stochastic")
class CVAE(LatentSampler, nn.Module):
    def __init__(self, config: CVAEConfig) -> None:
        super().__init__()
        self.config = config
        c = config
        self.obs_encoder = LSTMEncoder(c.feature_dim, c.hidden_dim, layer_norm=c.layer_norm)
        self.posterior_encoder = LSTMEncoder(c.feature_dim, c.hidden_dim, layer_norm=c.layer_norm)
        self.posterior_head = GaussianHead(c.hidden_dim, c.latent_dim)
        self.decoder = LSTMDecoder(
            feature_dim=c.feature_dim,
            cond_dim=c.hidden_dim + c.latent_dim,
            hidden_dim=c.hidden_dim,
            layer_norm=c.layer_norm,
        )

    def encode(self, obs: torch.Tensor, future: torch.Tensor) -> LatentPosterior:
        """q(z | obs, future): obs (B, To, F), future (B, Tf, F) -> mu, logvar (B, Z)."""
        check_sequences(obs, future, feature_dim=self.config.feature_dim)
        h = self.posterior_encoder(torch.cat([obs, future], dim=1))[:, -1]  # (B, H)
        return self.posterior_head(h)

    def _decode_from_feature(
        self, e_a: torch.Tensor, z: torch.Tensor, *, last: torch.Tensor, horizon: int
    ) -> torch.Tensor:
        return self.decoder(torch.cat([e_a, z], dim=-1), last, horizon=horizon)  # (B, horizon, F)

    def decode(self, obs: torch.Tensor, z: torch.Tensor, *, horizon: int) -> torch.Tensor:
        """p(future | obs, z): obs (B, To, F), z (B, Z) -> (B, horizon, F)."""
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        e_a = self.obs_encoder(obs)[:, -1]  # (B, H)
        return self._decode_from_feature(e_a, z, last=obs[:, -1], horizon=horizon)

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        c = self.config
        post = self.encode(obs, future)
        z = reparameterize(post, torch.randn_like(post.mu))
        pred = self.decode(obs, z, horizon=future.shape[1])
        recon = reconstruction_l1(pred, future)
        kl = kl_std_normal(post).mean()
        w = c.kl_weight * linear_ramp(step, length=c.kl_anneal_steps)
        total = recon + w * kl
        return LossOutput(
            total=total, terms={"recon": float(recon.detach()), "kl": float(kl.detach()), "kl_weight": w}
        )

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """z ~ N(0, I): (B*K, horizon, F) (see :class:`~motion2video.models.base.LatentSampler`)."""
        B, K = obs.shape[0], num_samples
        e_a = repeat_batch(self.obs_encoder(obs)[:, -1], K)  # (B*K, H)
        last = repeat_batch(obs[:, -1], K)  # (B*K, F)
        z = randn((B * K, self.config.latent_dim), like=obs, generator=generator)  # (B*K, Z)
        return self._decode_from_feature(e_a, z, last=last, horizon=horizon)  # (B*K, horizon, F)
