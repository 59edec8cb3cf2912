"""MT-VAE (Yan et al., ECCV 2018): motion transformations in a latent space, ``mtvae-add`` and ``mtvae-concat``.

Four parts (Sec. 3.2-3.3):
1. a sequence encoder f (LSTM with layer norm). One pass over the whole sequence [obs, future]: the motion
   feature e_A is its hidden state after the last observed frame (= f(obs), the encoder is causal) and e_B
   its state after the last future frame (the "full sequence" feature, s(x_{1:T}) in Fig. 2);
2. a latent encoder (three fully-connected layers with a skip connection and layer norm, :class:`SkipMLP`):
   add: z ~ h_{T->z}(e_B - e_A); concat: z ~ h_{e->z}([e_A, e_B]);
3. a latent decoder (same MLP shape): add: e*_B = e_A + h_{z->T}(z, e_A); concat: e*_B = h_{z->e}(z, e_A);
   with ``context_free_decoder`` the latent decoder sees z only (the ablation of Table 3);
4. a sequence decoder g (LSTM with layer norm): state initialised from e*_B, input [e*_B, y_{t-1}] from
   y_0 = x_T (last observed frame), residual output.

Loss (Eq. 5): L1 reconstruction + w(step) KL(q || N(0, I)) (w annealed linearly 0 -> ``kl_weight``)
+ lambda_cycle L_cycle (Eq. 2/3: ||z* - z||_2 with z ~ N(0, I) and z* the latent-encoder mean of the
decoded transformation) + lambda_motion L_motion (Eq. 4: mean over the first K steps of the Euclidean norm of
the velocity difference between a prior sample's decoding and the ground truth, v_1 = y_1 - x_T).
Defaults follow the paper's best settings: K = 8, lambda_cycle = 5, lambda_motion = 5 (add) / 20 (concat).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from motion2video.models.base import LatentPosterior, LatentSampler, LossOutput, register_model
from motion2video.models.blocks import (
    LSTMDecoder, LSTMEncoder, SkipMLP, kl_std_normal, linear_ramp, motion_stats_error, randn, reconstruction_l1,
    repeat_batch, reparameterize,
)
from motion2video.models.base import check_sequences


def cycle_consistency(z_star: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
    """Eq. 2/3: mean over the batch of ||z* - z||_2; (B, Z) x 2 -> scalar."""
    return (z_star - z).norm(dim=-1).mean()


def motion_coherence(pred: torch.Tensor, target: torch.Tensor, *, last_obs: torch.Tensor, steps: int) -> torch.Tensor:
    """Eq. 4: (1/K) sum_{t<=K} ||v*_t - v_t||_2, averaged over the batch.

    pred, target (B, T, F) (T >= 1; only the first min(K, T) frames are used), last_obs (B, F) = x_T.
    Velocities: v_1 = y_1 - x_T, v_k = y_k - y_{k-1}.
    """
    k = min(steps, pred.shape[1], target.shape[1])
    prev_pred = torch.cat([last_obs[:, None], pred[:, : k - 1]], dim=1)  # (B, K, F)
    prev_true = torch.cat([last_obs[:, None], target[:, : k - 1]], dim=1)  # (B, K, F)
    v_pred = pred[:, :k] - prev_pred
    v_true = target[:, :k] - prev_true
    return (v_pred - v_true).norm(dim=-1).mean()


@dataclass(frozen=True)
class MTVAEConfig:
    """``transform``: "add" (MT-VAE add, Fig. 2d) or "concat" (Fig. 2c)."""

    feature_dim: int = 51
    hidden_dim: int = 128  # N_e, the motion-feature size
    latent_dim: int = 32  # N_z
    mlp_dim: int = 128
    layer_norm: bool = True
    transform: str = "add"
    context_free_decoder: bool = False
    kl_weight: float = 1.0
    kl_anneal_steps: int = 1000
    lambda_cycle: float = 5.0
    lambda_motion: float = 5.0
    coherence_steps: int = 8
    # Liveliness: weight of :func:`~motion2video.models.blocks.motion_stats_error` on the
    # reconstruction (generated vs true mean absolute velocity and acceleration per feature). 0 = the paper's
    # loss; the L1 reconstruction alone is minimised by futures slower and smoother than real motion.
    motion_stats_weight: float = 0.0
    # The sequence decoder also reads the last step's velocity, from the observed one on (without it
    # the first future frames were as far off as standing still). False = the paper's decoder input.
    velocity_input: bool = False


@dataclass(frozen=True)
class MTVAEConcatConfig(MTVAEConfig):
    transform: str = "concat"
    lambda_motion: float = 20.0


class MTVAE(LatentSampler, nn.Module):
    """Shared implementation; registered as ``mtvae-add`` (:class:`MTVAEAdd`) and ``mtvae-concat``."""

    def __init__(self, config: MTVAEConfig) -> None:
        super().__init__()
        if config.transform not in ("add", "concat"):
            raise ValueError(f"transform must be 'add' or 'concat', got {config.transform!r}")
        self.config = config
        c = config
        H, Z = c.hidden_dim, c.latent_dim
        self.encoder = LSTMEncoder(c.feature_dim, H, layer_norm=c.layer_norm)
        enc_in = H if c.transform == "add" else 2 * H
        dec_in = Z if c.context_free_decoder else Z + H
        self.latent_encoder = SkipMLP(enc_in, 2 * Z, hidden_dim=c.mlp_dim)
        self.latent_decoder = SkipMLP(dec_in, H, hidden_dim=c.mlp_dim)
        self.decoder = LSTMDecoder(feature_dim=c.feature_dim, cond_dim=H, hidden_dim=H, layer_norm=c.layer_norm,
                                   velocity_input=c.velocity_input)

    # -- latent mappings -------------------------------------------------------------------------

    def _posterior_from_features(self, e_a: torch.Tensor, e_b: torch.Tensor) -> LatentPosterior:
        x = e_b - e_a if self.config.transform == "add" else torch.cat([e_a, e_b], dim=-1)
        mu, logvar = self.latent_encoder(x).chunk(2, dim=-1)  # (B, Z) each
        return LatentPosterior(mu=mu, logvar=logvar.clamp(-12.0, 8.0))

    def _future_feature(self, e_a: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        """e*_B from e_A (B, H) and z (B, Z)."""
        x = z if self.config.context_free_decoder else torch.cat([z, e_a], dim=-1)
        out = self.latent_decoder(x)  # (B, H)
        return e_a + out if self.config.transform == "add" else out

    def _decode_sequence(self, e_b_star: torch.Tensor, obs: torch.Tensor, horizon: int) -> torch.Tensor:
        """The sequence decoder g from e*_B (B, H), seeded with the last observed frames of obs (B, To, F)."""
        previous = obs[:, -2] if obs.shape[1] > 1 else obs[:, -1]  # one observed frame: velocity 0
        return self.decoder(e_b_star, obs[:, -1], horizon=horizon, previous_input=previous)

    def _cycle_latent(self, e_a: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        """z* of Eq. 2/3: the latent-encoder mean of the transformation decoded from z."""
        e_b_star = self._future_feature(e_a, z)
        return self._posterior_from_features(e_a, e_b_star).mu

    # -- public API ------------------------------------------------------------------------------

    def features(self, obs: torch.Tensor, future: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(e_A, e_B), each (B, H), from one encoder pass over [obs, future]."""
        states = self.encoder(torch.cat([obs, future], dim=1))  # (B, To+Tf, H)
        return states[:, obs.shape[1] - 1], states[:, -1]

    def encode(self, obs: torch.Tensor, future: torch.Tensor) -> LatentPosterior:
        """q(z | obs, future): obs (B, To, F), future (B, Tf, F) -> mu, logvar (B, Z)."""
        check_sequences(obs, future, feature_dim=self.config.feature_dim)
        return self._posterior_from_features(*self.features(obs, future))

    def decode(self, obs: torch.Tensor, z: torch.Tensor, *, horizon: int) -> torch.Tensor:
        """The future of ``obs`` under transformation z: obs (B, To, F), z (B, Z) -> (B, horizon, F)."""
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        e_a = self.encoder(obs)[:, -1]  # (B, H)
        return self._decode_sequence(self._future_feature(e_a, z), obs, horizon)

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        c = self.config
        check_sequences(obs, future, feature_dim=c.feature_dim)
        B, Tf = future.shape[0], future.shape[1]
        last = obs[:, -1]  # (B, F)
        e_a, e_b = self.features(obs, future)
        post = self._posterior_from_features(e_a, e_b)
        z = reparameterize(post, torch.randn_like(post.mu))
        pred = self._decode_sequence(self._future_feature(e_a, z), obs, Tf)  # (B, Tf, F)
        recon = reconstruction_l1(pred, future)
        lively = motion_stats_error(pred, future, last) if c.motion_stats_weight > 0 else pred.new_zeros(())
        kl = kl_std_normal(post).mean()
        w = c.kl_weight * linear_ramp(step, length=c.kl_anneal_steps)

        # cycle consistency (Eq. 2/3) with z ~ N(0, I)
        z_prior = torch.randn(B, c.latent_dim, dtype=obs.dtype, device=obs.device)
        cycle = cycle_consistency(self._cycle_latent(e_a, z_prior), z_prior)

        # motion coherence (Eq. 4): decode only the first K steps of another prior sample
        k = min(c.coherence_steps, Tf)
        z_motion = torch.randn(B, c.latent_dim, dtype=obs.dtype, device=obs.device)
        pred_prior = self._decode_sequence(self._future_feature(e_a, z_motion), obs, k)  # (B, K, F)
        motion = motion_coherence(pred_prior, future, last_obs=last, steps=k)

        total = recon + w * kl + c.lambda_cycle * cycle + c.lambda_motion * motion + c.motion_stats_weight * lively
        terms = {
            "recon": float(recon.detach()),
            "lively": float(lively.detach()),
            "kl": float(kl.detach()),
            "kl_weight": w,
            "cycle": float(cycle.detach()),
            "motion": float(motion.detach()),
        }
        return LossOutput(total=total, terms=terms)

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """z ~ N(0, I): (B*K, horizon, F) (see :class:`~motion2video.models.base.LatentSampler`)."""
        B, K = obs.shape[0], num_samples
        e_a = repeat_batch(self.encoder(obs)[:, -1], K)  # (B*K, H)
        z = randn((B * K, self.config.latent_dim), like=obs, generator=generator)  # (B*K, Z)
        return self._decode_sequence(self._future_feature(e_a, z), repeat_batch(obs[:, -2:], K), horizon)


@register_model("mtvae-add", MTVAEConfig, kind="stochastic")
class MTVAEAdd(MTVAE):
    """MT-VAE (add): z from e_B - e_A, e*_B = e_A + h_{z->T}(z, e_A)."""

    def __init__(self, config: MTVAEConfig) -> None:
        if config.transform != "add":
            raise ValueError(f"mtvae-add needs transform='add', got {config.transform!r}")
        super().__init__(config)


@register_model("mtvae-concat", MTVAEConcatConfig, kind="stochastic")
class MTVAEConcat(MTVAE):
    """MT-VAE (concat): z from [e_A, e_B], e*_B = h_{z->e}(z, e_A)."""

    def __init__(self, config: MTVAEConfig) -> None:
        if config.transform != "concat":
            raise ValueError(f"mtvae-concat needs transform='concat', got {config.transform!r}")
        super().__init__(config)
