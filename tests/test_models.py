"""The learned motion models: shapes, gradients, seeded sampling, the flow, and a tiny overfit on real data."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest
import torch

from motion2video.models.base import MODEL_REGISTRY, build_model
from motion2video.models.flow import AffineCoupling, Flow, fit_flow

FACE_CSV = Path(__file__).parents[2] / "shared" / "data" / "face" / "livelinkface" / "alex_rom_3.csv"
LEARNED = ["pred-lstm", "cvae", "mtvae-add", "mtvae-concat", "lcpvae", "behavior"]
STOCHASTIC = [n for n in LEARNED if n != "pred-lstm"]
LATENT = STOCHASTIC
F = 6
TINY = {"feature_dim": F, "hidden_dim": 16}


def _tiny(name: str, **extra: object) -> torch.nn.Module:
    torch.manual_seed(0)
    return build_model(name, {**TINY, **extra})


def _batch(b: int = 3, to: int = 5, tf: int = 7) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(123)
    return torch.randn(b, to, F, generator=g), torch.randn(b, tf, F, generator=g)


def _sample(model: torch.nn.Module, obs: torch.Tensor, *, k: int, horizon: int, seed: int) -> torch.Tensor:
    extra = {"use_flow": False} if isinstance(model, MODEL_REGISTRY["behavior"].model_cls) else {}
    gen = torch.Generator().manual_seed(seed)
    return model.sample(obs, num_samples=k, horizon=horizon, generator=gen, **extra)



# ---------------------------------------------------------------------------------------------- registry


def test_registry_names_and_kinds() -> None:
    for name in LEARNED:
        assert name in MODEL_REGISTRY
    assert MODEL_REGISTRY["pred-lstm"].kind == "deterministic"
    assert all(MODEL_REGISTRY[n].kind == "stochastic" for n in STOCHASTIC)
    for name in LEARNED:  # configs are frozen dataclasses and rebuild the same model
        model = build_model(name)
        assert dataclasses.is_dataclass(model.config)
        with pytest.raises(dataclasses.FrozenInstanceError):
            model.config.feature_dim = 3  # type: ignore[misc]
    with pytest.raises(KeyError):
        build_model("cvae", {"no_such_field": 1})


def test_mtvae_variant_must_match_its_name() -> None:
    with pytest.raises(ValueError, match="transform"):
        build_model("mtvae-add", {"transform": "concat"})
    with pytest.raises(ValueError, match="transform"):
        build_model("mtvae-concat", {"transform": "add"})


def test_default_models_are_small() -> None:
    for name in LEARNED:
        n = sum(p.numel() for p in build_model(name).parameters())
        assert n < 3_000_000, (name, n)  # well under 30 MB in float32


# ---------------------------------------------------------------------------------------------- shapes


@pytest.mark.parametrize("name", LEARNED)
def test_loss_and_sample_shapes(name: str) -> None:
    model = _tiny(name)
    obs, future = _batch()
    out = model.loss(obs, future, step=10)
    assert out.total.ndim == 0 and torch.isfinite(out.total)
    assert all(isinstance(v, float) for v in out.terms.values()) and "recon" in out.terms
    model.eval()
    samples = _sample(model, obs, k=4, horizon=11, seed=0)  # horizon differs from training
    assert samples.shape == (3, 4, 11, F)
    assert torch.isfinite(samples).all()


@pytest.mark.parametrize("name", LATENT)
def test_encode_decode_shapes(name: str) -> None:
    model = _tiny(name, latent_dim=5)
    obs, future = _batch()
    post = model.encode(obs, future)
    assert post.mu.shape == post.logvar.shape == (3, 5)
    assert model.decode(obs, post.mu, horizon=9).shape == (3, 9, F)


@pytest.mark.parametrize("name", LEARNED)
def test_bad_shapes_are_rejected(name: str) -> None:
    model = _tiny(name)
    obs, future = _batch()
    with pytest.raises(ValueError):
        model.loss(obs[..., :-1], future[..., :-1], step=0)
    with pytest.raises(ValueError):
        _sample(model, obs, k=0, horizon=5, seed=0)


# ---------------------------------------------------------------------------------------------- gradients


def _assert_grads(params: dict[str, torch.nn.Parameter], *, nonzero: bool) -> None:
    for pname, p in params.items():
        has = p.grad is not None and p.grad.abs().sum() > 0
        assert has == nonzero, f"{pname}: gradient {'missing' if nonzero else 'unexpected'}"


@pytest.mark.parametrize("name", [n for n in LEARNED if n != "behavior"])
@pytest.mark.parametrize("step", [0, 5000])
def test_gradients_reach_every_parameter(name: str, step: int) -> None:
    model = _tiny(name)
    obs, future = _batch()
    model.loss(obs, future, step=step).total.backward()
    _assert_grads(dict(model.named_parameters()), nonzero=True)


def test_mtvae_context_free_decoder_gradients() -> None:
    model = _tiny("mtvae-add", context_free_decoder=True)
    assert model.latent_decoder.fc1.in_features == model.config.latent_dim
    model.loss(*_batch(), step=50).total.backward()
    _assert_grads(dict(model.named_parameters()), nonzero=True)


def test_behavior_parameter_groups_and_alternating_gradients() -> None:
    model = _tiny("behavior")
    groups = model.parameter_groups()
    names = {id(p): n for n, p in model.named_parameters()}
    main = {names[id(p)]: p for p in groups["main"]}
    aux = {names[id(p)]: p for p in groups["auxiliary"]}
    flow = {n: p for n, p in model.named_parameters() if n.startswith("flow.")}
    assert set(aux) == {n for n in names.values() if n.startswith("regressor.")}
    assert set(main) | set(aux) | set(flow) == set(names.values()) and not set(main) & set(aux)
    obs, future = _batch()
    model.train()
    model.loss(obs, future, step=0).total.backward()
    _assert_grads(main, nonzero=True)
    _assert_grads(flow, nonzero=False)
    model.zero_grad(set_to_none=True)
    model.auxiliary_loss(obs, future).total.backward()
    _assert_grads(aux, nonzero=True)
    _assert_grads(main, nonzero=False)  # z is detached: the regressor step trains only the regressor


# ---------------------------------------------------------------------------------------------- seeded sampling


@pytest.mark.parametrize("name", STOCHASTIC)
def test_sampling_is_seeded(name: str) -> None:
    model = _tiny(name).eval()
    obs, _ = _batch()
    a = _sample(model, obs, k=3, horizon=6, seed=0)
    b = _sample(model, obs, k=3, horizon=6, seed=0)
    c = _sample(model, obs, k=3, horizon=6, seed=1)
    torch.testing.assert_close(a, b, rtol=0, atol=0)
    assert (a - c).abs().max() > 1e-4
    assert (a[:, 0] - a[:, 1]).abs().max() > 1e-4, "the K samples of one context must differ"


def test_pred_lstm_returns_identical_copies() -> None:
    model = _tiny("pred-lstm").eval()
    obs, _ = _batch()
    a = _sample(model, obs, k=4, horizon=6, seed=0)
    b = _sample(model, obs, k=4, horizon=6, seed=1)
    torch.testing.assert_close(a, b, rtol=0, atol=0)
    for k in range(1, 4):
        torch.testing.assert_close(a[:, k], a[:, 0], rtol=0, atol=0)


@pytest.mark.parametrize("name", STOCHASTIC)
def test_batched_sampling_matches_per_context_sampling(name: str) -> None:
    """Sampling several contexts at once gives each context the rows b*K .. b*K+K-1 of one noise draw."""
    model = _tiny(name).eval()
    obs, _ = _batch(b=2)
    both = _sample(model, obs, k=3, horizon=5, seed=7)
    assert both.shape == (2, 3, 5, F)
    first = _sample(model, obs[:1], k=3, horizon=5, seed=7)  # same generator state -> first 3 noise rows
    torch.testing.assert_close(both[:1], first, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("name", LEARNED)
def test_state_dict_round_trip_rebuilds_the_model(name: str) -> None:
    model = _tiny(name).eval()
    if name == "behavior":
        model.kl_multiplier.fill_(2.5)
        model.fit_flow(torch.randn(64, model.config.latent_dim), steps=3)
    clone = build_model(name, dataclasses.asdict(model.config))
    clone.load_state_dict(model.state_dict())
    clone.eval()
    obs, _ = _batch()
    gen_kwargs = {"num_samples": 2, "horizon": 4}
    a = model.sample(obs, generator=torch.Generator().manual_seed(3), **gen_kwargs)
    b = clone.sample(obs, generator=torch.Generator().manual_seed(3), **gen_kwargs)
    torch.testing.assert_close(a, b, rtol=0, atol=0)
    if name == "behavior":
        assert float(clone.kl_multiplier) == 2.5 and bool(clone.flow_fitted)


# ---------------------------------------------------------------------------------------------- behaviour API


def test_behavior_transfer_api_and_flow_sampling() -> None:
    model = _tiny("behavior", latent_dim=4, flow_blocks=2, flow_hidden=16).eval()
    obs, future = _batch()
    sequence = torch.cat([obs[:, -1:], future], dim=1)  # (B, 1+Tf, F): starts at its posture
    z = model.behavior_latent(sequence)
    assert z.shape == (3, 4)
    torch.testing.assert_close(z, model.encode(obs, future).mu)
    start = torch.randn(3, F)
    enacted = model.transfer(z, start, 10)
    assert enacted.shape == (3, 10, F)
    with pytest.raises(RuntimeError, match="flow"):
        model.sample(obs, num_samples=2, horizon=5)
    gen = torch.Generator().manual_seed(0)
    latents = model.posterior_latents(obs.repeat(20, 1, 1), future.repeat(20, 1, 1), generator=gen)
    assert latents.shape == (60, 4)
    result = model.fit_flow(latents, steps=60, batch_size=32)
    assert len(result.losses) == 60 and np.mean(result.losses[-10:]) < np.mean(result.losses[:10])
    out = model.sample(obs, num_samples=2, horizon=5, generator=torch.Generator().manual_seed(0))
    assert out.shape == (3, 2, 5, F) and torch.isfinite(out).all()


def test_behavior_options_velocities_z_at_every_step_and_root_weight() -> None:
    """The encoder reads [frames, velocities], the decoder gets z at every step, and the root features' error
    is weighted: the reconstruction error grows by exactly (w - 1) x the root part."""
    obs, future = _batch()
    model = _tiny("behavior", latent_dim=4, decoder_feeds_z=True, encoder_velocities=True).eval()
    assert model.encoder.cell.w_x.in_features == 2 * F and _tiny("behavior").encoder.cell.w_x.in_features == F
    assert model.decoder.cell.w_x.in_features == F + 4
    sequence = torch.cat([obs[:, -1:], future], dim=1)
    z = model.behavior_latent(sequence)
    assert model.transfer(z, torch.randn(3, F), 6).shape == (3, 6, F)
    pred, target = torch.randn(3, 7, F), torch.randn(3, 7, F)
    plain = _tiny("behavior").reconstruction_error(pred, target)
    weighted = _tiny("behavior", root_weight=4.0, root_dims=2).reconstruction_error(pred, target)
    root = (pred - target)[..., -2:].pow(2).sum(dim=(1, 2)).mean()
    torch.testing.assert_close(weighted, plain + 3.0 * root)


def test_motion_stats_error_penalises_sluggish_motion_and_not_a_phase_shift() -> None:
    """The liveliness term is 0 for the true sequence and for a time-shifted copy of a periodic one (same
    speed, other phase), and positive for a slowed-down (half-amplitude) copy."""
    from motion2video.models.blocks import motion_stats_error

    t = torch.arange(49, dtype=torch.float32)
    wave = torch.sin(2 * np.pi * t / 12)[None, :, None].repeat(2, 1, F)  # (2, 49, F), period 12 frames
    true, start = wave[:, 1:], wave[:, 0]
    shifted = torch.sin(2 * np.pi * (t + 12) / 12)[None, 1:, None].repeat(2, 1, F)
    assert float(motion_stats_error(true, true, start)) == 0.0
    assert float(motion_stats_error(shifted, true, start)) < 1e-6
    assert float(motion_stats_error(0.5 * true, true, start)) > 0.1
    model = _tiny("behavior", motion_stats_weight=3.0)
    model.train()
    obs, future = _batch()
    assert torch.isfinite(model.loss(obs, future, step=0).total)


@pytest.mark.parametrize("name", ["mtvae-add", "lcpvae"])
def test_liveliness_term_adds_weight_times_motion_stats_error_to_the_loss(name: str) -> None:
    """``motion_stats_weight`` adds exactly weight x the liveliness term of the reconstruction to the loss
    (same seed, same noise: every other term is unchanged), and 0 leaves the paper's loss as it was."""
    obs, future = _batch()
    losses = {}
    for w in (0.0, 7.0):
        model = _tiny(name, motion_stats_weight=w).train()
        torch.manual_seed(5)
        losses[w] = model.loss(obs, future, step=2000)
    assert losses[0.0].terms["lively"] == 0.0
    lively = losses[7.0].terms["lively"]
    assert lively > 0.0
    torch.testing.assert_close(float(losses[7.0].total.detach()), float(losses[0.0].total.detach()) + 7.0 * lively,
                               rtol=1e-5, atol=1e-3)
    losses[7.0].total.backward()


