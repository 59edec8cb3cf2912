"""DLow sampler on top of a trained MT-VAE: its losses, its frozen base, the CLI, and evaluate's multi-model
comparison with the ADE-per-frame plot."""

from __future__ import annotations

import json

import imageio.v3 as iio
import numpy as np
import pytest
import torch
from safetensors import safe_open

from motion2video.evaluation import metrics as M
from motion2video.models.checkpoint import load_model
from motion2video.cli import main
from motion2video.models.base import build_model
from motion2video.models.dlow import best_of_k_sse, pairwise_diversity
from tests.conftest import link_clips

CLIPS = ("cmu/131_01.bvh", "cmu/01_01.bvh", "mass/mass_pirouette.bvh", "cmu/13_10.bvh")
BASE = json.dumps({"model": {"hidden_dim": 8, "latent_dim": 4, "mlp_dim": 8},
                   "train": {"batch_size": 4, "checkpoint_every": 5, "val_every": 5, "val_windows": 8}})
DLOW = json.dumps({"model": {"num_samples": 6, "hidden_dim": 8},
                   "train": {"batch_size": 4, "checkpoint_every": 5, "val_every": 5, "val_windows": 8}})


@pytest.fixture(scope="module")
def trained(tmp_path_factory, mocap_dir):
    """A tiny mtvae-add (10 steps) and a DLow sampler trained on it (10 steps), through the CLI."""
    data = link_clips(tmp_path_factory.mktemp("mocap_dlow"), mocap_dir, CLIPS)
    out = tmp_path_factory.mktemp("ckpt")
    base, dlow = out / "base.safetensors", out / "base-dlow.safetensors"
    assert main(["train", "--model", "mtvae-add", "--data", str(data), "-o", str(base), "--steps", "10",
                 "--config", BASE, "--no-progress"]) == 0
    assert main(["train", "--model", "dlow", "--base", str(base), "--data", str(data), "-o", str(dlow),
                 "--steps", "10", "--config", DLOW, "--no-progress"]) == 0
    return data, base, dlow


def test_best_of_k_and_diversity_known_answers():
    target = torch.zeros(1, 2, 3)
    futures = torch.stack([torch.full((2, 3), 2.0), torch.full((2, 3), 0.5)])[None]  # (1, K=2, 2, 3)
    assert float(best_of_k_sse(futures, target)) == pytest.approx(6 * 0.25)
    same = torch.zeros(2, 4, 5, 3)
    assert float(pairwise_diversity(same, scale=0.25)) == pytest.approx(1.0)
    apart = torch.arange(4.0)[None, :, None, None].expand(2, 4, 5, 3) * 10
    assert float(pairwise_diversity(apart, scale=0.25)) < 1e-12


def test_initial_maps_are_distinct_and_match_the_prior_variance():
    model = build_model("dlow", {"base_config": {"hidden_dim": 8, "latent_dim": 16, "mlp_dim": 8},
                                 "num_samples": 200, "hidden_dim": 8})
    with torch.no_grad():
        a, b = model.maps(torch.zeros(3, 16, 51))
    assert a.shape == b.shape == (3, 200, 16)
    variance = (a ** 2).mean() + (b ** 2).mean()  # marginal variance of z_k = a eps + b over k
    assert float(variance) == pytest.approx(1.0, abs=0.1)
    assert float(torch.cdist(b[0], b[0]).fill_diagonal_(1.0).min()) > 0.1


def test_training_keeps_the_base_frozen_and_moves_the_maps(trained):
    _, base, dlow = trained
    bundle = load_model(dlow)
    assert bundle.name == "dlow" and bundle.label == "base-dlow"
    assert bundle.meta.config["base_model"] == "mtvae-add"
    with safe_open(str(base), framework="pt") as f:
        for key in f.keys():
            assert torch.equal(bundle.model.state_dict()["base." + key], f.get_tensor(key)), key
    assert float(bundle.model.head[-1].weight.abs().sum()) > 0  # zero at initialisation
    assert bundle.stats.mean.tobytes() == load_model(base).stats.mean.tobytes()


