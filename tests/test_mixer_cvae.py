"""mixer-cvae: a conditional VAE with the DCT MLP-mixer decoder; its latent interface (encode /
decode) is what DLow samples, and its recognition model must carry the future into the latent."""

from __future__ import annotations

import json

import pytest
import torch

import motion2video.models  # noqa: F401  (importing registers the models)
from motion2video.cli import main
from motion2video.models.base import MODEL_REGISTRY, build_model
from motion2video.models.checkpoint import load_model
from motion2video.models.mixer_cvae import fit_future
from tests.conftest import link_clips
from tests.test_mixer import F, _batch, _sample, _two_futures, _without_gradient

TINY = {"feature_dim": F, "observed": 5, "future": 7, "num_coeffs": 8, "hidden_dim": 16, "context_blocks": 1,
        "encoder_blocks": 1, "decoder_blocks": 1, "latent_dim": 4}


def _tiny(**extra: object) -> torch.nn.Module:
    torch.manual_seed(0)
    return build_model("mixer-cvae", {**TINY, **extra})


def test_registered_stochastic_and_small() -> None:
    assert MODEL_REGISTRY["mixer-cvae"].kind == "stochastic"
    n = sum(p.numel() for p in build_model("mixer-cvae").parameters())
    assert 100_000 < n < 3_000_000, n


def test_fit_future_cuts_and_pads() -> None:
    fut = torch.arange(4 * 2, dtype=torch.float32).view(1, 4, 2)
    assert torch.equal(fit_future(fut, 3), fut[:, :3])
    longer = fit_future(fut, 6)
    assert longer.shape == (1, 6, 2) and torch.equal(longer[0, 4:], fut[0, -1].expand(2, 2))


def test_untrained_model_with_the_full_basis_is_zero_velocity() -> None:
    model = _tiny(num_coeffs=12).eval()
    obs, _ = _batch()
    out = _sample(model, obs, k=4, horizon=7, seed=0)
    assert torch.allclose(out, obs[:, None, -1:].expand(-1, 4, 7, -1), atol=1e-5)


def test_shapes_long_horizons_and_the_latent_interface() -> None:
    model = _tiny()
    with torch.no_grad():
        model.head.weight.normal_(0.0, 0.5)
    obs, fut = _batch()
    out = model.loss(obs, fut, step=0)
    assert out.total.ndim == 0 and torch.isfinite(out.total)
    assert set(out.terms) == {"recon", "past", "kl", "kl_weight", "stats"}
    model.eval()
    post = model.encode(obs, fut)
    assert post.mu.shape == post.logvar.shape == (3, 4)
    assert model.encode(obs, fut[:, :4]).mu.shape == (3, 4)  # a shorter future is padded
    z = torch.randn(3, 4)
    long = model.decode(obs, z, horizon=20)  # three chunks of 7 frames with the same z
    assert long.shape == (3, 20, F) and torch.isfinite(long).all()
    assert torch.allclose(long[:, :7], model.decode(obs, z, horizon=7))
    assert model.decode(obs[:, 2:], z, horizon=7).shape == (3, 7, F)  # 3 observed frames: padded
    a, b = _sample(model, obs, k=5, horizon=7, seed=1), _sample(model, obs, k=5, horizon=7, seed=1)
    assert a.shape == (3, 5, 7, F) and torch.equal(a, b)
    assert (a[:, 0] - a[:, 1]).abs().max() > 1e-3  # different latents, different futures
    with pytest.raises(ValueError, match="future"):
        model.loss(obs, fut[:, :5], step=0)


def test_gradients_reach_every_parameter() -> None:
    model = _tiny(stats_weight=1.0)
    with torch.no_grad():
        model.head.weight.normal_(0.0, 0.1)
    obs, fut = _batch()
    model.loss(obs, fut, step=500).total.backward()
    missing = _without_gradient(model)
    assert not missing, missing


