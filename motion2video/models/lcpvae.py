"""``lcpvae``: VAE with a Learned Conditional Prior (Aliakbarian et al. 2020, "Contextually plausible and
diverse 3D human motion prediction").

Two autoencoders (Sec. 4, Appendix A/C), all recurrent parts single-layer GRUs:
- CS-VAE on the condition (the observation): h_t = GRU(obs), q(z_c | obs) = N(mu_c, sigma_c^2) (Eq. 3), and
  an observed-motion decoder (initial state tanh(MLP(z_c)), seeded with a zero frame) reconstructing obs;
- LCP-VAE on the data (the future): h_T = GRU(future), (mu, sigma) = MLP([h_T, h_t]) and the extended
  reparameterisation z = mu + sigma * z_c (Eq. 4), so q(z | obs, future) = N(mu + sigma mu_c, (sigma sigma_c)^2);
  the future decoder starts from the last observed frame with initial state tanh(MLP(z)).
At inference z = z_c ~ q(z_c | obs) (Algorithm 2): the CS-VAE posterior is the learned conditional prior.

Loss (Eq. 9): lambda(step) [KL(q(z_c) || N(0, I)) (Eq. 5) + KL(q(z) || q(z_c)) (Eq. 6/7, with the CS-VAE
posterior detached: "frozen" for that term)] + MSE reconstructions of obs and future (Eq. 8, summed).
lambda follows a logistic curve from 0 to ``kl_weight``; both decoders use teacher forcing during training
with probability annealed linearly from 1 to 0 over ``teacher_forcing_steps`` (Appendix C).

Deviations from the paper, on purpose: sigma is parameterised by a log-variance (the paper uses a ReLU on
sigma, which can reach 0 and make the KL infinite); decoders predict residuals; Eq. 7 as printed has a sign
slip (-1/2) and writes Sigma mu_c for sigma * mu_c: :func:`lcp_kl` computes the KL of Eq. 6 exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from motion2video.models.base import LatentPosterior, LatentSampler, LossOutput, register_model
from motion2video.models.blocks import (
    GaussianHead, GRUDecoder, GRUEncoder, kl_diag_gaussians, kl_std_normal, logistic_ramp, motion_stats_error, randn,
    reconstruction_mse, repeat_batch, reparameterize, teacher_forcing_probability,
)
from motion2video.models.base import check_sequences


def lcp_posterior(data: LatentPosterior, cond: LatentPosterior) -> LatentPosterior:
    """The LCP-VAE posterior of Eq. 4, N(mu + sigma mu_c, diag(sigma sigma_c)^2), from the data encoder's
    (mu, sigma) and the CS-VAE posterior (mu_c, sigma_c); all (B, Z)."""
    return LatentPosterior(mu=data.mu + torch.exp(0.5 * data.logvar) * cond.mu, logvar=data.logvar + cond.logvar)


def lcp_kl(data: LatentPosterior, cond: LatentPosterior) -> torch.Tensor:
    """Eq. 6: KL(N(mu + sigma mu_c, (sigma sigma_c)^2) || N(mu_c, sigma_c^2)) per row, (B, Z) -> (B,).

    Equals 1/2 sum_j [-log sigma_j^2 - 1 + sigma_j^2 + (mu_c - mu - sigma mu_c)_j^2 / sigma_c,j^2] (Eq. 7 with
    its sign and sigma/Sigma slips corrected). Pass a detached ``cond`` to freeze CS-VAE for this term.
    """
    return kl_diag_gaussians(lcp_posterior(data, cond), cond)


@dataclass(frozen=True)
class LCPVAEConfig:
    feature_dim: int = 51
    hidden_dim: int = 128
    latent_dim: int = 32
    mlp_dim: int = 128
    kl_weight: float = 1.0  # final lambda
    kl_midpoint: int = 500  # logistic annealing: lambda = kl_weight / (1 + exp(-(step - midpoint) / width))
    kl_width: float = 100.0
    teacher_forcing_steps: int = 1000  # P_tf: 1 -> 0 linearly over these steps
    # Weight of KL(q(z_c | obs) || N(0, I)) relative to the other terms (1 = Eq. 9). The learned prior is
    # what inference samples from; with weight 1 the CS-VAE's observation reconstruction (summed MSE over
    # 16 frames x 51 features) outweighs it and q(z_c | obs) shrinks to sigma_c ~ 0.3: a collapsed sampler
    # (docs/results.md, "LCP-VAE's learned prior"). A larger weight keeps the prior wide.
    cs_kl_weight: float = 1.0
    # Liveliness: weight of :func:`~motion2video.models.blocks.motion_stats_error` on the future
    # reconstruction (0 = the paper's loss, whose summed MSE favours slow, smooth futures).
    motion_stats_weight: float = 0.0


def _mlp(in_dim: int, hidden_dim: int, out_dim: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(in_dim, hidden_dim), nn.ReLU(), nn.Linear(hidden_dim, out_dim))


@register_model("lcpvae", LCPVAEConfig, kind="stochastic")
class LCPVAE(LatentSampler, nn.Module):
    def __init__(self, config: LCPVAEConfig) -> None:
        super().__init__()
        self.config = config
        c = config
        H, Z, M = c.hidden_dim, c.latent_dim, c.mlp_dim
        # CS-VAE (condition = observation)
        self.obs_encoder = GRUEncoder(c.feature_dim, H)
        self.cs_encoder = nn.Sequential(nn.Linear(H, M), nn.ReLU())
        self.cs_head = GaussianHead(M, Z)
        self.cs_decoder = _mlp(Z, M, H)
        self.obs_decoder = GRUDecoder(feature_dim=c.feature_dim, hidden_dim=H)
        # LCP-VAE (data = future)
        self.future_encoder = GRUEncoder(c.feature_dim, H)
        self.lcp_encoder = nn.Sequential(nn.Linear(2 * H, M), nn.ReLU())
        self.lcp_head = GaussianHead(M, Z)
        self.lcp_decoder = _mlp(Z, M, H)
        self.future_decoder = GRUDecoder(feature_dim=c.feature_dim, hidden_dim=H)

    def condition_posterior(self, obs: torch.Tensor) -> tuple[LatentPosterior, torch.Tensor]:
        """CS-VAE posterior q(z_c | obs) (B, Z) and the observation feature h_t (B, H)."""
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        h_t = self.obs_encoder(obs)  # (B, H)
        return self.cs_head(self.cs_encoder(h_t)), h_t

    def data_params(self, h_t: torch.Tensor, future: torch.Tensor) -> LatentPosterior:
        """(mu, log sigma^2) of the LCP-VAE encoder from h_t (B, H) and future (B, Tf, F): (B, Z) each."""
        h_future = self.future_encoder(future)  # (B, H)
        return self.lcp_head(self.lcp_encoder(torch.cat([h_future, h_t], dim=-1)))

    @staticmethod
    def prior_kl(cond: LatentPosterior, data: LatentPosterior) -> tuple[torch.Tensor, torch.Tensor]:
        """Batch means of KL(q(z_c | obs) || N(0, I)) (Eq. 5) and KL(q(z | obs, future) || q(z_c | obs))
        (Eq. 6), the latter with the CS-VAE posterior detached (frozen for that term)."""
        kl_cs = kl_std_normal(cond).mean()
        frozen = LatentPosterior(mu=cond.mu.detach(), logvar=cond.logvar.detach())
        kl_lcp = lcp_kl(data, frozen).mean()
        return kl_cs, kl_lcp

    def encode(self, obs: torch.Tensor, future: torch.Tensor) -> LatentPosterior:
        """q(z | obs, future) = N(mu + sigma mu_c, (sigma sigma_c)^2): mu, logvar (B, Z)."""
        check_sequences(obs, future, feature_dim=self.config.feature_dim)
        cond, h_t = self.condition_posterior(obs)
        return lcp_posterior(self.data_params(h_t, future), cond)

    def decode(self, obs: torch.Tensor, z: torch.Tensor, *, horizon: int) -> torch.Tensor:
        """Future from z, seeded with the last observed frame: obs (B, To, F), z (B, Z) -> (B, horizon, F)."""
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        return self.future_decoder(torch.tanh(self.lcp_decoder(z)), obs[:, -1], horizon=horizon)

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        c = self.config
        check_sequences(obs, future, feature_dim=c.feature_dim)
        p_tf = teacher_forcing_probability(step, steps=c.teacher_forcing_steps)
        cond, h_t = self.condition_posterior(obs)
        z_c = reparameterize(cond, torch.randn_like(cond.mu))  # Eq. 3
        start_token = torch.zeros_like(obs[:, 0])  # the observed-motion decoder's seed frame
        obs_rec = self.obs_decoder(
            torch.tanh(self.cs_decoder(z_c)), start_token, horizon=obs.shape[1], targets=obs, teacher_forcing=p_tf
        )
        data = self.data_params(h_t, future)
        z = data.mu + torch.exp(0.5 * data.logvar) * z_c  # Eq. 4, extended reparameterisation
        fut_rec = self.future_decoder(
            torch.tanh(self.lcp_decoder(z)), obs[:, -1], horizon=future.shape[1], targets=future, teacher_forcing=p_tf
        )
        rec_obs = reconstruction_mse(obs_rec, obs)
        rec_future = reconstruction_mse(fut_rec, future)
        lively = motion_stats_error(fut_rec, future, obs[:, -1]) if c.motion_stats_weight > 0 else fut_rec.new_zeros(())
        kl_cs, kl_lcp = self.prior_kl(cond, data)
        lam = c.kl_weight * logistic_ramp(step, midpoint=c.kl_midpoint, width=c.kl_width)
        total = lam * (c.cs_kl_weight * kl_cs + kl_lcp) + rec_obs + rec_future  # Eq. 9 (cs_kl_weight 1)
        total = total + c.motion_stats_weight * lively
        terms = {
            "recon": float(rec_future.detach()),
            "lively": float(lively.detach()),
            "recon_obs": float(rec_obs.detach()),
            "kl_cs": float(kl_cs.detach()),
            "kl": float(kl_lcp.detach()),
            "kl_weight": lam,
            "teacher_forcing": p_tf,
        }
        return LossOutput(total=total, terms=terms)

    def check_context(self, obs: torch.Tensor) -> None:
        """Checked by :meth:`condition_posterior`."""

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """z = z_c ~ q(z_c | obs): (B*K, horizon, F) (see :class:`~motion2video.models.base.LatentSampler`)."""
        cond, _ = self.condition_posterior(obs)
        K = num_samples
        cond_k = LatentPosterior(mu=repeat_batch(cond.mu, K), logvar=repeat_batch(cond.logvar, K))  # (B*K, Z)
        z = reparameterize(cond_k, randn(tuple(cond_k.mu.shape), like=obs, generator=generator))
        return self.future_decoder(torch.tanh(self.lcp_decoder(z)), repeat_batch(obs[:, -1], K), horizon=horizon)
