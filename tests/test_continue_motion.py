"""Sampled futures continue the observed motion: a future's first frame is the last observed frame plus
the last observed step, for every learned model, and a baseline keeps its own rule.

Real parts: the shipped mtvae-add and the demo's real CMU walk.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2video.stages.sampling import CONTINUE_FRAMES, continue_observed, forecast, sample_futures

ROOT = Path(__file__).resolve().parents[1]


def test_continue_observed_starts_at_the_extrapolated_frame_and_fades():
    rng = np.random.default_rng(0)
    obs = np.cumsum(rng.normal(size=(3, 5, 4)), axis=1).astype(np.float32)  # (N, To, F)
    samples = rng.normal(size=(3, 2, 30, 4)).astype(np.float32)  # (N, K, T, F)
    out = continue_observed(samples, obs)
    step = obs[:, -1] - obs[:, -2]
    for k in range(2):
        np.testing.assert_allclose(out[:, k, 0], obs[:, -1] + step, atol=1e-5)
    shift0 = out[:, :, 0] - samples[:, :, 0]
    for t in (1, 10, 29):
        np.testing.assert_allclose(out[:, :, t] - samples[:, :, t], shift0 * np.exp(-t / CONTINUE_FRAMES), atol=1e-5)
    # The motion of each sample is its own after the shift has faded.
    assert np.abs(out[:, :, -1] - samples[:, :, -1]).max() < 0.2 * np.abs(shift0).max()
    assert continue_observed(samples, obs[:, :1]) is samples  # one observed frame: no step to continue


def test_a_shipped_model_continues_a_real_walk_and_a_baseline_keeps_its_rule():
    from motion2video.models.checkpoint import baseline_bundle, load_model

    bundle = load_model("mtvae-add")
    clip = np.asarray(np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"], np.float64)
    out = forecast(bundle, clip, num_samples=4, seed=0)
    observed = out.observed  # (16, 17, 3) world metres
    step = observed[-1] - observed[-2]
    assert np.linalg.norm(step, axis=-1).mean() > 0.005  # the walker moves
    first = out.futures[:, 0]  # (K, 17, 3)
    np.testing.assert_allclose(first, np.broadcast_to(observed[-1] + step, first.shape), atol=2e-4)
    # A zero-velocity baseline through the same call still stands still.
    zero = baseline_bundle("zero-velocity", bundle.data_config, stats=bundle.stats)
    features = bundle.layout.num_features
    ramp = np.broadcast_to(np.linspace(0.0, 1.0, 16, dtype=np.float32)[None, :, None], (2, 16, features))
    futures = sample_futures(zero.model, np.ascontiguousarray(ramp), num_samples=2, horizon=5, seed=0)
    np.testing.assert_allclose(futures, 1.0, atol=1e-6)