def test_velocity_input_decoder_reads_the_observed_velocity() -> None:
    """MT-VAE's ``velocity_input``: the decoder's first step depends on the second-to-last observed frame (the
    observed velocity), the default decoder's does not; loss and sampling run with it."""
    obs, future = _batch()
    moved = obs.clone()
    moved[:, -2] += 1.0  # same last frame, other observed velocity
    for velocity, differs in ((True, True), (False, False)):
        model = _tiny("mtvae-add", velocity_input=velocity).eval()
        z = torch.randn(3, model.config.latent_dim, generator=torch.Generator().manual_seed(1))
        with torch.no_grad():
            e_a = model.encoder(obs)[:, -1]
            a = model._decode_sequence(model._future_feature(e_a, z), obs, 4)
            b = model._decode_sequence(model._future_feature(e_a, z), moved, 4)
        assert (not torch.allclose(a, b)) == differs
    model = _tiny("mtvae-add", velocity_input=True).train()
    model.loss(obs, future, step=10).total.backward()
    assert _sample(model.eval(), obs, k=2, horizon=5, seed=0).shape == (3, 2, 5, F)


def test_behavior_root_trajectory_decoder_follows_a_given_path_or_makes_its_own() -> None:
    """With ``root_trajectory`` the re-enactment's root features are exactly the given path; without a path
    the decoder generates its own root; training mixes both (its loss backpropagates)."""
    from motion2video.stages.latents import behavior_root

    model = _tiny("behavior", latent_dim=4, root_trajectory=True, root_dims=2)
    obs, future = _batch()
    model.train()
    model.loss(obs, future, step=0).total.backward()
    assert model.decoder.cell.w_x.weight.grad is not None
    model.eval()
    z, start = torch.randn(3, 4), torch.randn(3, F)
    path = torch.randn(3, 7, 2)
    with torch.no_grad():
        along = model.transfer(z, start, 7, root=path)
        free = model.transfer(z, start, 7)
    torch.testing.assert_close(along[..., -2:], path)
    assert not torch.allclose(free[..., -2:], path) and torch.isfinite(free).all()
    source = np.random.default_rng(0).normal(size=(3, 8, F)).astype(np.float32)
    root = behavior_root(model, source, start.numpy())
    np.testing.assert_allclose(root[..., 0], source[:, 1:, -2])  # horizontal: the source's own relative path
    np.testing.assert_allclose(root[..., 1] - source[:, 1:, -1], np.repeat((start.numpy()[:, -1] - source[:, 0, -1])[:, None], 7, 1), rtol=1e-5, atol=1e-5)
    assert behavior_root(_tiny("behavior"), source, start.numpy()) is None


