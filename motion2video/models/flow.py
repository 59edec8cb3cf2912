"""A small RealNVP/Glow-style normalizing flow on latent vectors (behaviour paper, Sec. 3.4).

Each block is actnorm (Glow) -> affine coupling (RealNVP) -> fixed shuffle. ``forward`` maps data x (a
posterior latent) to u with the log-determinant of the Jacobian; ``inverse`` maps u ~ N(0, I) back to the
latent space. Trained after the behaviour model by maximum likelihood (Eq. 6, with the standard sign:
log p(x) = log N(T(x); 0, I) + log |det dT/dx|) with :func:`fit_flow`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn


class ActNorm(nn.Module):
    """y = (x + b) * exp(s), per dimension; initialised from the first batch so y has zero mean, unit variance."""

    def __init__(self, dim: int) -> None:
        super().__init__()
        self.bias = nn.Parameter(torch.zeros(dim))
        self.log_scale = nn.Parameter(torch.zeros(dim))
        self.register_buffer("initialized", torch.tensor(False))

    @torch.no_grad()
    def initialize(self, x: torch.Tensor) -> None:
        """Data-dependent init from x (N, D), N >= 2."""
        self.bias.copy_(-x.mean(dim=0))
        self.log_scale.copy_(-torch.log(x.std(dim=0) + 1e-6))
        self.initialized.fill_(True)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        if self.training and not bool(self.initialized):
            self.initialize(x)
        y = (x + self.bias) * torch.exp(self.log_scale)
        return y, self.log_scale.sum().expand(x.shape[0])

    def inverse(self, y: torch.Tensor) -> torch.Tensor:
        return y * torch.exp(-self.log_scale) - self.bias


class AffineCoupling(nn.Module):
    """RealNVP coupling: x = [x1, x2]; y1 = x1, y2 = x2 * exp(s(x1)) + t(x1), s = tanh-bounded.

    (s, t) come from a two-hidden-layer MLP whose last layer starts at zero (identity at init).
    """

    def __init__(self, dim: int, hidden_dim: int) -> None:
        super().__init__()
        if dim < 2:
            raise ValueError(f"coupling needs dim >= 2, got {dim}")
        self.d1 = dim // 2
        d2 = dim - self.d1
        self.net = nn.Sequential(
            nn.Linear(self.d1, hidden_dim),
            nn.ReLU(),
            nn.Linear(hidden_dim, hidden_dim),
            nn.ReLU(),
            nn.Linear(hidden_dim, 2 * d2),
        )
        nn.init.zeros_(self.net[-1].weight)
        nn.init.zeros_(self.net[-1].bias)
        self.scale = nn.Parameter(torch.ones(d2))  # s = scale * tanh(raw): bounded, learnable range

    def _st(self, x1: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        raw_s, t = self.net(x1).chunk(2, dim=-1)
        return self.scale * torch.tanh(raw_s), t

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        x1, x2 = x[:, : self.d1], x[:, self.d1 :]
        s, t = self._st(x1)
        y2 = x2 * torch.exp(s) + t
        return torch.cat([x1, y2], dim=-1), s.sum(dim=-1)

    def inverse(self, y: torch.Tensor) -> torch.Tensor:
        y1, y2 = y[:, : self.d1], y[:, self.d1 :]
        s, t = self._st(y1)
        return torch.cat([y1, (y2 - t) * torch.exp(-s)], dim=-1)


class Shuffle(nn.Module):
    """A fixed random permutation of the dimensions (log-det 0), reproducible from ``seed``."""

    def __init__(self, dim: int, *, seed: int) -> None:
        super().__init__()
        perm = torch.randperm(dim, generator=torch.Generator().manual_seed(seed))
        self.register_buffer("perm", perm)
        self.register_buffer("inv_perm", torch.argsort(perm))

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return x[:, self.perm], x.new_zeros(x.shape[0])

    def inverse(self, y: torch.Tensor) -> torch.Tensor:
        return y[:, self.inv_perm]


class Flow(nn.Module):
    """``num_blocks`` x (actnorm, affine coupling, shuffle) on (N, dim) vectors."""

    def __init__(self, dim: int, *, num_blocks: int, hidden_dim: int) -> None:
        super().__init__()
        self.dim = dim
        layers: list[nn.Module] = []
        for i in range(num_blocks):
            layers += [ActNorm(dim), AffineCoupling(dim, hidden_dim), Shuffle(dim, seed=i)]
        self.layers = nn.ModuleList(layers)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """x (N, D) -> u (N, D), log|det du/dx| (N,)."""
        logdet = x.new_zeros(x.shape[0])
        for layer in self.layers:
            x, ld = layer(x)
            logdet = logdet + ld
        return x, logdet

    def inverse(self, u: torch.Tensor) -> torch.Tensor:
        """u (N, D) -> x (N, D)."""
        for layer in reversed(self.layers):
            u = layer.inverse(u)
        return u

    def log_prob(self, x: torch.Tensor) -> torch.Tensor:
        """log p(x) under the flow with a standard-normal base: (N, D) -> (N,)."""
        u, logdet = self(x)
        base = -0.5 * (u.pow(2).sum(dim=-1) + self.dim * math.log(2.0 * math.pi))
        return base + logdet


@dataclass
class FlowFitResult:
    """``losses``: the mean negative log-likelihood (nats per vector) at every optimisation step."""

    losses: list[float]


def fit_flow(
    flow: Flow,
    latents: torch.Tensor,
    *,
    steps: int,
    batch_size: int = 256,
    lr: float = 1e-3,
    seed: int = 0,
) -> FlowFitResult:
    """Fit ``flow`` to ``latents`` (N, D) by maximum likelihood with Adam; leaves the flow in eval mode.

    The first batch initialises the actnorm layers (data-dependent init).
    """
    if latents.ndim != 2 or latents.shape[1] != flow.dim or latents.shape[0] < 2:
        raise ValueError(f"latents must have shape (N>=2, {flow.dim}), got {tuple(latents.shape)}")
    latents = latents.detach()
    gen = torch.Generator().manual_seed(seed)
    opt = torch.optim.Adam(flow.parameters(), lr=lr)
    flow.train()
    losses: list[float] = []
    n = latents.shape[0]
    for _ in range(steps):
        idx = torch.randint(0, n, (min(batch_size, n),), generator=gen).to(latents.device)
        nll = -flow.log_prob(latents[idx]).mean()
        opt.zero_grad(set_to_none=True)
        nll.backward()
        opt.step()
        losses.append(float(nll.detach()))
    flow.eval()
    return FlowFitResult(losses=losses)
