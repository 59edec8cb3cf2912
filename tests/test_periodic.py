"""``mirror-periodic`` (a walk's future read off its past, mirrored every half-period) and the shipped
``mixture-periodic`` that draws some of its futures from it. Known answers on synthetic periodic motion,
then the real CMU walk of ``make demo`` and the real shipped weights."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.data.windows import body_window_features
from motion2video.models.base import build_model
from motion2video.models.checkpoint import baseline_bundle, compose_mixture, load_model, save_checkpoint
from motion2video.models.periodic import feature_mirror, fitted_half_period, half_periods, repeat_mirrored

REPO = Path(__file__).resolve().parents[1]
MOCAP = REPO.parent / "shared" / "data" / "mocap"
WALK = REPO / "demo_inputs" / "cmu_walk.npz"  # CMU 07_04, a slow walk (0.95 m/s), 90 frames
PARTS = ("mtvae-add-dlow", "mixer-cvae-dlow", "mirror-periodic", "settle")
SHARES = (17, 17, 12, 4)


@pytest.fixture(scope="module")
def shipped():
    return load_model("mixture-periodic")


def _mirror(x: np.ndarray) -> np.ndarray:
    perm, sign = feature_mirror()
    return x[..., perm] * sign


def _periodic_window(tau: int, length: int = 64, seed: int = 0) -> np.ndarray:
    """(length, 51) features whose joints and root steps repeat mirrored every ``tau`` frames exactly: the first
    ``tau`` frames are random, the rest follow the rule; the root's x, y are summed from its steps."""
    rng = np.random.default_rng(seed)
    x = np.zeros((length, 51))
    x[:tau] = rng.normal(0.0, 0.2, (tau, 51))
    for t in range(tau, length):
        x[t] = _mirror(x[t - tau])
    x[:, 48:50] = np.cumsum(x[:, 48:50], axis=0)  # rows held steps for the root's x, y: make them positions
    return x


def test_the_mirror_swaps_sides_and_negates_the_lateral_axis():
    perm, sign = feature_mirror()
    x = np.arange(51, dtype=float)
    assert np.array_equal(_mirror(_mirror(x)), x)  # a mirror twice is the identity
    # joint 1 (right hip) and joint 4 (left hip) swap: features 0..2 and 9..11
    assert list(perm[0:3]) == [9, 10, 11] and list(perm[9:12]) == [0, 1, 2]
    assert list(perm[48:51]) == [48, 49, 50] and list(sign[48:51]) == [-1.0, 1.0, 1.0]


@pytest.mark.parametrize("tau", [8, 11, 15])
def test_an_exactly_periodic_motion_is_continued_exactly(tau):
    """Known answer: motion that repeats mirrored every tau frames is continued to the last digit by the future
    whose half-period is tau (before the continuation shift and the smoothing, which the rule adds after)."""
    x = _periodic_window(tau)
    obs = torch.from_numpy(x[None, :16])
    perm, sign = (torch.from_numpy(a) for a in feature_mirror())
    got = repeat_mirrored(obs, np.array([float(tau)]), 48, perm, sign)[0, 0].numpy()
    np.testing.assert_allclose(got, x[16:], atol=1e-9)


def test_a_fractional_half_period_reads_between_frames():
    """Known answer of the interpolation: with tau = 11.25 the first future frame is the mirror of 0.75 x frame 5
    + 0.25 x frame 4 (16 - 11.25 = 4.75), and the next one reads frames 5 and 6."""
    x = _periodic_window(11, seed=3)
    obs = torch.from_numpy(x[None, :16])
    perm, sign = (torch.from_numpy(a) for a in feature_mirror())
    got = repeat_mirrored(obs, np.array([11.25]), 3, perm, sign)[0, 0].numpy()
    joints = slice(0, 48)  # the root's x, y are summed from steps: compare the joints and the height
    np.testing.assert_allclose(got[0, joints], _mirror(0.75 * x[5] + 0.25 * x[4])[joints], atol=1e-9)
    np.testing.assert_allclose(got[1, joints], _mirror(0.75 * x[6] + 0.25 * x[5])[joints], atol=1e-9)
    np.testing.assert_allclose(got[0, 50], 0.75 * x[5, 50] + 0.25 * x[4, 50], atol=1e-9)