def test_samples_are_seeded_and_extend_past_k(trained):
    bundle = load_model(trained[2])
    obs = torch.zeros(2, 16, 51)
    out = bundle.model.sample(obs, num_samples=9, horizon=5, generator=torch.Generator().manual_seed(3))
    again = bundle.model.sample(obs, num_samples=9, horizon=5, generator=torch.Generator().manual_seed(3))
    assert out.shape == (2, 9, 5, 51) and torch.equal(out, again)
    flat = out[0].reshape(9, -1)
    assert float(torch.cdist(flat, flat).fill_diagonal_(1.0).min()) > 0


def test_evaluate_compares_models_and_plots_ade_per_frame(trained, tmp_path, capsys):
    data, base, dlow = trained
    out = tmp_path / "deep" / "eval.json"
    plot = tmp_path / "deep" / "ade.png"
    assert main(["evaluate", "--model", str(base), "--model", str(dlow), "--data", str(data), "--split", "all",
                 "--samples", "6", "--stride", "32", "--json", str(out), "--plot", str(plot)]) == 0
    payload = json.loads(out.read_text())
    assert set(payload["results"]) == {"base", "base-dlow", "zero-velocity", "last-step", "sequence-motion"}
    for name, row in payload["results"].items():
        curve = payload["ade_per_frame"][name]
        assert len(curve) == 48 and np.mean(curve) == pytest.approx(row["ade"], rel=1e-6)
    image = iio.imread(plot)
    assert image.ndim == 3 and image.shape[0] > 300 and image.std() > 10


def test_ade_per_frame_known_answer():
    gt = np.zeros((2, 3, 2))
    pred = np.zeros((2, 2, 3, 2))
    pred[:, 0, :, 0] = [1.0, 2.0, 3.0]  # mean 2
    pred[:, 1, :, 0] = [0.0, 0.0, 4.5]  # mean 1.5: the best of K
    np.testing.assert_allclose(M.ade_per_frame(pred, gt), [0.0, 0.0, 4.5])
    assert M.ade_per_frame(pred, gt).mean() == pytest.approx(M.ade(pred, gt))


def test_bad_dlow_requests_exit_2(trained, tmp_path, capsys):
    data, base, _ = trained
    out = tmp_path / "x.safetensors"
    assert main(["train", "--model", "dlow", "--data", str(data), "-o", str(out), "--steps", "2"]) == 2
    assert "--base" in capsys.readouterr().err
    assert main(["train", "--model", "mtvae-add", "--base", str(base), "--data", str(data), "-o", str(out),
                 "--steps", "2"]) == 2
    assert main(["evaluate", "--model", str(base), "--model", str(base), "--data", str(data)]) == 2
    assert "share the name" in capsys.readouterr().err
    assert not out.exists()


def test_maps_live_in_a_learned_conditional_prior():
    """Over LCP-VAE, z_k = mu_c + sigma_c * (a_k eps + b_k): the maps are standardised by the base's prior."""
    model = build_model("dlow", {"base_model": "lcpvae", "num_samples": 4, "hidden_dim": 8,
                                 "base_config": {"hidden_dim": 8, "latent_dim": 3, "mlp_dim": 8}}).eval()
    obs = torch.randn(2, 16, 51, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        a, b = model.maps(obs)
        eps = torch.randn(2, 1, 3)
        cond, _ = model.base.condition_posterior(obs)
        z = model.latents(obs, a, b, eps)
    expected = cond.mu[:, None] + torch.exp(0.5 * cond.logvar)[:, None] * (a * eps + b)
    torch.testing.assert_close(z, expected)
    plain = build_model("dlow", {"num_samples": 4, "hidden_dim": 8,
                                 "base_config": {"hidden_dim": 8, "latent_dim": 3, "mlp_dim": 8}})
    assert plain.base_prior(obs) is None