# ---------------------------------------------------------------------------------------------- flow


def _random_flow(dim: int) -> Flow:
    torch.manual_seed(0)
    flow = Flow(dim, num_blocks=3, hidden_dim=16).double()
    flow.train()
    flow(torch.randn(32, dim, dtype=torch.float64) * 2.0 + 1.0)  # actnorm data-dependent init
    with torch.no_grad():  # move the couplings away from their identity initialisation
        for layer in flow.layers:
            if isinstance(layer, AffineCoupling):
                for p in layer.net.parameters():
                    p.add_(0.3 * torch.randn_like(p))
    return flow.eval()


def test_flow_is_invertible() -> None:
    flow = _random_flow(5)
    x = torch.randn(7, 5, dtype=torch.float64)
    u, _ = flow(x)
    assert (u - x).abs().max() > 1e-2  # not the identity
    torch.testing.assert_close(flow.inverse(u), x, rtol=1e-9, atol=1e-9)
    torch.testing.assert_close(flow(flow.inverse(x))[0], x, rtol=1e-9, atol=1e-9)


def test_flow_logdet_matches_autograd_jacobian() -> None:
    flow = _random_flow(4)
    x = torch.randn(3, 4, dtype=torch.float64)
    _, logdet = flow(x)
    for i in range(3):
        jac = torch.autograd.functional.jacobian(lambda v: flow(v[None])[0][0], x[i])  # (4, 4)
        torch.testing.assert_close(logdet[i], torch.linalg.slogdet(jac).logabsdet, rtol=1e-9, atol=1e-9)


