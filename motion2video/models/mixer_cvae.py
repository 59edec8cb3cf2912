"""``mixer-cvae``: a conditional VAE whose decoder is ``mixer-dct``'s DCT MLP-mixer.

Why: the recurrent decoders of MT-VAE / LCP-VAE draw a held-out future poorly even from the latent of its own
recognition model (docs/results.md, "More futures, and what limits the forecast"), so no sampler over them
reaches the forecasting targets. This model keeps the latent-variable interface (``encode`` / ``decode``, so DLow
samples it like ``mtvae-add``: ``motion2video train --model dlow --base mixer-cvae.safetensors``) and replaces the
decoder with the representation and backbone of the 2023-2026 forecasters.

Representation (as :mod:`motion2video.models.mixer`): the ``observed`` frames padded with the last observed
frame x_T, minus x_T, projected on the first ``num_coeffs`` DCT-II vectors of the window length L:
c_pad = D (pad(obs) - x_T)  (Nc, F). The true window [obs, future] - x_T gives c_true = D (window - x_T).

- context: c_pad embedded to ``hidden_dim`` channels per coefficient (token), ``context_blocks`` mixer blocks
  -> h (Nc, C);
- recognition model q(z | obs, future): c_true embedded, added to h, ``encoder_blocks`` mixer blocks, mean
  over the tokens, a linear Gaussian head -> mu, logvar (Z);
- decoder p(future | obs, z): h through ``decoder_blocks`` mixer blocks, each modulated by z through a FiLM
  scale and shift of its channels, a linear head to a correction of c_pad (zero at initialisation, so the
  untrained decoder is zero-velocity), then back through D^T and + x_T.

Loss on a batch (per-frame error = Euclidean norm over the F features scaled by ``feature_scale``: metres, as
``evaluate`` measures, when it holds the training set's standard deviations, as ``motion2video train`` sets it):
the mean per-frame error of the decoded future + ``fde_weight`` x its final-frame error + ``observed_weight`` x
the mean per-frame error of the decoded observed frames, + w(step) x KL(q || p) with w rising linearly to
``kl_weight`` over ``kl_anneal_steps``, + ``stats_weight`` x the liveliness error of a prior sample's future
(:func:`~motion2video.models.blocks.motion_stats_error`: mean absolute velocity and acceleration against the
truth's, so that prior samples move like real motion).

The prior p: N(0, I), or with ``learned_prior`` a condition-dependent Gaussian p(z | obs) = N(mu_c, sigma_c^2)
read from the context tokens (mean over tokens, a linear head), trained by that same KL term (the CVAE of Sohn et
al. 2015, the idea of LCP-VAE): with a weak KL weight the posteriors of one context sit in a small part of
N(0, I), and a learned prior samples there. ``condition_posterior(obs)`` gives it (N(0, I) without one), which is
how DLow finds it: its maps then work in the prior's standardised coordinates. Measured (docs/results.md, "A
decoder that draws held-out futures"): no better than N(0, I) under DLow, so it is off in the shipped model.

Horizons longer than ``future`` are decoded in chunks, each chunk continuing from its own last ``observed``
frames with the same z; a future passed to ``encode`` is cut or padded (last frame repeated) to ``future``
frames; observations shorter than ``observed`` are padded with their first frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import torch
from torch import nn

from motion2video.models.base import LatentPosterior, LatentSampler, LossOutput, check_sequences, register_model
from motion2video.models.blocks import (
    kl_diag_gaussians, kl_std_normal, linear_ramp, motion_stats_error, randn, reparameterize,
)
from motion2video.models.mixer import MixerBlock, anchored_coefficients, check_window_config, dct_basis, fit_context


@dataclass(frozen=True)
class MixerCVAEConfig:
    """Sizes and loss weights of :class:`MixerCVAE` (see the module docstring)."""

    feature_dim: int = 51
    observed: int = 16
    future: int = 48
    num_coeffs: int = 32
    hidden_dim: int = 128
    expansion: int = 2
    context_blocks: int = 4
    encoder_blocks: int = 2
    decoder_blocks: int = 4
    latent_dim: int = 32
    kl_weight: float = 0.01
    kl_anneal_steps: int = 1000
    fde_weight: float = 0.5
    observed_weight: float = 0.1
    stats_weight: float = 0.0
    learned_prior: bool = False
    # Per-feature scale of the errors (F numbers; the training set's standard deviations, filled in by
    # :func:`motion2video.models.training.train_model`): errors then are metres. Empty: normalised units.
    feature_scale: list = field(default_factory=list)

    def __post_init__(self) -> None:
        check_window_config(self)
        if min(self.hidden_dim, self.latent_dim, self.context_blocks, self.decoder_blocks) < 1:
            raise ValueError("hidden_dim, latent_dim, context_blocks and decoder_blocks must be >= 1")


def fit_future(future: torch.Tensor, length: int) -> torch.Tensor:
    """(B, Tf, F) -> (B, length, F): the first ``length`` frames, the last frame repeated if shorter."""
    if future.shape[1] >= length:
        return future[:, :length]
    return torch.cat([future, future[:, -1:].expand(-1, length - future.shape[1], -1)], dim=1)


@register_model("mixer-cvae", MixerCVAEConfig, kind="stochastic")
class MixerCVAE(LatentSampler, nn.Module):
    def __init__(self, config: MixerCVAEConfig) -> None:
        super().__init__()
        self.config = c = config
        self.register_buffer("basis", dct_basis(c.observed + c.future, c.num_coeffs), persistent=False)  # (Nc, L)
        scale = torch.tensor(c.feature_scale or [1.0] * c.feature_dim, dtype=torch.float32)
        self.register_buffer("scale", scale, persistent=False)  # (F,)
        C, Nc = c.hidden_dim, c.num_coeffs

        def blocks(n: int) -> nn.ModuleList:
            return nn.ModuleList([MixerBlock(tokens=Nc, channels=C, expansion=c.expansion) for _ in range(n)])

        self.embed = nn.Linear(c.feature_dim, C)
        self.position = nn.Parameter(torch.zeros(Nc, C))
        self.context = blocks(c.context_blocks)
        self.embed_true = nn.Linear(c.feature_dim, C)
        self.encoder = blocks(c.encoder_blocks)
        self.posterior_head = nn.Sequential(nn.LayerNorm(C), nn.Linear(C, 2 * c.latent_dim))
        self.prior_head = nn.Sequential(nn.LayerNorm(C), nn.Linear(C, 2 * c.latent_dim)) if c.learned_prior else None
        self.decoder = blocks(c.decoder_blocks)
        self.film = nn.ModuleList([nn.Linear(c.latent_dim, 2 * C) for _ in range(c.decoder_blocks)])
        self.out_norm = nn.LayerNorm(C)
        self.head = nn.Linear(C, c.feature_dim)
        with torch.no_grad():  # start as zero-velocity: no correction of the padded window's coefficients
            self.head.weight.zero_()
            self.head.bias.zero_()

    # -- pieces ----------------------------------------------------------------------------------

    def _context(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """obs (B, To, F) -> (h (B, Nc, C), c_pad (B, Nc, F), the anchor x_T (B, F))."""
        c_pad, last = anchored_coefficients(obs, self.basis, observed=self.config.observed, future=self.config.future)
        h = self.embed(c_pad) + self.position
        for block in self.context:
            h = block(h)
        return h, c_pad, last

    def _posterior(self, h: torch.Tensor, obs: torch.Tensor, future: torch.Tensor, last: torch.Tensor
                   ) -> LatentPosterior:
        """q(z | obs, future) from the context tokens h (B, Nc, C) and the true window."""
        window = torch.cat([fit_context(obs, self.config.observed), fit_future(future, self.config.future)], dim=1)
        c_true = torch.einsum("kl,blf->bkf", self.basis, window - last[:, None])  # (B, Nc, F)
        g = h + self.embed_true(c_true)
        for block in self.encoder:
            g = block(g)
        mu, logvar = self.posterior_head(g.mean(dim=1)).chunk(2, dim=-1)
        return LatentPosterior(mu=mu, logvar=logvar.clamp(-12.0, 8.0))

    def _prior(self, h: torch.Tensor) -> LatentPosterior:
        """p(z | obs) from the context tokens h (B, Nc, C): the learned prior, or N(0, I)."""
        if self.prior_head is None:
            zeros = h.new_zeros(h.shape[0], self.config.latent_dim)
            return LatentPosterior(mu=zeros, logvar=zeros)
        mu, logvar = self.prior_head(h.mean(dim=1)).chunk(2, dim=-1)
        return LatentPosterior(mu=mu, logvar=logvar.clamp(-12.0, 8.0))

    def _window(self, h: torch.Tensor, c_pad: torch.Tensor, last: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        """The decoded window (B, L, F) (observed part and future) for latents z (B, Z)."""
        for block, film in zip(self.decoder, self.film):
            h = block(h, film(z).chunk(2, dim=-1))
        coeffs = c_pad + self.head(self.out_norm(h))  # (B, Nc, F)
        return torch.einsum("kl,bkf->blf", self.basis, coeffs) + last[:, None]

    # -- public API ------------------------------------------------------------------------------

    def encode(self, obs: torch.Tensor, future: torch.Tensor) -> LatentPosterior:
        """q(z | obs, future): obs (B, To, F), future (B, Tf, F) -> mu, logvar (B, Z)."""
        check_sequences(obs, future, feature_dim=self.config.feature_dim)
        h, _, last = self._context(obs)
        return self._posterior(h, obs, future, last)

    def condition_posterior(self, obs: torch.Tensor) -> tuple[LatentPosterior, torch.Tensor]:
        """The prior p(z | obs) (B, Z) (N(0, I) without ``learned_prior``) and the pooled context (B, C)."""
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        h, _, _ = self._context(obs)
        return self._prior(h), h.mean(dim=1)

    def decode(self, obs: torch.Tensor, z: torch.Tensor, *, horizon: int) -> torch.Tensor:
        """The future of ``obs`` under latent z: obs (B, To, F), z (B, Z) -> (B, horizon, F)."""
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        c = self.config
        history, pieces, done = fit_context(obs, c.observed), [], 0
        while done < horizon:
            h, c_pad, last = self._context(history[:, -c.observed:])
            nxt = self._window(h, c_pad, last, z)[:, c.observed:]  # (B, Tf, F)
            pieces.append(nxt)
            history = torch.cat([history, nxt], dim=1)
            done += c.future
        return torch.cat(pieces, dim=1)[:, :horizon]

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        c = self.config
        check_sequences(obs, future, feature_dim=c.feature_dim)
        if future.shape[1] != c.future:
            raise ValueError(f"mixer-cvae trains on {c.future} future frames, got {future.shape[1]}")
        h, c_pad, last = self._context(obs)
        post = self._posterior(h, obs, future, last)
        z = reparameterize(post, torch.randn_like(post.mu))
        window = self._window(h, c_pad, last, z)  # (B, L, F)
        fut, past = window[:, c.observed:], window[:, : c.observed]
        err = ((fut - future) * self.scale).pow(2).sum(-1).add(1e-8).sqrt()  # (B, Tf) metres per frame
        recon = err.mean() + c.fde_weight * err[:, -1].mean()
        ctx = fit_context(obs, c.observed)
        past_err = ((past - ctx) * self.scale).pow(2).sum(-1).add(1e-8).sqrt().mean()
        prior = self._prior(h)
        kl = kl_diag_gaussians(post, prior).mean() if self.prior_head is not None else kl_std_normal(post).mean()
        w = c.kl_weight * linear_ramp(step, length=c.kl_anneal_steps)
        if c.stats_weight > 0:  # a prior sample must move like real motion
            z_prior = reparameterize(prior, torch.randn_like(post.mu))
            prior_fut = self._window(h, c_pad, last, z_prior)[:, c.observed:]
            stats = motion_stats_error(prior_fut * self.scale, future * self.scale, last * self.scale)
        else:
            stats = fut.new_zeros(())
        total = recon + c.observed_weight * past_err + w * kl + c.stats_weight * stats
        return LossOutput(total=total, terms={"recon": float(recon.detach()), "past": float(past_err.detach()),
                                              "kl": float(kl.detach()), "kl_weight": w,
                                              "stats": float(stats.detach())})

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """z from the prior: (B*K, horizon, F), context-major (see :class:`~motion2video.models.base.LatentSampler`)."""
        B, K = obs.shape[0], num_samples
        obs_k = fit_context(obs, self.config.observed).repeat_interleave(K, dim=0)  # (B*K, To, F)
        prior, _ = self.condition_posterior(obs_k)
        eps = randn((B * K, self.config.latent_dim), like=obs, generator=generator)
        z = reparameterize(prior, eps)
        return self.decode(obs_k, z, horizon=horizon)
