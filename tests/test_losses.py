"""Every loss term of the motion models against a hand-computed value on a tiny input."""

from __future__ import annotations

import math

import pytest
import torch
from torch.distributions import Normal, kl_divergence

from motion2video.models.base import build_model
from motion2video.models.base import LatentPosterior
from motion2video.models.behavior import dual_ascent
from motion2video.models.blocks import (
    kl_diag_gaussians,
    kl_std_normal,
    linear_ramp,
    logistic_ramp,
    reconstruction_l1,
    reconstruction_mse,
    reparameterize,
    teacher_forcing_probability,
)
from motion2video.models.flow import Flow
from motion2video.models.lcpvae import lcp_kl, lcp_posterior
from motion2video.models.mtvae import cycle_consistency, motion_coherence

F = 5



def _gaussians(seed: int, b: int = 3, z: int = 4) -> tuple[torch.Tensor, ...]:
    g = torch.Generator().manual_seed(seed)
    return tuple(torch.randn(b, z, generator=g, dtype=torch.float64) for _ in range(4))


# ---------------------------------------------------------------------------------------------- KL


def test_kl_std_normal_matches_torch() -> None:
    mu, logvar, _, _ = _gaussians(0)
    ref = kl_divergence(Normal(mu, torch.exp(0.5 * logvar)), Normal(0.0, 1.0)).sum(-1)
    torch.testing.assert_close(kl_std_normal(LatentPosterior(mu, logvar)), ref)
    assert torch.allclose(kl_std_normal(LatentPosterior(torch.zeros(2, 3), torch.zeros(2, 3))), torch.zeros(2))


def test_kl_between_diagonal_gaussians_matches_torch() -> None:
    mu1, lv1, mu2, lv2 = _gaussians(1)
    ref = kl_divergence(Normal(mu1, torch.exp(0.5 * lv1)), Normal(mu2, torch.exp(0.5 * lv2))).sum(-1)
    torch.testing.assert_close(kl_diag_gaussians(LatentPosterior(mu1, lv1), LatentPosterior(mu2, lv2)), ref)


def test_kl_by_hand_one_dimension() -> None:
    # KL(N(1, 4) || N(0, 1)) = 0.5 (4 + 1 - 1 - ln 4)
    post = LatentPosterior(torch.tensor([[1.0]]).double(), torch.tensor([[math.log(4.0)]]).double())
    got = kl_std_normal(post)
    assert got.item() == pytest.approx(0.5 * (4.0 + 1.0 - 1.0 - math.log(4.0)))


def test_reparameterize() -> None:
    mu = torch.tensor([[1.0, -2.0]])
    logvar = torch.tensor([[math.log(4.0), 0.0]])
    z = reparameterize(LatentPosterior(mu, logvar), torch.tensor([[0.5, -1.0]]))
    torch.testing.assert_close(z, torch.tensor([[2.0, -3.0]]))


# ---------------------------------------------------------------------------------------------- LCP-VAE


def test_lcp_posterior_is_the_extended_reparameterisation() -> None:
    mu, logvar, mu_c, logvar_c = _gaussians(2)
    eps = torch.randn(3, 4, generator=torch.Generator().manual_seed(9), dtype=torch.float64)
    z_c = reparameterize(LatentPosterior(mu_c, logvar_c), eps)  # Eq. 3
    z = mu + torch.exp(0.5 * logvar) * z_c  # Eq. 4
    post = lcp_posterior(LatentPosterior(mu, logvar), LatentPosterior(mu_c, logvar_c))
    torch.testing.assert_close(reparameterize(post, eps), z)


