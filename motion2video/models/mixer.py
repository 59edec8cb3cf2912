"""``mixer-dct``: a stochastic forecaster built like the 2023-2026 methods: a DCT representation
anchored at the last observed pose, an MLP-mixer over DCT coefficients and joint features, and a noise
sampler trained for best-of-K coverage.

Representation (HumanMAC / CoMusion / siMLPe). The window of ``observed`` + ``future`` frames is the observed
frames followed by the last observed frame repeated; the last observed frame is subtracted from every frame
(so the future part is all zero: "the body stays where it is", the zero-velocity forecast) and the sequence
is projected on the first ``num_coeffs`` vectors of the orthonormal DCT-II basis of the window length L:

    c = D r        D (Nc, L),  r (L, F)  ->  c (Nc, F)

The network predicts corrected coefficients c' = c + f(c, z); the future is x_T + (D^T c')[To:]. With f = 0 the
model is exactly zero-velocity, and a truncated cosine basis keeps the predicted future continuous with the
observed past (the first future frame is pulled to where the observed motion is heading).

Backbone (siMLPe-style mixer, :class:`MixerBlock`): the Nc coefficients are the tokens, each embedded from the
F joint features to ``hidden_dim`` channels. A block is LayerNorm -> a fully-connected layer across the tokens
(time mixing), residual; LayerNorm -> a two-layer MLP across the channels (joint mixing), residual.
``context_blocks`` blocks run once per observation; ``sample_blocks`` blocks run once per sample, each
modulated by the sample's noise z ~ N(0, I) (``noise_dim``) through a FiLM scale and shift of its channels.

Training objective on a batch (per-frame error = Euclidean norm over the F features, each scaled by
``feature_scale``: metres when it holds the training set's standard deviations, as ``motion2video train``
sets it), with K = ``train_samples`` futures per window drawn from K independent noises:

- best-of-K: min over k of (mean per-frame error over the future + ``fde_weight`` x final-frame error)
  (the multiple-hypothesis / best-of-many loss: only the closest sample is pulled to the truth, so the K
  samples spread over the futures a context allows);
- ``observed_weight`` x the mean per-frame error of every sample's reconstruction of the observed frames
  (the coefficients must describe the past they continue);
- ``early_weight`` x the mean per-frame error of EVERY sample over the first ``early_frames`` future frames
  (the next 0.16 s follow from the observed velocity whatever happens later; without it the best-of-K loss
  leaves the first frames of the other samples free, and the first frame's best-of-50 error stayed above the
  constant-velocity forecast's; MT-VAE's motion-coherence term does the same for its samples);
- ``stats_weight`` x :func:`~motion2video.models.blocks.motion_stats_error` of every sample against the
  truth (mean absolute velocity and acceleration per feature): samples that do not win must still move
  like real motion, neither frozen nor jittering;
- ``diversity_weight`` x the mean over sample pairs of exp(-D^2 / ``diversity_scale``) (DLow's term, D^2 the
  mean squared feature difference of two futures).

Horizons longer than ``future`` are sampled autoregressively (each sample continues from its own last
``observed`` frames); observations shorter than ``observed`` are padded with their first frame, longer ones
are read from their last ``observed`` frames.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import torch
from torch import nn

from motion2video.models.base import LatentSampler, LossOutput, register_model
from motion2video.models.base import check_sequences
from motion2video.models.blocks import motion_stats_error, randn


@dataclass(frozen=True)
class MixerDCTConfig:
    """Sizes and loss weights of :class:`MixerDCT` (see the module docstring)."""

    feature_dim: int = 51
    observed: int = 16
    future: int = 48
    num_coeffs: int = 32
    hidden_dim: int = 128
    expansion: int = 2
    context_blocks: int = 4
    sample_blocks: int = 4
    noise_dim: int = 32
    train_samples: int = 16
    fde_weight: float = 0.5
    observed_weight: float = 0.1
    stats_weight: float = 1.0
    diversity_weight: float = 0.0
    diversity_scale: float = 1.0
    early_frames: int = 4
    early_weight: float = 1.0
    # Per-feature scale of the errors (F numbers; the training set's standard deviations, filled in by
    # :func:`motion2video.models.training.train_model`): the best-of-K and observed errors are then measured in
    # metres, as ``evaluate`` measures them, instead of in normalised units. Empty: normalised units.
    feature_scale: list = field(default_factory=list)

    def __post_init__(self) -> None:
        check_window_config(self)
        if self.train_samples < 1 or self.noise_dim < 1 or self.hidden_dim < 1:
            raise ValueError("train_samples, noise_dim and hidden_dim must be >= 1")


def check_window_config(config) -> None:
    """The checks every anchored-DCT config shares (``feature_dim``, ``observed``, ``future``, ``num_coeffs``,
    ``feature_scale``): raise ValueError on the first that fails."""
    c = config
    if c.feature_scale and len(c.feature_scale) != c.feature_dim:
        raise ValueError(f"feature_scale needs {c.feature_dim} numbers, got {len(c.feature_scale)}")
    if c.observed < 2 or c.future < 1:
        raise ValueError(f"need observed >= 2 and future >= 1, got {c.observed}, {c.future}")
    if not 1 <= c.num_coeffs <= c.observed + c.future:
        raise ValueError(f"num_coeffs must be in [1, observed + future], got {c.num_coeffs}")


def dct_basis(length: int, count: int) -> torch.Tensor:
    """The first ``count`` vectors of the orthonormal DCT-II basis of ``length`` samples: (count, length);
    ``D @ D.T = I`` (count x count), and ``D.T @ D`` projects on the lowest ``count`` frequencies."""
    n = torch.arange(length, dtype=torch.float64)
    k = torch.arange(count, dtype=torch.float64)[:, None]
    basis = torch.cos(math.pi * (n + 0.5) * k / length) * math.sqrt(2.0 / length)
    basis[0] /= math.sqrt(2.0)
    return basis.float()


def pad_with_last(obs: torch.Tensor, future: int) -> torch.Tensor:
    """(B, To, F) -> (B, To + future, F): the observed frames, then the last one repeated."""
    return torch.cat([obs, obs[:, -1:].expand(-1, future, -1)], dim=1)


def fit_context(obs: torch.Tensor, length: int) -> torch.Tensor:
    """(B, To, F) -> (B, length, F): the last ``length`` frames, left-padded with the first frame if shorter."""
    if obs.shape[1] >= length:
        return obs[:, obs.shape[1] - length:]
    return torch.cat([obs[:, :1].expand(-1, length - obs.shape[1], -1), obs], dim=1)


def anchored_coefficients(obs: torch.Tensor, basis: torch.Tensor, *, observed: int, future: int
                          ) -> tuple[torch.Tensor, torch.Tensor]:
    """obs (B, To, F) -> (DCT coefficients (B, Nc, F) of the last ``observed`` frames padded with the last one to
    ``observed + future`` frames, minus that anchor; the anchor x_T (B, F)); ``basis`` (Nc, observed + future)."""
    ctx = fit_context(obs, observed)
    last = ctx[:, -1]  # (B, F)
    window = pad_with_last(ctx, future) - last[:, None]  # (B, L, F)
    return torch.einsum("kl,blf->bkf", basis, window), last


def pairwise_similarity(futures: torch.Tensor, *, scale: float) -> torch.Tensor:
    """Mean over ordered pairs j != k of exp(-D^2_jk / scale); futures (B, K, T, F) -> scalar (0 for K = 1).
    D^2_jk is the mean squared difference of futures j and k over frames and features."""
    B, K = futures.shape[:2]
    if K < 2:
        return futures.new_zeros(())
    flat = futures.reshape(B, K, -1)  # (B, K, T*F)
    d2 = torch.cdist(flat, flat).pow(2) / flat.shape[-1]  # (B, K, K)
    off = ~torch.eye(K, dtype=torch.bool, device=futures.device)
    return torch.exp(-d2 / scale)[:, off].mean()


class MixerBlock(nn.Module):
    """Token (DCT coefficient) mixing then channel (joint feature) mixing, pre-LayerNorm, residual; an
    optional FiLM (scale, shift) of the normalised channels before the token mixing."""

    def __init__(self, *, tokens: int, channels: int, expansion: int) -> None:
        super().__init__()
        self.norm_tokens = nn.LayerNorm(channels)
        self.token_fc = nn.Linear(tokens, tokens)
        self.norm_channels = nn.LayerNorm(channels)
        self.channel_mlp = nn.Sequential(nn.Linear(channels, expansion * channels), nn.GELU(),
                                         nn.Linear(expansion * channels, channels))

    def forward(self, x: torch.Tensor, film: tuple[torch.Tensor, torch.Tensor] | None = None) -> torch.Tensor:
        """x (N, Nc, C); film: (scale, shift), each (N, C) -> (N, Nc, C)."""
        h = self.norm_tokens(x)
        if film is not None:
            scale, shift = film
            h = h * (1.0 + scale[:, None]) + shift[:, None]
        x = x + self.token_fc(h.transpose(1, 2)).transpose(1, 2)  # mix across the Nc coefficients
        return x + self.channel_mlp(self.norm_channels(x))  # mix across joint features


@register_model("mixer-dct", MixerDCTConfig, kind="stochastic")
class MixerDCT(LatentSampler, nn.Module):
    def __init__(self, config: MixerDCTConfig) -> None:
        super().__init__()
        self.config = c = config
        length = c.observed + c.future
        self.register_buffer("basis", dct_basis(length, c.num_coeffs), persistent=False)  # (Nc, L)
        scale = torch.tensor(c.feature_scale or [1.0] * c.feature_dim, dtype=torch.float32)
        self.register_buffer("scale", scale, persistent=False)  # (F,)
        C = c.hidden_dim
        self.embed = nn.Linear(c.feature_dim, C)
        self.position = nn.Parameter(torch.zeros(c.num_coeffs, C))
        self.context = nn.ModuleList([MixerBlock(tokens=c.num_coeffs, channels=C, expansion=c.expansion)
                                      for _ in range(c.context_blocks)])
        self.sampled = nn.ModuleList([MixerBlock(tokens=c.num_coeffs, channels=C, expansion=c.expansion)
                                      for _ in range(c.sample_blocks)])
        self.film = nn.ModuleList([nn.Linear(c.noise_dim, 2 * C) for _ in range(c.sample_blocks)])
        self.out_norm = nn.LayerNorm(C)
        self.head = nn.Linear(C, c.feature_dim)
        with torch.no_grad():  # start as zero-velocity: no correction of the padded window's coefficients
            self.head.weight.zero_()
            self.head.bias.zero_()

    # -- pieces ----------------------------------------------------------------------------------

    def coefficients(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """obs (B, To, F) -> (DCT coefficients (B, Nc, F) of the padded window minus its anchor, anchor (B, F))."""
        return anchored_coefficients(obs, self.basis, observed=self.config.observed, future=self.config.future)

    def windows(self, obs: torch.Tensor, noise: torch.Tensor) -> torch.Tensor:
        """The predicted padded windows (B, K, L, F) (anchor added back) for noises (B, K, Z)."""
        B, K = noise.shape[:2]
        coeffs, last = self.coefficients(obs)  # (B, Nc, F), (B, F)
        h = self.embed(coeffs) + self.position  # (B, Nc, C)
        for block in self.context:
            h = block(h)
        h = h[:, None].expand(B, K, *h.shape[1:]).reshape(B * K, *h.shape[1:])  # (B*K, Nc, C)
        z = noise.reshape(B * K, -1)  # (B*K, Z)
        for block, film in zip(self.sampled, self.film):
            h = block(h, film(z).chunk(2, dim=-1))
        delta = self.head(self.out_norm(h)).view(B, K, *coeffs.shape[1:])  # (B, K, Nc, F)
        out = coeffs[:, None] + delta  # (B, K, Nc, F)
        return torch.einsum("kl,bnkf->bnlf", self.basis, out) + last[:, None, None]  # (B, K, L, F)

    # -- training --------------------------------------------------------------------------------

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        c = self.config
        check_sequences(obs, future, feature_dim=c.feature_dim)
        if future.shape[1] != c.future:
            raise ValueError(f"mixer-dct trains on {c.future} future frames, got {future.shape[1]}")
        B, K, To = obs.shape[0], c.train_samples, c.observed
        noise = torch.randn(B, K, c.noise_dim, dtype=obs.dtype, device=obs.device)
        pred = self.windows(obs, noise)  # (B, K, L, F)
        fut, past = pred[:, :, To:], pred[:, :, :To]
        err = ((fut - future[:, None]) * self.scale).pow(2).sum(-1).add(1e-8).sqrt()  # (B, K, Tf) per frame
        score = err.mean(-1) + c.fde_weight * err[..., -1]  # (B, K)
        best = score.min(dim=1).values.mean()
        ctx = fit_context(obs, To)
        past_err = ((past - ctx[:, None]) * self.scale).pow(2).sum(-1).add(1e-8).sqrt().mean()
        early = err[..., : c.early_frames].mean() if c.early_frames > 0 else fut.new_zeros(())
        stats = motion_stats_error(fut.reshape(B * K, c.future, -1),
                                   future[:, None].expand(-1, K, -1, -1).reshape(B * K, c.future, -1),
                                   ctx[:, -1:].expand(-1, K, -1).reshape(B * K, -1))
        div = pairwise_similarity(fut, scale=c.diversity_scale) if c.diversity_weight > 0 else fut.new_zeros(())
        total = (best + c.observed_weight * past_err + c.early_weight * early + c.stats_weight * stats
                 + c.diversity_weight * div)
        return LossOutput(total=total, terms={"best_of_k": float(best.detach()), "past": float(past_err.detach()),
                                              "early": float(early.detach()),
                                              "stats": float(stats.detach()), "diversity": float(div.detach())})

    # -- sampling --------------------------------------------------------------------------------

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None) -> torch.Tensor:
        """K futures per context from K independent noises: (B*K, horizon, F), context-major; horizons
        beyond ``future`` continue each sample from its own last ``observed`` frames."""
        c = self.config
        B, K = obs.shape[0], num_samples
        noise = randn((B, K, c.noise_dim), like=obs, generator=generator)
        pieces = [self.windows(obs, noise)[:, :, c.observed:].reshape(B * K, c.future, -1)]  # (B*K, Tf, F)
        history = torch.cat([fit_context(obs, c.observed).repeat_interleave(K, dim=0), pieces[0]], dim=1)
        done = c.future
        while done < horizon:
            noise = randn((B * K, 1, c.noise_dim), like=obs, generator=generator)
            nxt = self.windows(history[:, -c.observed:], noise)[:, 0, c.observed:]  # (B*K, Tf, F)
            pieces.append(nxt)
            history = torch.cat([history, nxt], dim=1)
            done += c.future
        return torch.cat(pieces, dim=1)[:, :horizon]
