"""mixer-dct: the anchored DCT representation, the mixer, best-of-K training and its sampling;
and the action / source balanced window sampling of the dataset."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motion2video.data.dataset import Clip, clip_sampling_weights
import motion2video.models  # noqa: F401  (importing registers the models)
from motion2video.models.base import MODEL_REGISTRY, build_model
from motion2video.models.mixer import dct_basis, fit_context, pad_with_last

F = 6
TINY = {"feature_dim": F, "observed": 5, "future": 7, "num_coeffs": 8, "hidden_dim": 16, "context_blocks": 1,
        "sample_blocks": 1, "noise_dim": 4, "train_samples": 3}


def _tiny(**extra: object) -> torch.nn.Module:
    torch.manual_seed(0)
    return build_model("mixer-dct", {**TINY, **extra})


def _batch(b: int = 3, to: int = 5, tf: int = 7) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(123)
    return torch.randn(b, to, F, generator=g), torch.randn(b, tf, F, generator=g)


def _sample(model, obs, *, k: int, horizon: int, seed: int) -> torch.Tensor:
    return model.sample(obs, num_samples=k, horizon=horizon, generator=torch.Generator().manual_seed(seed))


def _two_futures() -> tuple[torch.Tensor, torch.Tensor]:
    """One context (zeros, 5 frames) twice, with two equally likely futures (up or down): (2, 5, F), (2, 7, F)."""
    t = torch.linspace(0.1, 1.0, 7)[:, None].expand(7, F)
    return torch.zeros(2, 5, F), torch.stack([t, -t])


def test_registered_stochastic_and_small() -> None:
    assert MODEL_REGISTRY["mixer-dct"].kind == "stochastic"
    n = sum(p.numel() for p in build_model("mixer-dct").parameters())
    assert 100_000 < n < 3_000_000, n


def test_dct_basis_is_orthonormal_and_complete() -> None:
    d = dct_basis(12, 12).double()
    assert torch.allclose(d @ d.T, torch.eye(12, dtype=torch.float64), atol=1e-6)
    x = torch.randn(12, 3, dtype=torch.float64)
    assert torch.allclose(d.T @ (d @ x), x, atol=1e-6)
    low = dct_basis(12, 4).double()
    assert torch.allclose(low @ low.T, torch.eye(4, dtype=torch.float64), atol=1e-6)


def test_context_padding_and_cropping() -> None:
    obs = torch.arange(3 * 2, dtype=torch.float32).view(1, 3, 2)
    padded = pad_with_last(obs, 4)
    assert padded.shape == (1, 7, 2) and torch.equal(padded[0, 3:], obs[0, -1].expand(4, 2))
    assert torch.equal(fit_context(obs, 2), obs[:, 1:])
    longer = fit_context(obs, 5)
    assert torch.equal(longer[0, :2], obs[0, 0].expand(2, 2)) and torch.equal(longer[:, 2:], obs)


def test_untrained_model_with_the_full_basis_is_zero_velocity() -> None:
    """The head starts at zero, so with every DCT coefficient kept the future is the last pose."""
    model = _tiny(num_coeffs=12).eval()
    obs, _ = _batch()
    out = _sample(model, obs, k=4, horizon=7, seed=0)
    assert torch.allclose(out, obs[:, None, -1:].expand(-1, 4, 7, -1), atol=1e-5)


def test_loss_and_sample_shapes_and_long_horizons() -> None:
    model = _tiny()
    obs, fut = _batch()
    out = model.loss(obs, fut, step=0)
    assert out.total.ndim == 0 and torch.isfinite(out.total)
    assert set(out.terms) == {"best_of_k", "past", "early", "stats", "diversity"}
    model.eval()
    assert _sample(model, obs, k=4, horizon=7, seed=0).shape == (3, 4, 7, F)
    assert _sample(model, obs, k=2, horizon=3, seed=0).shape == (3, 2, 3, F)
    long = _sample(model, obs, k=2, horizon=20, seed=0)  # three autoregressive passes of 7 frames
    assert long.shape == (3, 2, 20, F) and torch.isfinite(long).all()
    assert torch.equal(long[:, :, :7], _sample(model, obs, k=2, horizon=7, seed=0))
    short = _sample(model, obs[:, 2:], k=2, horizon=7, seed=0)  # 3 observed frames: padded with the first
    assert short.shape == (3, 2, 7, F)
    with pytest.raises(ValueError, match="future"):
        model.loss(obs, fut[:, :5], step=0)


def test_sampling_is_seeded_batched_and_diverse() -> None:
    model = _tiny()
    with torch.no_grad():  # a non-zero head so that the noise reaches the output
        model.head.weight.normal_(0.0, 0.5)
    model.eval()
    obs, _ = _batch()
    a, b = _sample(model, obs, k=5, horizon=7, seed=1), _sample(model, obs, k=5, horizon=7, seed=1)
    assert torch.equal(a, b)
    assert not torch.allclose(a, _sample(model, obs, k=5, horizon=7, seed=2))
    assert (a[:, 0] - a[:, 1]).abs().max() > 1e-3  # different noises, different futures


def _without_gradient(model: torch.nn.Module) -> list[str]:
    """Names of the parameters that the last backward pass left without a gradient (None or all zero)."""
    return [n for n, p in model.named_parameters() if p.grad is None or not torch.any(p.grad != 0)]


def test_gradients_reach_every_parameter() -> None:
    model = _tiny(diversity_weight=1.0)
    with torch.no_grad():
        model.head.weight.normal_(0.0, 0.1)
    obs, fut = _batch()
    model.loss(obs, fut, step=0).total.backward()
    missing = _without_gradient(model)
    assert not missing, missing


def test_best_of_k_training_fits_a_two_mode_future() -> None:
    """One context, two equally likely futures (up or down): best-of-K training puts samples on both."""
    torch.manual_seed(0)
    model = build_model("mixer-dct", {**TINY, "hidden_dim": 32, "train_samples": 6, "stats_weight": 0.0})
    obs, fut = _two_futures()
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    for step in range(300):
        loss = model.loss(obs, fut, step=step)
        opt.zero_grad()
        loss.total.backward()
        opt.step()
    model.eval()
    samples = _sample(model, obs[:1], k=20, horizon=7, seed=0)[0]  # (20, 7, F)
    err = torch.stack([(samples - f).pow(2).sum(-1).sqrt().mean(-1) for f in fut])  # (2 modes, 20)
    zero_velocity = fut.pow(2).sum(-1).sqrt().mean(-1)  # (2,)
    assert torch.all(err.min(dim=1).values < 0.25 * zero_velocity), err.min(dim=1).values


def _clip(name: str, label: str | None, frames: int) -> Clip:
    return Clip(name=name, data=np.zeros((frames, 17, 3), np.float32), label=label, group=name)


def test_clip_sampling_weights_balance_actions_and_sources() -> None:
    clips = [_clip("acrnn/salsa_1.bvh", "salsa", 1009), _clip("acrnn/salsa_2.bvh", "salsa", 1009),
             _clip("cmu/01_01.bvh", "walk", 209), _clip("cmu/01_02.bvh", None, 109)]
    plain = clip_sampling_weights(clips, min_frames=10)
    assert np.allclose(plain, [1000, 1000, 200, 100])  # every window start alike
    full = clip_sampling_weights(clips, min_frames=10, balance_actions=1.0)
    per_action = [full[:2].sum(), full[2], full[3]]
    assert np.allclose(per_action, per_action[0])  # each action (None is one) the same total weight
    half = clip_sampling_weights(clips, min_frames=10, balance_actions=0.5)
    share_salsa = half[:2].sum() / half.sum()
    assert plain[:2].sum() / plain.sum() > share_salsa > 1 / 3
    by_source = clip_sampling_weights(clips, min_frames=10, balance_sources=1.0)
    assert np.isclose(by_source[:2].sum(), by_source[2:].sum())  # acrnn and cmu alike
    too_short = clip_sampling_weights([_clip("a.bvh", "walk", 5)] + clips, min_frames=10)
    assert too_short[0] == 0