def test_the_prior_is_standard_normal_unless_learned() -> None:
    obs, _ = _batch()
    prior, pooled = _tiny().condition_posterior(obs)
    assert torch.equal(prior.mu, torch.zeros(3, 4)) and torch.equal(prior.logvar, torch.zeros(3, 4))
    assert pooled.shape == (3, 16)
    learned = _tiny(learned_prior=True)
    with torch.no_grad():
        learned.prior_head[1].bias.copy_(torch.tensor([5.0, 5.0, 5.0, 5.0, -12.0, -12.0, -12.0, -12.0]))
        learned.prior_head[1].weight.zero_()
    prior, _ = learned.condition_posterior(obs)
    assert torch.allclose(prior.mu, torch.full((3, 4), 5.0))
    with torch.no_grad():
        learned.head.weight.normal_(0.0, 0.5)
    learned.eval()
    a, b = _sample(learned, obs, k=2, horizon=7, seed=1), _sample(learned, obs, k=2, horizon=7, seed=2)
    assert torch.allclose(a, b, atol=2e-2)  # sigma = exp(-6): every sample decodes about z = 5
    z = torch.full((3, 4), 5.0)
    assert torch.allclose(a[:, 0], learned.decode(obs, z, horizon=7), atol=2e-2)


@pytest.mark.parametrize("learned_prior", [False, True])
def test_the_latent_carries_which_of_two_futures(learned_prior: bool) -> None:
    """One context, two futures (up or down): decoded from the recognition model's mean the future is the right
    one, and prior samples land near both."""
    torch.manual_seed(0)
    model = build_model("mixer-cvae", {**TINY, "hidden_dim": 32, "kl_weight": 0.01, "kl_anneal_steps": 50,
                                       "learned_prior": learned_prior})
    obs, fut = _two_futures()
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    for step in range(400):
        loss = model.loss(obs, fut, step=step)
        opt.zero_grad()
        loss.total.backward()
        opt.step()
    model.eval()
    zero_velocity = fut.pow(2).sum(-1).sqrt().mean(-1)  # (2,)
    with torch.no_grad():
        recon = model.decode(obs, model.encode(obs, fut).mu, horizon=7)
    assert torch.all((recon - fut).pow(2).sum(-1).sqrt().mean(-1) < 0.2 * zero_velocity)
    samples = _sample(model, obs[:1], k=20, horizon=7, seed=0)[0]  # (20, 7, F)
    err = torch.stack([(samples - f).pow(2).sum(-1).sqrt().mean(-1) for f in fut])  # (2 modes, 20)
    assert torch.all(err.min(dim=1).values < 0.3 * zero_velocity), err.min(dim=1).values


def test_dlow_samples_a_trained_mixer_cvae_through_the_cli(tmp_path, mocap_dir):
    """The shipped recipe in small: mixer-cvae trained with the training set's feature scales, DLow trained on
    it as its frozen base, both reloaded and sampled."""
    data = link_clips(tmp_path / "mocap", mocap_dir, ("cmu/131_01.bvh", "cmu/01_01.bvh", "cmu/13_10.bvh"))
    base, dlow = tmp_path / "base.safetensors", tmp_path / "base-dlow.safetensors"
    train = {"batch_size": 4, "checkpoint_every": 5, "val_every": 5, "val_windows": 8}
    cfg = {"model": {"hidden_dim": 16, "context_blocks": 1, "encoder_blocks": 1, "decoder_blocks": 1,
                     "latent_dim": 4, "stats_weight": 1.0}, "train": train}
    assert main(["train", "--model", "mixer-cvae", "--data", str(data), "-o", str(base), "--steps", "6",
                 "--config", json.dumps(cfg), "--no-progress"]) == 0
    dlow_cfg = {"model": {"num_samples": 5, "hidden_dim": 8}, "train": train}
    assert main(["train", "--model", "dlow", "--base", str(base), "--data", str(data), "-o", str(dlow),
                 "--steps", "4", "--config", json.dumps(dlow_cfg), "--no-progress"]) == 0
    base_bundle, bundle = load_model(base), load_model(dlow)
    assert base_bundle.model.config.feature_scale and len(base_bundle.model.config.feature_scale) == 51
    assert bundle.model.config.base_model == "mixer-cvae"
    obs = torch.zeros(2, 16, 51)
    samples = bundle.model.sample(obs, num_samples=5, horizon=60, generator=torch.Generator().manual_seed(0))
    assert samples.shape == (2, 5, 60, 51) and torch.isfinite(samples).all()