@pytest.mark.parametrize("tau", [9, 13])
def test_one_future_takes_the_half_period_that_fits_the_observed_frames(tau):
    """Known answer: for motion that repeats mirrored every tau frames the fit finds tau, and a single future of the
    rule is that repetition (through the module, identity statistics, no smoothing)."""
    x = _periodic_window(tau, seed=1)
    cfg = build_model("mirror-periodic").config
    assert fitted_half_period(x[:16], cfg) == tau
    rule = build_model("mirror-periodic", {"smooth_frames": 0.0})
    one = rule.sample(torch.from_numpy(x[None, :16]), num_samples=1, horizon=48)[0, 0].numpy()
    perm, sign = (torch.from_numpy(a) for a in feature_mirror())
    exact = repeat_mirrored(torch.from_numpy(x[None, :16]), np.array([float(tau)]), 48, perm, sign)[0, 0].numpy()
    shift = (2 * x[15] - x[14]) - exact[0]  # the continuation shift, fading over 16 frames
    np.testing.assert_allclose(one, exact + shift * np.exp(-np.arange(48) / 16.0)[:, None], atol=1e-9)


def test_half_periods_spread_over_the_range():
    cfg = build_model("mirror-periodic").config
    assert list(half_periods(cfg, 9)) == [8, 9, 10, 11, 12, 13, 14, 15, 16]
    assert list(half_periods(cfg, 1)) == [12.0]


def test_futures_start_where_the_observation_ends_and_are_normalised_like_it():
    """Through the module, in a checkpoint's normalisation: the first future frame is the last observed frame
    plus the last observed step (as every learned model's), and K futures differ."""
    bundle = load_model("mtvae-add-dlow")
    rule = baseline_bundle("mirror-periodic", bundle.data_config, stats=bundle.stats).model
    joints = np.load(WALK)["joints"][24:88][None]
    feats, _ = body_window_features(joints, layout=bundle.data_config.feature_layout, anchor=15)
    obs = torch.as_tensor(bundle.stats.normalize(feats[:, :16]), dtype=torch.float32)
    out = rule.sample(obs, num_samples=5, horizon=48)
    assert out.shape == (1, 5, 48, 51)
    first = bundle.stats.denormalize(out[0, :, 0].double().numpy())
    np.testing.assert_allclose(first, np.repeat(2 * feats[:, 15] - feats[:, 14], 5, axis=0), atol=1e-4)
    assert float((out[0, 0] - out[0, 4]).abs().max()) > 0.1


def test_a_real_walk_keeps_walking_in_step():
    """The demo's real CMU walk (frames 24..87): the best of 9 half-periods is much closer to the true future than
    standing still, and every future travels within 25% of the truth's distance (the walk keeps its pace)."""
    bundle = load_model("mtvae-add-dlow")
    rule = baseline_bundle("mirror-periodic", bundle.data_config, stats=bundle.stats).model
    joints = np.load(WALK)["joints"][24:88][None]
    feats, _ = body_window_features(joints, layout=bundle.data_config.feature_layout, anchor=15)
    obs = torch.as_tensor(bundle.stats.normalize(feats[:, :16]), dtype=torch.float32)
    fut = bundle.stats.denormalize(rule.sample(obs, num_samples=9, horizon=48).double().numpy())[0]
    truth = feats[0, 16:]
    ade = np.linalg.norm(fut[..., :48] - truth[None, :, :48], axis=-1).mean(-1)  # (9,)
    still = np.linalg.norm(feats[0, 15, :48] - truth[:, :48], axis=-1).mean()
    assert ade.min() < 0.8 * still  # measured 0.287 against 0.435
    travel = np.linalg.norm(fut[:, -1, 48:50] - feats[0, 15, 48:50], axis=-1)
    true_travel = np.linalg.norm(truth[-1, 48:50] - feats[0, 15, 48:50])  # 1.85 m
    assert np.all(np.abs(travel / true_travel - 1) < 0.25)


def test_the_rule_refuses_what_it_cannot_do():
    with pytest.raises(ValueError, match="body3d"):
        build_model("mirror-periodic", {"feature_dim": 58})
    with pytest.raises(ValueError, match="min_half_period"):
        build_model("mirror-periodic", {"min_half_period": 12.0, "max_half_period": 8.0})
    with pytest.raises(ValueError, match="nothing to train"):
        build_model("mirror-periodic").loss(torch.zeros(1, 16, 51), torch.zeros(1, 48, 51), step=0)


def test_shares_decide_the_order_and_equal_shares_keep_k_mod_c(shipped):
    mix = shipped.model
    assert mix.names == list(PARTS)
    assert mix.counts(50) == list(SHARES) and mix.order(5) == [0, 1, 2, 0, 1]
    for k in range(1, 51):  # every prefix of the futures keeps the shares within one future
        assert all(abs(n - k * w) < 1 for n, w in zip(mix.counts(k), mix.shares))
    equal = build_model("mixture", {"components": shipped.meta.config["components"]})
    assert equal.order(9) == [0, 1, 2, 3, 0, 1, 2, 3, 0]
    with pytest.raises(ValueError, match="one positive share per component"):
        build_model("mixture", {"components": shipped.meta.config["components"], "shares": (1.0, 2.0)})


