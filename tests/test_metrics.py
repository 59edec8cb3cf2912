"""Every metric against values computed by hand on tiny inputs."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.evaluation import metrics as M


def _pred_gt():
    """N=1 window, K=2 samples, T=2 frames, D=2. gt is all zeros.

    sample 0: frames (3, 4), (0, 0)  -> distances 5, 0 -> ADE 2.5, FDE 0
    sample 1: frames (1, 0), (0, 2)  -> distances 1, 2 -> ADE 1.5, FDE 2
    """
    pred = np.array([[[[3.0, 4.0], [0.0, 0.0]], [[1.0, 0.0], [0.0, 2.0]]]])
    gt = np.zeros((1, 2, 2))
    return pred, gt


def test_ade_fde_are_best_of_k():
    pred, gt = _pred_gt()
    assert M.ade(pred, gt) == pytest.approx(1.5)
    assert M.fde(pred, gt) == pytest.approx(0.0)  # best final frame may come from another sample
    np.testing.assert_allclose(M.displacement(pred, gt), [[[5.0, 0.0], [1.0, 2.0]]])


def test_best_of_k_scores_from_one_displacement_match_the_single_metrics():
    """ADE, FDE and ADE per frame computed once from the displacements equal the functions that compute each."""
    rng = np.random.default_rng(3)
    pred, gt = rng.normal(size=(7, 5, 9, 6)), rng.normal(size=(7, 9, 6))
    best = M.best_of_k_displacements(M.displacement(pred, gt))
    np.testing.assert_array_equal(best["ade"], M.ade_per_window(pred, gt))
    np.testing.assert_allclose(best["fde"], np.linalg.norm(pred[:, :, -1] - gt[:, None, -1], axis=-1).min(axis=1))
    np.testing.assert_array_equal(best["fde"], M.fde_per_window(pred, gt))
    np.testing.assert_array_equal(best["ade_per_frame"], M.ade_per_frame(pred, gt))


def test_liveliness_of_windows_averages_to_the_liveliness_of_any_set_of_them():
    rng = np.random.default_rng(4)
    seq = rng.normal(size=(6, 3, 10, 4)).cumsum(axis=2)
    vel, acc = M.liveliness_per_window(seq)
    for idx in (np.arange(6), np.array([1, 4]), np.array([5])):
        np.testing.assert_allclose((vel[idx].mean(), acc[idx].mean()), M.liveliness(seq[idx]), rtol=1e-12)


def test_framewise_oracle_takes_the_closest_sample_at_each_frame():
    pred, gt = _pred_gt()  # frame 0: min(5, 1) = 1; frame 1: min(0, 2) = 0
    np.testing.assert_allclose(M.framewise_oracle_ade_per_window(pred, gt), [0.5])
    assert M.framewise_oracle_ade_per_window(pred, gt)[0] < M.ade_per_window(pred, gt)[0]  # 0.5 < 1.5


def test_ade_averages_windows():
    pred, gt = _pred_gt()
    pred2 = np.concatenate([pred, pred + 1.0])  # second window: gt one unit away in each coordinate
    gt2 = np.concatenate([gt, gt + 1.0])
    assert M.ade(pred2, gt2) == pytest.approx(1.5)


def test_apd_is_the_mean_pairwise_distance_of_whole_sequences():
    pred, _ = _pred_gt()
    # flattened samples (3,4,0,0) and (1,0,0,2): difference (2,4,0,-2) -> sqrt(24)
    assert M.apd(pred) == pytest.approx(np.sqrt(24.0))
    three = np.zeros((1, 3, 1, 1))
    three[0, :, 0, 0] = [0.0, 1.0, 3.0]  # pairs 1, 3, 2 -> mean 2
    assert M.apd(three) == pytest.approx(2.0)
    assert M.apd(pred[:, :1]) == 0.0


def test_multimodal_ground_truth_and_mmade():
    last = np.array([[0.0], [0.3], [2.0]])
    groups = M.multimodal_ground_truth(last, threshold=0.5)
    assert [g.tolist() for g in groups] == [[0, 1], [0, 1], [2]]
    # One sample per window, T=1, D=1.
    futures = np.array([[[0.0]], [[1.0]], [[5.0]]])
    pred = np.array([[[[0.0]]], [[[0.5]]], [[[5.0]]]])
    # window 0: |0-0|, |0-1| -> mean 0.5; window 1: |0.5-0|, |0.5-1| -> 0.5; window 2: 0
    assert M.mmade(pred, futures, groups) == pytest.approx((0.5 + 0.5 + 0.0) / 3)
    assert M.mmfde(pred, futures, groups) == pytest.approx((0.5 + 0.5 + 0.0) / 3)


def test_mmade_takes_the_best_sample_per_ground_truth():
    futures = np.array([[[0.0]], [[1.0]]])
    groups = [np.array([0, 1]), np.array([1])]
    pred = np.array([[[[0.0]], [[1.0]]], [[[0.0]], [[3.0]]]])  # window 0 covers both futures exactly
    assert M.mmade(pred, futures, groups) == pytest.approx((0.0 + 1.0) / 2)


def test_best_of_k_mse():
    pred, gt = _pred_gt()
    # sample 0: (9+16+0+0)/4 = 6.25; sample 1: (1+0+0+4)/4 = 1.25
    assert M.best_of_k_mse(pred, gt) == pytest.approx(1.25)


def test_parzen_log_likelihood_matches_a_gaussian_mixture():
    samples = np.array([[[0.0, 0.0], [2.0, 0.0]]])  # K=2, M=2
    gt = np.array([[1.0, 0.0]])
    h = 0.5
    # each kernel: N(gt; s, h^2 I) = exp(-1 / (2 h^2)) / (2 pi h^2); mixture = same value
    expected = -1.0 / (2 * h * h) - np.log(2 * np.pi * h * h)
    assert M.parzen_log_likelihood(samples, gt, bandwidth=h)[0] == pytest.approx(expected)
    with pytest.raises(ValueError):
        M.parzen_log_likelihood(samples, gt, bandwidth=0.0)


def test_parzen_bandwidth_selection_prefers_the_right_spread():
    rng = np.random.default_rng(0)
    samples = rng.normal(scale=0.3, size=(200, 100, 1))
    gt = rng.normal(scale=0.3, size=(200, 1))
    h = M.select_parzen_bandwidth(samples, gt, candidates=np.array([0.01, 0.1, 0.3, 3.0]))
    assert h in (0.1, 0.3)  # a kernel width near the data's scale, not the extremes


def test_transfer_displacement_error():
    source = np.zeros((2, 3, 1))
    reenacted = np.array([[[1.0], [2.0], [3.0]], [[1.0], [0.0], [1.0]]])
    np.testing.assert_allclose(M.transfer_displacement_error(reenacted, source, timesteps=[0, 2]),
                               [(1 + 1) / 2, (9 + 1) / 2])


def test_latent_distance():
    d = M.latent_distance(np.array([[0.0, 0.0], [0.0, 0.0]]), np.array([[3.0, 4.0], [1.0, 0.0]]))
    assert d.mean == pytest.approx(3.0) and d.std == pytest.approx(2.0)


def test_asd_and_fsd():
    pred = np.zeros((1, 3, 2, 1))
    pred[0, :, :, 0] = [[0.0, 0.0], [1.0, 0.0], [4.0, 4.0]]
    # whole sequences: d01 = 1, d02 = sqrt(32), d12 = sqrt(9+16) = 5 -> nearest: 1, 1, 5
    assert M.asd(pred) == pytest.approx((1 + 1 + 5) / 3)
    # last frames 0, 0, 4: nearest 0, 0, 4
    assert M.fsd(pred) == pytest.approx(4 / 3)
    with pytest.raises(ValueError):
        M.asd(pred[:, :1])


def test_diversity_averages_per_frame_distances():
    pred = np.zeros((1, 2, 2, 2))
    pred[0, 1] = [[3.0, 4.0], [0.0, 1.0]]  # per-frame distances 5 and 1
    assert M.diversity(pred) == pytest.approx(3.0)
    assert M.diversity(pred[:, :1]) == 0.0


def test_ridge_classifier_separates_two_clusters():
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(-2, 0.5, (50, 3)), rng.normal(2, 0.5, (50, 3))])
    y = np.array(["a"] * 50 + ["b"] * 50)
    clf = M.fit_ridge_classifier(x, y)
    assert np.mean(clf.predict(x) == y) == 1.0
    assert M.mean_class_accuracy(np.array(["a", "a", "b"]), np.array(["a", "b", "b"])) == pytest.approx(0.75)


def test_quality_is_chance_for_real_against_real_and_high_for_frozen_fakes():
    rng = np.random.default_rng(1)
    t = np.arange(12)[None, :, None] / 12.0
    real = np.sin(2 * np.pi * (t + rng.uniform(size=(80, 1, 1)))) * rng.uniform(0.5, 1.5, (80, 1, 2))
    frozen = np.repeat(real[:, :1], 12, axis=1)  # a motionless "generator"
    assert M.quality(real, frozen) > 0.9
    other = np.sin(2 * np.pi * (t + rng.uniform(size=(80, 1, 1)))) * rng.uniform(0.5, 1.5, (80, 1, 2))
    assert 0.3 < M.quality(real, other) < 0.7


def test_context_accuracy_of_a_ground_truth_classifier():
    rng = np.random.default_rng(2)
    t = np.arange(12)[None, :, None] / 12.0
    slow = np.sin(2 * np.pi * (t + rng.uniform(size=(40, 1, 1))))
    fast = np.sin(6 * np.pi * (t + rng.uniform(size=(40, 1, 1))))
    train = np.concatenate([slow, fast])
    labels = np.array(["slow"] * 40 + ["fast"] * 40)
    pred = np.stack([fast[:10], slow[:10]], axis=1)  # (10, K=2, 12, 1): one right, one wrong per window
    assert M.context(train, labels, pred, np.array(["fast"] * 10)) == pytest.approx(0.5)
    assert M.context(train, labels, pred[:, :1], np.array(["fast"] * 10)) == pytest.approx(1.0)


def test_nearest_template_coverage_and_precision():
    templates = np.array([[[0.0]], [[1.0]], [[2.0]]])  # M=3 modes, T=1, D=1
    futures = np.array([[[[0.1]], [[0.9]], [[9.0]]], [[[2.1]], [[2.0]], [[1.9]]]])  # (N=2, K=3, 1, 1)
    modes = M.nearest_template(futures, templates, max_distance=0.5)
    np.testing.assert_array_equal(modes, [[0, 1, -1], [2, 2, 2]])
    valid = np.array([[True, True, True], [False, True, True]])
    assert M.mode_coverage(modes, valid) == pytest.approx((2 / 3 + 1 / 2) / 2)
    assert M.mode_precision(modes, valid) == pytest.approx(5 / 6)


def test_metrics_reject_bad_shapes():
    with pytest.raises(ValueError):
        M.ade(np.zeros((2, 3, 4)), np.zeros((2, 4)))