def test_lcp_kl_matches_torch_and_equation_7() -> None:
    mu, logvar, mu_c, logvar_c = _gaussians(3)
    sigma, sigma_c = torch.exp(0.5 * logvar), torch.exp(0.5 * logvar_c)
    ref = kl_divergence(Normal(mu + sigma * mu_c, sigma * sigma_c), Normal(mu_c, sigma_c)).sum(-1)  # Eq. 6
    got = lcp_kl(LatentPosterior(mu, logvar), LatentPosterior(mu_c, logvar_c))
    torch.testing.assert_close(got, ref)
    # Eq. 7 (sign and sigma-vs-Sigma slips corrected): 1/2 [-log|S| - d + tr S + (mu_c - mu - s mu_c)^2 / s_c^2]
    d = mu.shape[1]
    eq7 = 0.5 * (
        -logvar.sum(-1) - d + sigma.pow(2).sum(-1) + ((mu_c - (mu + sigma * mu_c)).pow(2) / sigma_c.pow(2)).sum(-1)
    )
    torch.testing.assert_close(got, eq7)
    # zero exactly when the data posterior adds nothing: mu = 0, sigma = 1
    zero = lcp_kl(LatentPosterior(torch.zeros_like(mu), torch.zeros_like(logvar)), LatentPosterior(mu_c, logvar_c))
    torch.testing.assert_close(zero, torch.zeros(3, dtype=torch.float64))


def test_lcp_prior_kl_freezes_cs_vae() -> None:
    torch.manual_seed(0)
    model = build_model("lcpvae", {"feature_dim": F, "hidden_dim": 16, "latent_dim": 4, "mlp_dim": 16})
    obs, future = torch.randn(3, 6, F), torch.randn(3, 7, F)
    cond, h_t = model.condition_posterior(obs)
    data = model.data_params(h_t.detach(), future)
    mu, logvar = data.mu, data.logvar
    kl_cs, kl_lcp = model.prior_kl(cond, data)
    cs_params = list(model.cs_encoder.parameters()) + list(model.cs_head.parameters())
    grads = torch.autograd.grad(kl_lcp, cs_params + list(model.lcp_head.parameters()), allow_unused=True)
    assert all(g is None for g in grads[: len(cs_params)]), "Eq. 6 must not move the CS-VAE posterior"
    assert all(g is not None and g.abs().sum() > 0 for g in grads[len(cs_params) :])
    grads_cs = torch.autograd.grad(kl_cs, cs_params)
    assert all(g.abs().sum() > 0 for g in grads_cs), "Eq. 5 trains the CS-VAE"
    ref = kl_divergence(
        Normal(mu + torch.exp(0.5 * logvar) * cond.mu, torch.exp(0.5 * (logvar + cond.logvar))),
        Normal(cond.mu, torch.exp(0.5 * cond.logvar)),
    ).sum(-1).mean()
    torch.testing.assert_close(kl_lcp, ref, rtol=1e-5, atol=1e-5)


# ---------------------------------------------------------------------------------------------- reconstruction


def test_reconstruction_losses_by_hand() -> None:
    pred = torch.tensor([[[1.0, 2.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 3.0]]])  # (B=2, T=2, F=2)
    target = torch.zeros_like(pred)
    # per sequence sums: L1 3 and 3 -> mean 3; MSE 5 and 9 -> mean 7
    assert reconstruction_l1(pred, target).item() == pytest.approx(3.0)
    assert reconstruction_mse(pred, target).item() == pytest.approx(7.0)


# ---------------------------------------------------------------------------------------------- MT-VAE terms


def test_cycle_consistency_by_hand() -> None:
    z = torch.zeros(2, 2)
    z_star = torch.tensor([[3.0, 4.0], [0.0, 1.0]])
    assert cycle_consistency(z_star, z).item() == pytest.approx((5.0 + 1.0) / 2)