def test_the_periodic_futures_of_the_mixture_are_the_rules(shipped):
    """Known answer of the drawing rule: with 50 futures, the 12 drawn from mirror-periodic are the rule's own 12
    half-periods, in order, in the mixture's normalisation."""
    joints = np.load(WALK)["joints"][24:40][None]
    feats, _ = body_window_features(joints, layout=shipped.data_config.feature_layout, anchor=15)
    obs = torch.as_tensor(shipped.stats.normalize(feats), dtype=torch.float32)
    got = shipped.model.sample(obs, num_samples=50, horizon=48, generator=torch.Generator().manual_seed(0))
    rows = [k for k, c in enumerate(shipped.model.order(50)) if c == 2]
    rule = baseline_bundle("mirror-periodic", shipped.data_config, stats=shipped.stats).model
    torch.testing.assert_close(got[:, rows], rule.sample(obs, num_samples=12, horizon=48), rtol=0, atol=0)


def test_the_shipped_file_is_the_composition_of_the_shipped_parts(shipped, tmp_path):
    """Composed again from the shipped samplers and the rule with the card's shares, saved and loaded, it has the
    shipped file's weights, statistics and record: a retrained component without a recomposed mixture fails."""
    first = load_model(PARTS[0])
    bundles = [first, load_model(PARTS[1])] + [baseline_bundle(rule, first.data_config, stats=first.stats)
                                               for rule in PARTS[2:]]
    composed = compose_mixture(bundles, list(SHARES))
    again = load_model(save_checkpoint(tmp_path / "m.safetensors", model=composed.model, meta=composed.meta))
    assert again.meta.config == shipped.meta.config
    ours, theirs = again.model.state_dict(), shipped.model.state_dict()
    assert ours.keys() == theirs.keys()
    for key in ours:
        torch.testing.assert_close(ours[key], theirs[key], rtol=0, atol=0)


@pytest.mark.slow
def test_bad_mixes_are_refused_in_one_line(tmp_path):
    first = load_model(PARTS[0])
    rule = baseline_bundle("mirror-periodic", first.data_config, stats=first.stats)
    with pytest.raises(InputError, match="first component"):
        compose_mixture([rule, first])
    with pytest.raises(InputError, match="one positive share per model"):
        compose_mixture([first, rule], [1.0, 0.0])
    zero = baseline_bundle("zero-velocity", first.data_config, stats=first.stats)
    with pytest.raises(InputError, match="multi-future rule"):
        compose_mixture([first, zero])
    script = REPO / "scripts" / "make_mixture.py"
    out = tmp_path / "m.safetensors"
    for args in (["mtvae-add-dlow", "mirror-periodic", "--shares", "1,2,3"],
                 ["mtvae-add-dlow", "mirror-periodic", "--shares", "a,b"],
                 ["mirror-periodic", "mtvae-add-dlow"]):
        run = subprocess.run([sys.executable, str(script), *args, "-o", str(out)], capture_output=True, text=True)
        assert run.returncode == 2, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1 and "Traceback" not in run.stderr
        assert not out.exists()
    assert "first model must be a trained sampler" in run.stderr  # the last case: a rule first


@pytest.mark.slow
def test_evaluate_scores_the_rule_in_the_trained_models_windows(tmp_path, capsys):
    """``evaluate --model M --model mirror-periodic``: the rule gets its rows (pooled, macro, per action) on M's
    windows; alone, or beside a face model, it is refused in one line with exit 2."""
    out = tmp_path / "eval.json"
    assert main(["evaluate", "--model", "mtvae-add-dlow", "--model", "mirror-periodic", "--data", str(MOCAP),
                 "--samples", "5", "--stride", "48", "--json", str(out)]) == 0
    import json

    result = json.loads(out.read_text())
    assert "mirror-periodic" in result["results"] and "mirror-periodic" in result["macro"]
    walk = result["per_action"]["mirror-periodic"]["walk"]
    assert walk["ade"] < result["per_action"]["zero-velocity"]["walk"]["ade"]  # it walks on
    capsys.readouterr()
    assert main(["evaluate", "--model", "mirror-periodic", "--data", str(MOCAP)]) == 2
    assert "name a trained model too" in capsys.readouterr().err
    face = REPO.parent / "shared" / "data" / "face" / "livelinkface" / "S07-001.csv"
    assert main(["evaluate", "--model", "mtvae-add-face", "--model", "mirror-periodic", "--data", str(face)]) == 2
    assert "3D body motion" in capsys.readouterr().err