def test_fit_flow_learns_a_non_gaussian_cloud() -> None:
    g = torch.Generator().manual_seed(0)
    x1 = torch.randn(1024, generator=g)
    banana = torch.stack([x1, x1.pow(2) + 0.2 * torch.randn(1024, generator=g), torch.randn(1024, generator=g)], 1)
    flow = Flow(3, num_blocks=4, hidden_dim=32)
    result = fit_flow(flow, banana, steps=150, batch_size=256, lr=3e-3)
    assert not flow.training and bool(flow.layers[0].initialized)
    # actnorm's init already fits the best Gaussian: the couplings must do better than that
    assert np.mean(result.losses[-10:]) < result.losses[0] - 0.3
    with pytest.raises(ValueError):
        fit_flow(flow, torch.randn(10, 4), steps=1)


# ---------------------------------------------------------------------------------------------- overfit (real data)


def _face_windows(n: int, length: int) -> torch.Tensor:
    """``n`` windows of ``length`` frames of 52 real ARKit coefficients, z-scored: (n, length, 52)."""
    with FACE_CSV.open(newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], [r for r in rows[1:] if len(r) == len(rows[0])]
    cols = slice(2, 2 + 52)  # Timecode, BlendShapeCount, then the 52 blendshapes
    assert header[2] == "EyeBlinkLeft" and header[2 + 51] == "TongueOut"
    data = np.asarray([[float(v) for v in r[cols]] for r in body], dtype=np.float32)  # (T, 52) at ~30 fps
    starts = np.linspace(200, len(data) - length - 200, n).astype(int)
    windows = np.stack([data[s : s + length] for s in starts])  # (n, length, 52)
    mean = windows.mean(axis=(0, 1))
    std = np.maximum(windows.std(axis=(0, 1)), 0.05)
    return torch.from_numpy((windows - mean) / std)