def test_motion_coherence_by_hand() -> None:
    last = torch.tensor([[0.0, 0.0]])  # x_T
    target = torch.tensor([[[1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [4.0, 0.0]]])  # v = (1,0) each step
    pred = torch.tensor([[[1.0, 0.0], [5.0, 3.0], [6.0, 3.0], [0.0, 0.0]]])  # v* = (1,0), (4,3), (1,0), ...
    # |v* - v| = 0, |(3,3)| = 3 sqrt 2, 0
    assert motion_coherence(pred, target, last_obs=last, steps=3).item() == pytest.approx(math.sqrt(18.0) / 3)
    assert motion_coherence(pred, target, last_obs=last, steps=1).item() == pytest.approx(0.0)
    # K longer than the sequence uses all of it: the 4th difference is (-6,-3) - (1,0) = (-7,-3)
    four = (math.sqrt(18.0) + math.sqrt(58.0)) / 4
    assert motion_coherence(pred, target, last_obs=last, steps=8).item() == pytest.approx(four)


@pytest.mark.parametrize("name", ["mtvae-add", "mtvae-concat"])
@pytest.mark.parametrize("context_free", [False, True])
def test_mtvae_cycle_latent_is_eq_2_3(name: str, context_free: bool) -> None:
    torch.manual_seed(0)
    cfg = {"feature_dim": F, "hidden_dim": 8, "latent_dim": 3, "mlp_dim": 8, "context_free_decoder": context_free}
    model = build_model(name, cfg)
    e_a, z = torch.randn(2, 8), torch.randn(2, 3)
    dec_in = z if context_free else torch.cat([z, e_a], dim=-1)
    if name == "mtvae-add":  # z* = h_{T->z}(h_{z->T}(z, e_A))
        enc_in = model.latent_decoder(dec_in)
    else:  # z* = h_{e->z}([e_A, h_{z->e}(z, e_A)])
        enc_in = torch.cat([e_a, model.latent_decoder(dec_in)], dim=-1)
    expected = model.latent_encoder(enc_in)[:, :3]
    torch.testing.assert_close(model._cycle_latent(e_a, z), expected)


# ---------------------------------------------------------------------------------------------- totals


def _total_from_terms(name: str, terms: dict[str, float], model: torch.nn.Module) -> float:
    c = model.config
    if name == "pred-lstm":
        return terms["recon"]
    if name == "cvae":
        return terms["recon"] + terms["kl_weight"] * terms["kl"]
    if name.startswith("mtvae"):
        return (
            terms["recon"]
            + terms["kl_weight"] * terms["kl"]
            + c.lambda_cycle * terms["cycle"]
            + c.lambda_motion * terms["motion"]
        )
    if name == "lcpvae":
        return terms["kl_weight"] * (terms["kl_cs"] + terms["kl"]) + terms["recon_obs"] + terms["recon"]
    if name == "behavior":
        return (
            terms["recon"]
            + terms["kl_multiplier"] * (terms["kl"] - c.kl_budget)
            - c.gamma_c * terms["regressor_error"]
        )
    raise AssertionError(name)


@pytest.mark.parametrize("name", ["pred-lstm", "cvae", "mtvae-add", "mtvae-concat", "lcpvae", "behavior"])
def test_total_loss_is_the_weighted_sum_of_its_terms(name: str) -> None:
    torch.manual_seed(0)
    model = build_model(name, {"feature_dim": F, "hidden_dim": 16})
    model.eval()  # no multiplier update
    out = model.loss(torch.randn(2, 4, F), torch.randn(2, 6, F), step=300)
    assert out.total.item() == pytest.approx(_total_from_terms(name, out.terms, model), rel=1e-5, abs=1e-4)


def test_mtvae_default_weights_follow_the_paper() -> None:
    add, concat = build_model("mtvae-add").config, build_model("mtvae-concat").config
    assert (add.coherence_steps, add.lambda_cycle, add.lambda_motion) == (8, 5.0, 5.0)
    assert (concat.coherence_steps, concat.lambda_cycle, concat.lambda_motion) == (8, 5.0, 20.0)


# ---------------------------------------------------------------------------------------------- schedules


def test_linear_ramp() -> None:
    assert [linear_ramp(s, length=100) for s in (-5, 0, 50, 100, 1000)] == [0.0, 0.0, 0.5, 1.0, 1.0]
    assert linear_ramp(30, start=20, length=40) == pytest.approx(0.25)
    assert linear_ramp(5, length=0) == 1.0


def test_logistic_ramp() -> None:
    assert logistic_ramp(500, midpoint=500, width=100.0) == pytest.approx(0.5)
    assert logistic_ramp(600, midpoint=500, width=100.0) == pytest.approx(1.0 / (1.0 + math.exp(-1.0)))
    assert logistic_ramp(-10**6, midpoint=500, width=100.0) == 0.0
    values = [logistic_ramp(s, midpoint=500, width=100.0) for s in range(0, 2001, 100)]
    assert values == sorted(values) and values[0] < 0.01 and values[-1] > 0.99


def test_teacher_forcing_probability_anneals_to_zero() -> None:
    assert [teacher_forcing_probability(s, steps=10) for s in (0, 5, 10, 20)] == [1.0, 0.5, 0.0, 0.0]


# ---------------------------------------------------------------------------------------------- behaviour


def test_dual_ascent_sign() -> None:
    assert dual_ascent(1.0, constraint=40.0, budget=30.0, lr=0.01) == pytest.approx(1.1)  # over budget: up
    assert dual_ascent(1.0, constraint=20.0, budget=30.0, lr=0.01) == pytest.approx(0.9)  # under: down
    assert dual_ascent(0.05, constraint=0.0, budget=30.0, lr=0.01) == 0.0  # projected onto >= 0


@pytest.mark.parametrize("budget, direction", [(0.0, 1), (1e6, -1)])
def test_behavior_loss_updates_the_multiplier(budget: float, direction: int) -> None:
    torch.manual_seed(0)
    model = build_model("behavior", {"feature_dim": F, "hidden_dim": 16, "kl_budget": budget, "kl_multiplier_lr": 1e-6})
    obs, future = torch.randn(2, 4, F), torch.randn(2, 6, F)
    before = float(model.kl_multiplier)
    model.eval()
    model.loss(obs, future, step=0)
    assert float(model.kl_multiplier) == before, "eval mode must not update the multiplier"
    model.train()
    out = model.loss(obs, future, step=0)
    expected = dual_ascent(before, constraint=out.terms["kl"], budget=budget, lr=1e-6)
    assert float(model.kl_multiplier) == pytest.approx(expected)
    assert (float(model.kl_multiplier) - before) * direction > 0


def test_behavior_main_loss_penalises_regressor_success() -> None:
    torch.manual_seed(0)
    model = build_model("behavior", {"feature_dim": F, "hidden_dim": 16, "gamma_c": 0.5})
    model.eval()
    obs, future = torch.randn(2, 4, F), torch.randn(2, 6, F)
    torch.manual_seed(1)
    base = model.loss(obs, future, step=0)
    with torch.no_grad():  # a regressor that is worse by a constant offset raises its error ...
        model.regressor[-1].bias += 3.0
    torch.manual_seed(1)
    worse = model.loss(obs, future, step=0)
    assert worse.terms["regressor_error"] > base.terms["regressor_error"]
    # ... and lowers the main loss by gamma_C times the increase (all other terms identical)
    drop = 0.5 * (worse.terms["regressor_error"] - base.terms["regressor_error"])
    assert base.total.item() - worse.total.item() == pytest.approx(drop, rel=1e-4)
    # the auxiliary loss is the regressor's own error (same noise -> same value)
    torch.manual_seed(1)
    aux = model.auxiliary_loss(obs, future)
    post = model.encode(obs, future)
    torch.manual_seed(1)
    z = reparameterize(post, torch.randn_like(post.mu))
    ref = (model.regressor(z) - obs[:, -1]).pow(2).sum(-1).mean()
    assert aux.total.item() == pytest.approx(ref.item(), rel=1e-5)


def test_identity_flow_log_prob_is_standard_normal() -> None:
    flow = Flow(4, num_blocks=2, hidden_dim=8).double().eval()  # fresh: actnorm and couplings are identities
    x = torch.randn(5, 4, dtype=torch.float64)
    torch.testing.assert_close(flow.log_prob(x), Normal(0.0, 1.0).log_prob(x).sum(-1))

