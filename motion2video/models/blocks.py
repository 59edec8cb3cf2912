"""Building blocks shared by the learned motion models.

Recurrent encoders/decoders over feature sequences ``(B, T, F)``, the three-layer skip-connected MLP that
MT-VAE uses for its latent mappings, diagonal-Gaussian helpers (KL divergences, reparameterisation), the
reconstruction losses, and the annealing schedules (pure functions of the training step).

Conventions:
- Reconstruction losses are summed over time and features and averaged over the batch (the negative
  log-likelihood of a whole sequence, up to constants), KL divergences are summed over latent dimensions
  and averaged over the batch, so both are "nats per sequence".
- Every decoder predicts residuals: ``y_t = y_{t-1} + W h_t`` with ``y_0`` the first input (the last
  observed frame), as in Martinez et al. and the behaviour paper; a decoder is autoregressive, so any
  horizon works.
"""

from __future__ import annotations

import math

import torch
from torch import nn

from motion2video.models.base import LatentPosterior

# --------------------------------------------------------------------------------------------------
# Shape checks and random numbers


def randn(shape: tuple[int, ...], *, like: torch.Tensor, generator: torch.Generator | None) -> torch.Tensor:
    """Standard normal noise with ``like``'s dtype and device, drawn from ``generator`` when given.

    The noise is drawn on the generator's device (a CPU generator with a GPU model works) and moved.
    """
    device = generator.device if generator is not None else like.device
    noise = torch.randn(shape, generator=generator, device=device, dtype=like.dtype)
    return noise.to(like.device)


def repeat_batch(x: torch.Tensor, k: int) -> torch.Tensor:
    """(B, ...) -> (B*K, ...), each row repeated K times consecutively (row b*K + k is sample k of b)."""
    return x.repeat_interleave(k, dim=0)


# --------------------------------------------------------------------------------------------------
# Diagonal Gaussians


def reparameterize(post: LatentPosterior, eps: torch.Tensor) -> torch.Tensor:
    """z = mu + sigma * eps, all (B, Z)."""
    return post.mu + torch.exp(0.5 * post.logvar) * eps


def kl_std_normal(post: LatentPosterior) -> torch.Tensor:
    """KL(N(mu, diag exp(logvar)) || N(0, I)) per row: (B, Z) -> (B,)."""
    return 0.5 * (torch.exp(post.logvar) + post.mu.pow(2) - 1.0 - post.logvar).sum(dim=-1)


def kl_diag_gaussians(q: LatentPosterior, p: LatentPosterior) -> torch.Tensor:
    """KL(q || p) between diagonal Gaussians, per row: (B, Z) each -> (B,)."""
    log_ratio = q.logvar - p.logvar
    mean_term = (q.mu - p.mu).pow(2) * torch.exp(-p.logvar)
    return 0.5 * (torch.exp(log_ratio) + mean_term - 1.0 - log_ratio).sum(dim=-1)


# --------------------------------------------------------------------------------------------------
# Reconstruction losses


