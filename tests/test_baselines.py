"""The three data-driven baselines: registry, shapes, and exactness in joint space on real mocap."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motion2video.models.checkpoint import baseline_bundle
from motion2video.data.dataset import DatasetConfig, build_dataset, decode_samples
from motion2video.models.base import MODEL_REGISTRY, build_model
from motion2video.models.baselines import BASELINES


@pytest.fixture(scope="module")
def walk_windows(mocap_dir):
    """Windows of one real walking clip (CMU 131_02, 260 frames at 25 fps) with its own normalisation."""
    cfg = DatasetConfig(stride=8)
    ds = build_dataset(mocap_dir / "cmu" / "131_02.bvh", cfg, stats=None)
    return ds, ds.windows("all")


def test_registered_as_baselines_without_parameters():
    for name in BASELINES:
        assert MODEL_REGISTRY[name].kind == "baseline"
        model = build_model(name, {"feature_dim": 5})
        assert sum(p.numel() for p in model.parameters()) == 0


def test_predictions_on_a_hand_made_sequence():
    obs = torch.tensor([[[0.0], [1.0], [4.0]]])  # (1, 3, 1): velocities 1 then 3, mean 2
    zv = build_model("zero-velocity", {"feature_dim": 1}).sample(obs, num_samples=2, horizon=2)
    ls = build_model("last-step", {"feature_dim": 1}).sample(obs, num_samples=2, horizon=2)
    sm = build_model("sequence-motion", {"feature_dim": 1}).sample(obs, num_samples=2, horizon=2)
    assert zv.shape == (1, 2, 2, 1)
    np.testing.assert_allclose(zv[0, 0, :, 0], [4.0, 4.0])
    np.testing.assert_allclose(ls[0, 1, :, 0], [7.0, 10.0])
    np.testing.assert_allclose(sm[0, 0, :, 0], [6.0, 8.0])
    assert torch.equal(ls[0, 0], ls[0, 1])  # deterministic copies


def test_feature_space_extrapolation_is_exact_in_joint_space(walk_windows):
    """Extrapolating normalised features then decoding == extrapolating the world joints."""
    ds, w = walk_windows
    cfg = ds.config
    obs = torch.from_numpy(w.obs)
    world_obs = decode_samples(w.obs[:, None], config=cfg, stats=ds.stats, frame=w.frames)[:, 0]  # (N, To, 17, 3)
    steps = np.arange(1, cfg.future + 1)[None, :, None, None]
    expected = {
        "zero-velocity": np.repeat(world_obs[:, -1:], cfg.future, axis=1),
        "last-step": world_obs[:, -1:] + steps * (world_obs[:, -1:] - world_obs[:, -2:-1]),
        "sequence-motion": world_obs[:, -1:] + steps * (world_obs[:, -1:] - world_obs[:, :1]) / (cfg.observed - 1),
    }
    for name in BASELINES:
        bundle = baseline_bundle(name, cfg, stats=ds.stats)
        pred = bundle.model.sample(obs, num_samples=1, horizon=cfg.future).numpy()
        joints = decode_samples(pred, config=cfg, stats=ds.stats, frame=w.frames)[:, 0]  # (N, Tf, 17, 3)
        np.testing.assert_allclose(joints, expected[name], atol=2e-4, err_msg=name)


def test_zero_velocity_holds_the_last_observed_pose_of_a_real_clip(walk_windows):
    ds, w = walk_windows
    bundle = baseline_bundle("zero-velocity", ds.config, stats=ds.stats)
    pred = bundle.model.sample(torch.from_numpy(w.obs), num_samples=3, horizon=5).numpy()
    np.testing.assert_allclose(pred, np.broadcast_to(w.obs[:, None, -1:], pred.shape), atol=1e-6)


def test_loss_reports_mse_and_has_no_gradient(walk_windows):
    _, w = walk_windows
    model = build_model("last-step", {"feature_dim": w.features.shape[-1]})
    out = model.loss(torch.from_numpy(w.obs), torch.from_numpy(w.future), step=0)
    assert out.total.requires_grad is False and out.terms["mse"] > 0


def test_evaluation_scores_zero_velocity_by_hand(walk_windows):
    """evaluate_bundles on real windows == the metric computed directly from the raw windows."""
    from motion2video.evaluation import metrics as M
    from motion2video.data.windows import metric_vectors
    from motion2video.evaluation.forecasting import EvalProtocol, evaluate_bundles

    ds, w = walk_windows
    bundles = [baseline_bundle(n, ds.config, stats=ds.stats) for n in BASELINES]
    result = evaluate_bundles(bundles, w, protocol=EvalProtocol(samples=2))
    last = w.raw[:, ds.config.observed - 1, :48]  # root-relative pose of the last observed frame
    future = w.raw[:, ds.config.observed:, :48]
    by_hand = np.linalg.norm(future - last[:, None], axis=-1)  # (N, Tf)
    row = result.results["zero-velocity"]
    assert row["ade"] == pytest.approx(by_hand.mean(), rel=1e-5)
    assert row["fde"] == pytest.approx(by_hand[:, -1].mean(), rel=1e-5)
    assert row["apd"] == 0.0
    groups = M.multimodal_ground_truth(metric_vectors(w.raw[:, ds.config.observed - 1], ds.layout), threshold=0.5)
    assert result.protocol["mean_multimodal_futures"] == pytest.approx(np.mean([len(g) for g in groups]))
    assert list(result.results) == list(BASELINES)
