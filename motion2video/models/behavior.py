"""``behavior``: behaviour-driven synthesis (Blattmann et al., CVPR 2021), posture-conditioned cVAE.

A behaviour sequence x = [x_t, x_1, ..., x_T] starts at its posture x_t. In the forecasting setting x_t is
the last observed frame and x_1..x_T the future window.
- q(z | x, x_t): an LSTM over the whole sequence (x_t included, as in Fig. 2a) and a linear Gaussian head;
- p(x | z, x_t): an LSTM decoder whose state is initialised from z, whose first input is x_t, then its own
  predictions, with a linear residual output (Sec. 4.1);
- the auxiliary posture regressor p_psi (a three-layer MLP) predicts the start posture x_t from z.

Objective (Eq. 5, minimised):
    recon + gamma_KL (KL(q || N(0, I)) - I_KL) - gamma_C * regressor_error(z)
with recon the summed squared error of the sequence, ``regressor_error`` the summed squared error of the
regressor's start-posture prediction from a posterior sample (the model is penalised when the regressor
succeeds: z should not carry posture), I_KL the information budget and gamma_KL the Lagrange multiplier,
updated by dual gradient ascent (:func:`dual_ascent`) after every training-mode ``loss`` call:
    gamma_KL <- max(0, gamma_KL + eta (KL - I_KL)).
gamma_KL is a buffer (``kl_multiplier``), so it is saved in checkpoints.

Options for behaviour that comes across (off by default: older checkpoints load as they were; the shipped checkpoint
uses all of them, see weights/behavior.md): ``decoder_feeds_z`` (z at every decoder step),
``encoder_velocities`` (the encoder reads frame differences too), ``root_weight`` (the root trajectory's share
of the reconstruction error), ``root_trajectory`` (:class:`RootTrajectoryDecoder`: the decoder can be given the
behaviour's root path and enacts the pose along it) and ``motion_stats_weight`` (:func:`motion_stats_error`,
matching the generated motion's mean speed and acceleration to the real one's).

After training, a normalizing flow (:mod:`motion2video.models.flow`) is fitted to posterior latents
(:meth:`BehaviorModel.fit_flow`); ``sample(..., use_flow=True)`` draws u ~ N(0, I) and decodes z = T^-1(u).

Training protocol (alternating optimisation, two optimisers), for a generic training loop:
- ``parameter_groups() -> {"main": [...], "auxiliary": [...]}``: one optimiser per group. The flow's
  parameters are in neither (fitted afterwards).
- each iteration, in train mode:
    1. main step:  ``opt_main.zero_grad(); model.loss(obs, future, step=step).total.backward(); opt_main.step()``
       (this also updates gamma_KL; the backward leaves gradients on the regressor too, which step 2
       clears: always zero a group's gradients right before its backward);
    2. auxiliary step: ``opt_aux.zero_grad(); model.auxiliary_loss(obs, future).total.backward(); opt_aux.step()``
       (z is detached: only the regressor learns here).
- after training: ``model.fit_flow(model.posterior_latents(obs_all, future_all), steps=...)``.
Models without ``parameter_groups`` train with one optimiser over all parameters and ``loss`` only.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from motion2video.models.base import LatentPosterior, LatentSampler, LossOutput, register_model
from motion2video.models.blocks import (
    GaussianHead, LSTMCell, LSTMDecoder, LSTMEncoder, kl_std_normal, motion_stats_error, randn, reconstruction_mse,
    repeat_batch, reparameterize,
)
from motion2video.models.base import check_sequences
from motion2video.models.flow import Flow, FlowFitResult, fit_flow


def dual_ascent(multiplier: float, *, constraint: float, budget: float, lr: float) -> float:
    """One projected dual-gradient-ascent step on the Lagrange multiplier of ``constraint <= budget``.

    Returns max(0, multiplier + lr * (constraint - budget)): it grows while the KL exceeds the budget and
    shrinks (never below 0) while it is under.
    """
    return max(0.0, multiplier + lr * (constraint - budget))


@dataclass(frozen=True)
class BehaviorConfig:
    feature_dim: int = 51
    hidden_dim: int = 128
    latent_dim: int = 32
    regressor_dim: int = 128
    layer_norm: bool = True
    kl_budget: float = 30.0  # I_KL, nats per sequence
    gamma_c: float = 0.1  # weight of the disentanglement penalty (paper: 0.1)
    kl_multiplier_init: float = 1.0  # initial gamma_KL
    kl_multiplier_lr: float = 1e-3  # dual ascent step size eta
    flow_blocks: int = 6
    flow_hidden: int = 128
    # Measured: without these the model could not even reconstruct a jump from its own start posture,
    # as its z only set the decoder's initial state. So: feed z to the decoder at every step, and give the
    # behaviour encoder the frame-to-frame velocities beside the frames. Both off = the old architecture.
    decoder_feeds_z: bool = False
    encoder_velocities: bool = False
    # Weight of the last ``root_dims`` features (the root trajectory of the body layouts: x, y, height) in the
    # reconstruction error. Measured: with weight 1 the model reconstructed no jump at all, even of training
    # clips (the pelvis height is 1 of 51 features and jumps are rare). 1.0 = the plain summed squared error.
    root_weight: float = 1.0
    root_dims: int = 3
    # The decoder's access to the behaviour's root trajectory: at every step it may get the behaviour's root
    # features (the last ``root_dims``: x, y relative to the start in its heading frame, height) and then
    # enacts the pose along that path (the root it outputs is the given one). Trained with the trajectory
    # given for a random ``root_given_prob`` share of the sequences and not given for the rest, so the same
    # decoder also generates its own root (flow samples, and ``decode`` without a trajectory).
    root_trajectory: bool = False
    root_given_prob: float = 0.5
    # Liveliness: weight of a moment-matching term, the squared difference between the
    # generated and the true sequence's mean absolute velocity and acceleration per feature (summed over
    # features, times the sequence length). The squared error alone is minimised by smooth, slow motion.
    motion_stats_weight: float = 0.0


class RootTrajectoryDecoder(nn.Module):
    """The behaviour decoder with access to a root trajectory: an autoregressive residual LSTM whose state
    starts at (tanh(A z), A' z) and whose input at step t is [z, y_{t-1}, m r_t, m], with r_t (root_dims,) the
    given root features and m = 1 where a trajectory is given (then the root part of y_t is replaced by r_t),
    m = 0 where not (the decoder makes its own root).
    z (B, Z), first_input (B, F), root (B, horizon, R) or None, given (B,) bool or None (all given when a
    root is passed) -> (B, horizon, F).
    """

    def __init__(self, *, feature_dim: int, latent_dim: int, hidden_dim: int, root_dims: int,
                 layer_norm: bool) -> None:
        super().__init__()
        self.root_dims = root_dims
        self.init_h = nn.Linear(latent_dim, hidden_dim)
        self.init_c = nn.Linear(latent_dim, hidden_dim)
        self.cell = LSTMCell(latent_dim + feature_dim + root_dims + 1, hidden_dim, layer_norm=layer_norm)
        self.out = nn.Linear(hidden_dim, feature_dim)

    def forward(self, z: torch.Tensor, first_input: torch.Tensor, *, horizon: int,
                root: torch.Tensor | None = None, given: torch.Tensor | None = None) -> torch.Tensor:
        B, R = z.shape[0], self.root_dims
        if root is not None and root.shape != (B, horizon, R):
            raise ValueError(f"root must be (B, horizon, {R}) = {(B, horizon, R)}, got {tuple(root.shape)}")
        if root is None:
            m = z.new_zeros(B, 1)
            root = z.new_zeros(B, horizon, R)
        else:
            m = (torch.ones(B, dtype=torch.bool, device=z.device) if given is None else given).to(z.dtype)[:, None]
        h, c = torch.tanh(self.init_h(z)), self.init_c(z)
        y = first_input
        outputs = []
        for t in range(horizon):
            r = root[:, t] * m  # (B, R)
            h, c = self.cell(torch.cat([z, y, r, m], dim=-1), (h, c))
            y = y + self.out(h)
            y = torch.cat([y[:, :-R], m * root[:, t] + (1 - m) * y[:, -R:]], dim=-1)  # the given root wins
            outputs.append(y)
        return torch.stack(outputs, dim=1)


@register_model("behavior", BehaviorConfig, kind="stochastic")
class BehaviorModel(LatentSampler, nn.Module):
    def __init__(self, config: BehaviorConfig) -> None:
        super().__init__()
        self.config = config
        c = config
        F, H, Z = c.feature_dim, c.hidden_dim, c.latent_dim
        self.encoder = LSTMEncoder(2 * F if c.encoder_velocities else F, H, layer_norm=c.layer_norm)
        self.posterior_head = GaussianHead(H, Z)
        if c.root_trajectory:
            self.decoder = RootTrajectoryDecoder(feature_dim=F, latent_dim=Z, hidden_dim=H, root_dims=c.root_dims,
                                                 layer_norm=c.layer_norm)
        else:
            self.decoder = LSTMDecoder(
                feature_dim=F, cond_dim=Z, hidden_dim=H, layer_norm=c.layer_norm, feed_condition=c.decoder_feeds_z
            )
        self.regressor = nn.Sequential(
            nn.Linear(Z, c.regressor_dim),
            nn.ReLU(),
            nn.Linear(c.regressor_dim, c.regressor_dim),
            nn.ReLU(),
            nn.Linear(c.regressor_dim, F),
        )
        self.flow = Flow(Z, num_blocks=c.flow_blocks, hidden_dim=c.flow_hidden)
        self.register_buffer("kl_multiplier", torch.tensor(float(c.kl_multiplier_init)))
        self.register_buffer("flow_fitted", torch.tensor(False))

    # -- behaviour API ---------------------------------------------------------------------------

    def behavior_posterior(self, sequence: torch.Tensor) -> LatentPosterior:
        """q(z | x, x_t) for sequence (B, T, F) whose first frame is its start posture x_t."""
        check_sequences(sequence, None, feature_dim=self.config.feature_dim)
        if sequence.shape[1] < 2:
            raise ValueError(f"a behaviour sequence needs >= 2 frames, got {sequence.shape[1]}")
        if self.config.encoder_velocities:  # [x_t, x_t - x_{t-1}] (zero velocity at the start posture)
            velocity = torch.diff(sequence, dim=1, prepend=sequence[:, :1])
            sequence = torch.cat([sequence, velocity], dim=-1)  # (B, T, 2F)
        return self.posterior_head(self.encoder(sequence)[:, -1])

    def behavior_latent(self, sequence: torch.Tensor) -> torch.Tensor:
        """The behaviour representation (posterior mean) of sequence (B, T, F): (B, Z)."""
        return self.behavior_posterior(sequence).mu

    def transfer(self, z: torch.Tensor, start_posture: torch.Tensor, horizon: int,
                 root: torch.Tensor | None = None) -> torch.Tensor:
        """Enact behaviour z (B, Z) from start_posture (B, F): (B, horizon, F) (the frames after the start).

        ``root`` (B, horizon, root_dims): the behaviour's root trajectory for a ``root_trajectory`` model (the
        generated root is then this one; None = the model generates its own); ignored by other models.
        """
        if start_posture.ndim != 2 or start_posture.shape[-1] != self.config.feature_dim:
            raise ValueError(f"start_posture must be (B, {self.config.feature_dim}), got {tuple(start_posture.shape)}")
        if self.config.root_trajectory:
            return self.decoder(z, start_posture, horizon=horizon, root=root)
        return self.decoder(z, start_posture, horizon=horizon)

    # -- model protocol --------------------------------------------------------------------------

    def encode(self, obs: torch.Tensor, future: torch.Tensor) -> LatentPosterior:
        """q(z | [x_T, future]) with x_T = obs[:, -1]."""
        check_sequences(obs, future, feature_dim=self.config.feature_dim)
        return self.behavior_posterior(torch.cat([obs[:, -1:], future], dim=1))

    def decode(self, obs: torch.Tensor, z: torch.Tensor, *, horizon: int) -> torch.Tensor:
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        return self.transfer(z, obs[:, -1], horizon)

    def parameter_groups(self) -> dict[str, list[nn.Parameter]]:
        """{"main": encoder + decoder, "auxiliary": posture regressor}; the flow is in neither."""
        aux = list(self.regressor.parameters())
        skip = {id(p) for p in aux} | {id(p) for p in self.flow.parameters()}
        main = [p for p in self.parameters() if id(p) not in skip]
        return {"main": main, "auxiliary": aux}

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        """Eq. 5 (minimised); in train mode with grad enabled it then updates gamma_KL by dual ascent."""
        c = self.config
        post = self.encode(obs, future)
        start = obs[:, -1]  # (B, F)
        z = reparameterize(post, torch.randn_like(post.mu))
        if c.root_trajectory:  # the true root path given to a random share of the sequences
            given = torch.rand(future.shape[0], device=future.device) < c.root_given_prob
            pred = self.decoder(z, start, horizon=future.shape[1], root=future[..., -c.root_dims:], given=given)
        else:
            pred = self.decoder(z, start, horizon=future.shape[1])  # (B, Tf, F)
        recon = self.reconstruction_error(pred, future)
        if c.motion_stats_weight > 0:
            recon = recon + c.motion_stats_weight * motion_stats_error(pred, future, start)
        kl = kl_std_normal(post).mean()
        reg_err = (self.regressor(z) - start).pow(2).sum(dim=-1).mean()
        gamma_kl = float(self.kl_multiplier)
        total = recon + gamma_kl * (kl - c.kl_budget) - c.gamma_c * reg_err
        if self.training and torch.is_grad_enabled():
            new = dual_ascent(gamma_kl, constraint=float(kl.detach()), budget=c.kl_budget, lr=c.kl_multiplier_lr)
            self.kl_multiplier.fill_(new)
        terms = {
            "recon": float(recon.detach()),
            "kl": float(kl.detach()),
            "kl_multiplier": gamma_kl,
            "regressor_error": float(reg_err.detach()),
        }
        return LossOutput(total=total, terms=terms)

    def reconstruction_error(self, pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
        """Summed squared error of (B, T, F) sequences, averaged over the batch, the last ``root_dims``
        features weighted by ``root_weight`` (the plain :func:`reconstruction_mse` when it is 1)."""
        c = self.config
        if c.root_weight == 1.0 or c.root_dims <= 0:
            return reconstruction_mse(pred, target)
        weight = torch.ones(pred.shape[-1], dtype=pred.dtype, device=pred.device)
        weight[-c.root_dims:] = c.root_weight
        return ((pred - target).pow(2) * weight).sum(dim=(1, 2)).mean()

    def auxiliary_loss(self, obs: torch.Tensor, future: torch.Tensor) -> LossOutput:
        """Eq. 2 for the regressor: its start-posture error from a detached posterior sample."""
        with torch.no_grad():
            post = self.encode(obs, future)
            z = reparameterize(post, torch.randn_like(post.mu))
        err = (self.regressor(z) - obs[:, -1]).pow(2).sum(dim=-1).mean()
        return LossOutput(total=err, terms={"regressor": float(err.detach())})

    # -- flow ------------------------------------------------------------------------------------

    @torch.no_grad()
    def posterior_latents(
        self, obs: torch.Tensor, future: torch.Tensor, *, generator: torch.Generator | None = None
    ) -> torch.Tensor:
        """One sample z ~ q(z | x, x_t) per window: (B, Z), the flow's training data."""
        post = self.encode(obs, future)
        return reparameterize(post, randn(tuple(post.mu.shape), like=post.mu, generator=generator))

    def fit_flow(
        self, latents: torch.Tensor, *, steps: int, batch_size: int = 256, lr: float = 1e-3, seed: int = 0
    ) -> FlowFitResult:
        """Fit the flow to posterior latents (N, Z) (from :meth:`posterior_latents`) and mark it fitted."""
        result = fit_flow(self.flow, latents, steps=steps, batch_size=batch_size, lr=lr, seed=seed)
        self.flow_fitted.fill_(True)
        return result

    def check_context(self, obs: torch.Tensor, *, use_flow: bool = True) -> None:
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        if use_flow and not bool(self.flow_fitted):
            raise RuntimeError("the behaviour flow is not fitted: call fit_flow() first or pass use_flow=False")

    def sample_rows(self, obs: torch.Tensor, num_samples: int, *, horizon: int,
                    generator: torch.Generator | None, use_flow: bool = True) -> torch.Tensor:
        """New behaviours from the last observed posture: (B*K, horizon, F), ``sample(obs, ..., use_flow=True)``.

        u ~ N(0, I); z = T^-1(u) with ``use_flow`` (requires :meth:`fit_flow`), else z = u.
        """
        B, K = obs.shape[0], num_samples
        z = randn((B * K, self.config.latent_dim), like=obs, generator=generator)  # (B*K, Z)
        if use_flow:
            z = self.flow.inverse(z)
        return self.decoder(z, repeat_batch(obs[:, -1], K), horizon=horizon)  # (B*K, horizon, F)