def reconstruction_l1(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Sum over (T, F) of |pred - target|, averaged over the batch: (B, T, F) x 2 -> scalar."""
    return (pred - target).abs().sum(dim=(1, 2)).mean()


def reconstruction_mse(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Sum over (T, F) of (pred - target)^2, averaged over the batch: (B, T, F) x 2 -> scalar."""
    return (pred - target).pow(2).sum(dim=(1, 2)).mean()


def motion_stats_error(pred: torch.Tensor, target: torch.Tensor, start: torch.Tensor) -> torch.Tensor:
    """How much livelier or more sluggish ``pred`` is than ``target`` (both (B, T, F), after start (B, F)):
    per sequence and feature, the squared difference of the mean absolute velocity plus that of the mean
    absolute acceleration, summed over features, times T, averaged over the batch."""
    p = torch.cat([start[:, None], pred], dim=1)
    t = torch.cat([start[:, None], target], dim=1)
    vp, vt = torch.diff(p, dim=1), torch.diff(t, dim=1)
    ap, at = torch.diff(vp, dim=1), torch.diff(vt, dim=1)
    err = (vp.abs().mean(1) - vt.abs().mean(1)).pow(2) + (ap.abs().mean(1) - at.abs().mean(1)).pow(2)  # (B, F)
    return err.sum(-1).mean() * pred.shape[1]


# --------------------------------------------------------------------------------------------------
# Schedules (pure functions of the step)


def linear_ramp(step: int, *, start: int = 0, length: int) -> float:
    """0 before ``start``, rising linearly to 1 over ``length`` steps, then 1 (length <= 0: a step at start)."""
    if length <= 0:
        return 1.0 if step >= start else 0.0
    return float(min(1.0, max(0.0, (step - start) / length)))


def logistic_ramp(step: int, *, midpoint: int, width: float) -> float:
    """Logistic KL-annealing curve (Bowman et al.): 1 / (1 + exp(-(step - midpoint) / width)), in (0, 1)."""
    if width <= 0:
        raise ValueError(f"width must be > 0, got {width}")
    x = (step - midpoint) / width
    if x < -60.0:  # exp overflow guard; the value is 0 to double precision anyway
        return 0.0
    return 1.0 / (1.0 + math.exp(-x))


def teacher_forcing_probability(step: int, *, steps: int) -> float:
    """Probability of feeding the ground truth: 1 at step 0, linearly down to 0 at ``steps``, then 0."""
    return 1.0 - linear_ramp(step, start=0, length=steps)


# --------------------------------------------------------------------------------------------------
# Layers


class SkipMLP(nn.Module):
    """Three fully-connected layers with a skip connection and layer norm (MT-VAE's latent mappings).

    ``h1 = act(LN(W1 x))``, ``h2 = act(LN(W2 h1)) + h1``, ``out = W3 h2``: (B, in_dim) -> (B, out_dim).
    """

    def __init__(self, in_dim: int, out_dim: int, *, hidden_dim: int) -> None:
        super().__init__()
        self.fc1 = nn.Linear(in_dim, hidden_dim)
        self.ln1 = nn.LayerNorm(hidden_dim)
        self.fc2 = nn.Linear(hidden_dim, hidden_dim)
        self.ln2 = nn.LayerNorm(hidden_dim)
        self.fc3 = nn.Linear(hidden_dim, out_dim)
        self.act = nn.GELU()

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h1 = self.act(self.ln1(self.fc1(x)))
        h2 = self.act(self.ln2(self.fc2(h1))) + h1
        return self.fc3(h2)


class GaussianHead(nn.Module):
    """Linear map to a diagonal Gaussian: (B, in_dim) -> mu, logvar (B, Z) each (logvar clamped to [-12, 8])."""

    def __init__(self, in_dim: int, latent_dim: int) -> None:
        super().__init__()
        self.proj = nn.Linear(in_dim, 2 * latent_dim)

    def forward(self, x: torch.Tensor) -> LatentPosterior:
        mu, logvar = self.proj(x).chunk(2, dim=-1)
        return LatentPosterior(mu=mu, logvar=logvar.clamp(-12.0, 8.0))


class LSTMCell(nn.Module):
    """An LSTM cell with optional layer normalisation (Ba et al. 2016), as MT-VAE uses.

    With ``layer_norm``: gates = LN(W_x x) + LN(W_h h) + b, c' = f c + i g, h' = o tanh(LN(c')).
    Inputs x (B, in_dim), state (h, c) each (B, hidden_dim).
    """

    def __init__(self, in_dim: int, hidden_dim: int, *, layer_norm: bool) -> None:
        super().__init__()
        self.hidden_dim = hidden_dim
        self.layer_norm = layer_norm
        self.w_x = nn.Linear(in_dim, 4 * hidden_dim, bias=False)
        self.w_h = nn.Linear(hidden_dim, 4 * hidden_dim, bias=False)
        self.bias = nn.Parameter(torch.zeros(4 * hidden_dim))
        with torch.no_grad():  # forget-gate bias 1: remember by default
            self.bias[hidden_dim : 2 * hidden_dim] = 1.0
        if layer_norm:
            self.ln_x = nn.LayerNorm(4 * hidden_dim)
            self.ln_h = nn.LayerNorm(4 * hidden_dim)
            self.ln_c = nn.LayerNorm(hidden_dim)

    def forward(
        self, x: torch.Tensor, state: tuple[torch.Tensor, torch.Tensor]
    ) -> tuple[torch.Tensor, torch.Tensor]:
        h, c = state
        gx, gh = self.w_x(x), self.w_h(h)  # (B, 4H) each
        if self.layer_norm:
            gx, gh = self.ln_x(gx), self.ln_h(gh)
        i, f, g, o = (gx + gh + self.bias).chunk(4, dim=-1)  # (B, H) each
        c = torch.sigmoid(f) * c + torch.sigmoid(i) * torch.tanh(g)
        c_out = self.ln_c(c) if self.layer_norm else c
        h = torch.sigmoid(o) * torch.tanh(c_out)
        return h, c


class LSTMEncoder(nn.Module):
    """Runs an :class:`LSTMCell` over a sequence from a zero state: (B, T, F) -> hidden states (B, T, H)."""

    def __init__(self, feature_dim: int, hidden_dim: int, *, layer_norm: bool) -> None:
        super().__init__()
        self.cell = LSTMCell(feature_dim, hidden_dim, layer_norm=layer_norm)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        B, T, _ = x.shape
        h = x.new_zeros(B, self.cell.hidden_dim)
        c = x.new_zeros(B, self.cell.hidden_dim)
        outputs = []
        for t in range(T):
            h, c = self.cell(x[:, t], (h, c))
            outputs.append(h)
        return torch.stack(outputs, dim=1)  # (B, T, H)


class LSTMDecoder(nn.Module):
    """Autoregressive residual LSTM decoder conditioned on a vector.

    The state starts at (tanh(A cond), A' cond); at each step the input is [cond, y_{t-1}] (or only y_{t-1}
    when ``feed_condition`` is False), and ``y_t = y_{t-1} + W h_t`` with ``y_0 = first_input``.
    With ``velocity_input`` the input also holds the last step's velocity ``y_{t-1} - y_{t-2}``, starting from
    the observed one (``first_input - previous_input``), so the first generated frames can continue the
    motion instead of having to recover its speed from ``cond``.
    cond (B, C), first_input (B, F), previous_input (B, F) (velocity_input only) -> (B, horizon, F).
    """

    def __init__(
        self, *, feature_dim: int, cond_dim: int, hidden_dim: int, layer_norm: bool, feed_condition: bool = True,
        velocity_input: bool = False,
    ) -> None:
        super().__init__()
        self.feed_condition = feed_condition
        self.velocity_input = velocity_input
        in_dim = feature_dim * (2 if velocity_input else 1) + (cond_dim if feed_condition else 0)
        self.init_h = nn.Linear(cond_dim, hidden_dim)
        self.init_c = nn.Linear(cond_dim, hidden_dim)
        self.cell = LSTMCell(in_dim, hidden_dim, layer_norm=layer_norm)
        self.out = nn.Linear(hidden_dim, feature_dim)

    def forward(self, cond: torch.Tensor, first_input: torch.Tensor, *, horizon: int,
                previous_input: torch.Tensor | None = None) -> torch.Tensor:
        if self.velocity_input and previous_input is None:
            raise ValueError("a velocity_input decoder needs previous_input (the second-to-last observed frame)")
        h, c = torch.tanh(self.init_h(cond)), self.init_c(cond)  # (B, H) each
        y = first_input  # (B, F)
        v = first_input - previous_input if self.velocity_input else None  # (B, F)
        outputs = []
        for _ in range(horizon):
            parts = ([cond] if self.feed_condition else []) + [y] + ([v] if self.velocity_input else [])
            h, c = self.cell(torch.cat(parts, dim=-1), (h, c))
            step = self.out(h)
            y = y + step  # residual pose update
            v = step
            outputs.append(y)
        return torch.stack(outputs, dim=1)  # (B, horizon, F)


class GRUEncoder(nn.Module):
    """Single-layer GRU over a sequence: (B, T, F) -> last hidden state (B, H) (LCP-VAE's motion encoders)."""

    def __init__(self, feature_dim: int, hidden_dim: int) -> None:
        super().__init__()
        self.gru = nn.GRU(feature_dim, hidden_dim, batch_first=True)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        _, h_last = self.gru(x)  # (1, B, H)
        return h_last[0]


class GRUDecoder(nn.Module):
    """Autoregressive residual GRU decoder from an initial hidden state, with optional teacher forcing.

    h0 (B, H), first_input (B, F) -> (B, horizon, F); ``y_t = y_{t-1} + W h_t``. With ``targets``
    (B, horizon, F) and ``teacher_forcing`` p > 0, each sample's next input is the ground-truth frame with
    probability p (drawn independently per sample and step from the global RNG; training only), else its
    own prediction.
    """

    def __init__(self, *, feature_dim: int, hidden_dim: int) -> None:
        super().__init__()
        self.cell = nn.GRUCell(feature_dim, hidden_dim)
        self.out = nn.Linear(hidden_dim, feature_dim)

    def forward(
        self,
        h0: torch.Tensor,
        first_input: torch.Tensor,
        *,
        horizon: int,
        targets: torch.Tensor | None = None,
        teacher_forcing: float = 0.0,
    ) -> torch.Tensor:
        if teacher_forcing > 0.0 and (targets is None or targets.shape[1] < horizon):
            raise ValueError("teacher forcing needs targets covering the horizon")
        h, x = h0, first_input
        outputs = []
        for t in range(horizon):
            h = self.cell(x, h)
            y = x + self.out(h)  # residual on the input frame
            outputs.append(y)
            if teacher_forcing > 0.0:
                use_truth = torch.rand(y.shape[0], 1, device=y.device) < teacher_forcing  # (B, 1)
                x = torch.where(use_truth, targets[:, t], y)
            else:
                x = y
        return torch.stack(outputs, dim=1)  # (B, horizon, F)