@pytest.mark.slow
@pytest.mark.parametrize("name", LEARNED)
def test_tiny_overfit_on_real_face_windows(name: str) -> None:
    windows = _face_windows(4, 8 + 12)
    obs, future = windows[:, :8], windows[:, 8:]
    cfg = {"feature_dim": 52, "hidden_dim": 32}
    if name != "pred-lstm":
        cfg["latent_dim"] = 8
    if name == "lcpvae":
        cfg["teacher_forcing_steps"] = 100  # fully autoregressive for the second half
    torch.manual_seed(0)
    model = build_model(name, cfg)
    model.train()
    groups = model.parameter_groups() if hasattr(model, "parameter_groups") else {"main": list(model.parameters())}
    opts = {k: torch.optim.Adam(v, lr=3e-3) for k, v in groups.items()}
    recon = []
    for step in range(250):
        out = model.loss(obs, future, step=step)
        opts["main"].zero_grad(set_to_none=True)
        out.total.backward()
        opts["main"].step()
        if "auxiliary" in opts:
            aux = model.auxiliary_loss(obs, future)
            opts["auxiliary"].zero_grad(set_to_none=True)
            aux.total.backward()
            opts["auxiliary"].step()
        recon.append(out.terms["recon"])
    first, last = np.mean(recon[:5]), np.mean(recon[-10:])
    assert last < 0.5 * first, f"{name}: reconstruction {first:.1f} -> {last:.1f}"
