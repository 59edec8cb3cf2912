"""The known-answer multimodal benchmark, its mode classifier and the coverage / precision scores."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.data.multimodal import (
    UNKNOWN,
    BenchmarkBatch,
    ClassifierConfig,
    ModeClassifier,
    MultimodalBenchmark,
    coverage_from_labels,
    distribution_tv_from_labels,
    fit_default_classifier,
    mode_coverage,
    mode_features,
    mode_precision,
    precision_from_labels,
    score_futures,
)
from motion2video.data.procedural import MODES
from motion2video.core.errors import InputError


@pytest.fixture(scope="module")
def bench() -> MultimodalBenchmark:
    return MultimodalBenchmark()


@pytest.fixture(scope="module")
def classifier(bench) -> ModeClassifier:
    return fit_default_classifier(bench, per_mode=10, seed=100)


def test_valid_modes_and_config_checks(bench):
    assert bench.valid_modes("walk") == {"walk": 0.4, "run": 0.3, "turn": 0.3}
    for context in bench.contexts:
        assert sum(bench.valid_modes(context).values()) == pytest.approx(1.0)
    assert set(bench.valid_modes("stand")) == {"jump", "squat", "wave", "punch"}
    with pytest.raises(InputError, match="unknown benchmark context"):
        bench.valid_modes("swim")
    with pytest.raises(InputError, match="sum to 1"):
        MultimodalBenchmark(futures=(("walk", (("walk", 0.5), ("run", 0.3))),))
    with pytest.raises(InputError, match="not a procedural mode"):
        MultimodalBenchmark(futures=(("walk", (("fly", 1.0),)),))


def test_sample_shapes_determinism_and_continuity(bench):
    batch = bench.sample(24, seed=3)
    assert isinstance(batch, BenchmarkBatch)
    observed, future, context, future_mode = batch  # unpacks as a 4-tuple
    assert observed.shape == (24, 16, 17, 3) and future.shape == (24, 48, 17, 3)
    assert observed.dtype == np.float32 and np.all(np.isfinite(future))
    assert len(context) == len(future_mode) == 24
    for c, m in zip(context, future_mode):
        assert m in bench.valid_modes(c)
    again = bench.sample(24, seed=3)
    np.testing.assert_array_equal(again.future, future)
    assert again.future_mode == future_mode
    assert np.abs(bench.sample(24, seed=4).observed - observed).max() > 1e-3
    # The future continues the observed motion: no bigger step at the seam than within the observed part.
    seam = np.linalg.norm(future[:, 0] - observed[:, -1], axis=-1).max(axis=1)  # (n,)
    inner = np.linalg.norm(np.diff(observed, axis=1), axis=-1).max(axis=(1, 2))  # (n,)
    assert np.all(seam <= 1.1 * inner + 0.01)
    # Body sizes differ between samples.
    heights = observed[:, 0, 10, 2]
    assert heights.max() - heights.min() > 0.1


def test_future_modes_follow_the_known_probabilities(bench):
    batch = bench.sample(400, seed=0)
    context, future = np.array(batch.context), np.array(batch.future_mode)
    for c in bench.contexts:
        rows = future[context == c]
        assert len(rows) > 80
        for mode, p in bench.valid_modes(c).items():
            assert abs(np.mean(rows == mode) - p) < 0.1


def test_observed_part_does_not_reveal_the_future(bench):
    truth = bench.sample(12, seed=9)
    oracle = bench.oracle_futures(12, seed=9, k=6, future_seed=1)  # same observed, other futures
    assert oracle.shape == (12, 6, 48, 17, 3)
    # Every oracle future starts where the observed part ends, whatever its mode.
    seam = np.linalg.norm(oracle[:, :, 0] - truth.observed[:, None, -1], axis=-1).max(axis=(1, 2))  # (n,)
    inner = np.linalg.norm(np.diff(truth.observed, axis=1), axis=-1).max(axis=(1, 2))
    assert np.all(seam <= 1.1 * inner + 0.01)


def test_classifier_labels_held_out_clean_instances(bench, classifier):
    held_out = bench.templates(MODES, per_mode=12, seed=2024)  # different bodies, speeds, phases
    correct = total = 0
    for mode, clips in held_out.items():
        labels = classifier.predict(clips)
        correct += int(np.sum(labels == mode))
        total += len(labels)
    assert correct / total >= 0.95


def test_classifier_labels_benchmark_futures_despite_the_cross_fade_and_jitter(bench, classifier):
    batch = bench.sample(60, seed=21)
    truth = np.array(batch.future_mode)
    assert np.mean(classifier.predict(batch.future) == truth) >= 0.95
    noisy = batch.future + np.random.default_rng(0).normal(scale=0.01, size=batch.future.shape)
    assert np.mean(classifier.predict(noisy) == truth) >= 0.9  # 1 cm of per-frame jitter


def test_classifier_rejects_what_is_no_mode(bench, classifier):
    rng = np.random.default_rng(1)
    batch = bench.sample(20, seed=2)
    noise = batch.future[:, :1] + rng.normal(scale=0.1, size=batch.future.shape)  # jittering blob
    assert np.mean(classifier.predict(noise) == UNKNOWN) > 0.9
    scrambled = batch.future[:, rng.permutation(48)]  # right poses, nonsense time order
    assert np.mean(classifier.predict(scrambled) == UNKNOWN) > 0.6
    with pytest.raises(InputError, match="expects"):
        classifier.predict(batch.future[:, :40])


def test_ground_truth_futures_score_high_and_frozen_futures_low(bench, classifier):
    n = 30
    contexts = bench.sample(n, seed=5).context
    oracle = bench.oracle_futures(n, seed=5, k=10)
    scores = score_futures(oracle, contexts, classifier=classifier, benchmark=bench)
    assert scores.labels.shape == (n, 10)
    assert scores.coverage > 0.9 and scores.precision > 0.95 and scores.distribution_tv < 0.2
    assert mode_coverage(oracle, contexts, classifier=classifier, benchmark=bench) == scores.coverage
    assert mode_precision(oracle, contexts, classifier=classifier, benchmark=bench) == scores.precision
    assert mode_coverage(oracle, contexts) > 0.9  # the default classifier, built once
    # Zero-velocity futures: the last observed pose held for the whole future.
    batch = bench.sample(n, seed=5)
    frozen = np.repeat(batch.observed[:, None, -1:], 48, axis=2)  # (n, 1, 48, 17, 3)
    frozen_scores = score_futures(frozen, contexts, classifier=classifier, benchmark=bench)
    assert frozen_scores.coverage < 0.1 and frozen_scores.precision < 0.1
    # A single true future per sequence is precise but covers at most one of its 2-4 modes.
    single = score_futures(batch.future[:, None], contexts, classifier=classifier, benchmark=bench)
    assert single.precision > 0.95 and single.coverage <= 0.5


def test_scores_from_labels_have_known_answers(bench):
    contexts = ["walk", "stand"]
    labels = np.array([["walk", "run", "turn", "walk"], ["jump", "jump", "stand", UNKNOWN]])
    assert coverage_from_labels(labels, contexts, bench) == pytest.approx((1.0 + 0.25) / 2)
    assert precision_from_labels(labels, contexts, bench) == pytest.approx(6 / 8)
    # walk: freq walk .5 run .25 turn .25 vs .4 .3 .3 -> TV .1; stand: jump .5, invalid .5 -> TV .7
    assert distribution_tv_from_labels(labels, contexts, bench) == pytest.approx((0.1 + 0.7) / 2)


def test_features_ignore_position_heading_and_size(bench):
    clips = bench.templates(["walk"], per_mode=2, seed=0)["walk"].astype(np.float64)  # (2, 48, 17, 3)
    pose, vel = mode_features(clips, skip=10, fps=25.0)
    assert pose.shape == (2, 38, 51) and vel.shape == (2, 34, 3)
    angle = 1.1
    rot = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0.0, 0.0, 1.0]])
    moved = 1.3 * clips @ rot.T + np.array([4.0, -2.0, 0.0])
    pose2, vel2 = mode_features(moved, skip=10, fps=25.0)
    np.testing.assert_allclose(pose2, pose, atol=1e-9)
    np.testing.assert_allclose(vel2, vel, atol=1e-9)


def test_fit_checks_its_templates(bench):
    with pytest.raises(InputError, match="no templates"):
        ModeClassifier.fit({}, window=48, fps=25.0)
    short = bench.templates(["walk"], per_mode=2, seed=0)["walk"][:, :30]
    with pytest.raises(InputError, match="must be"):
        ModeClassifier.fit({"walk": short}, window=48, fps=25.0)
    one = bench.templates(["walk", "run"], per_mode=1, seed=0)
    with pytest.raises(InputError, match="at least 2 instances"):
        ModeClassifier.fit(one, window=48, fps=25.0)
    clf = ModeClassifier.fit(one, window=48, fps=25.0, config=ClassifierConfig(reject_factor=None))
    assert np.all(np.isinf(clf.thresholds))
