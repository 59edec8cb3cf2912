"""``pred-lstm``: the deterministic encoder-decoder LSTM baseline of MT-VAE (Sec. 3.1, Fig. 2a).

The encoder LSTM reads the observed features; its last hidden state e_A initialises the decoder, which
starts from the last observed frame x_T and predicts residuals autoregressively. Trained with the L1
reconstruction loss (as MT-VAE trains all its models). ``sample`` returns K identical copies.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from motion2video.models.base import DeterministicSampler, LossOutput, register_model
from motion2video.models.blocks import LSTMDecoder, LSTMEncoder, reconstruction_l1
from motion2video.models.base import check_sequences


@dataclass(frozen=True)
class PredLSTMConfig:
    feature_dim: int = 51
    hidden_dim: int = 128
    layer_norm: bool = True


@register_model("pred-lstm", PredLSTMConfig, kind="deterministic")
class PredLSTM(DeterministicSampler, nn.Module):
    """Deterministic forecaster: obs (B, To, F) -> future (B, horizon, F)."""

    def __init__(self, config: PredLSTMConfig) -> None:
        super().__init__()
        self.config = config
        c = config
        self.encoder = LSTMEncoder(c.feature_dim, c.hidden_dim, layer_norm=c.layer_norm)
        self.decoder = LSTMDecoder(
            feature_dim=c.feature_dim, cond_dim=c.hidden_dim, hidden_dim=c.hidden_dim, layer_norm=c.layer_norm
        )

    def predict(self, obs: torch.Tensor, *, horizon: int) -> torch.Tensor:
        """obs (B, To, F) -> (B, horizon, F)."""
        check_sequences(obs, None, feature_dim=self.config.feature_dim)
        e_a = self.encoder(obs)[:, -1]  # (B, H)
        return self.decoder(e_a, obs[:, -1], horizon=horizon)

    def loss(self, obs: torch.Tensor, future: torch.Tensor, *, step: int) -> LossOutput:
        check_sequences(obs, future, feature_dim=self.config.feature_dim)
        pred = self.predict(obs, horizon=future.shape[1])
        recon = reconstruction_l1(pred, future)
        return LossOutput(total=recon, terms={"recon": float(recon.detach())})

