"""The two-sample realism test: features by hand, the classifier, and its behaviour on real
mocap windows (real vs real about 0.5, real vs frozen or slowed futures of the same windows about 1.0)."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.evaluation import realism as R


def test_motion_features_by_hand():
    t = np.arange(5, dtype=np.float64)
    seq = np.zeros((1, 5, 6))
    seq[0, :, 0] = 2.0 * t  # point 0 moves along x at 2 units per frame
    seq[0, :, 4] = t ** 2  # point 1 accelerates along y: velocity 1, 3, 5, 7; acceleration 2
    f = R.motion_features(seq, dim=3)  # (1, 3 * 2): speeds, accelerations, spreads
    assert f.shape == (1, 6)
    np.testing.assert_allclose(f[0, :2], [2.0, 4.0])  # mean speeds
    np.testing.assert_allclose(f[0, 2:4], [0.0, 2.0])  # mean acceleration magnitudes
    np.testing.assert_allclose(f[0, 4:], [np.std(2.0 * t), np.std(t ** 2)])  # positional spreads
    with pytest.raises(ValueError):
        R.motion_features(seq, dim=4)


def test_logistic_regression_separates_and_cross_validation_keeps_groups_apart():
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(-2, 1, (100, 3)), rng.normal(2, 1, (100, 3))])
    y = np.repeat([0, 1], 100)
    model = R.fit_logistic(x, y)
    assert np.mean(model.predict(x) == y) > 0.97
    assert R.cross_validated_accuracy(x, y, np.arange(200)) > 0.95
    noise = rng.normal(size=(200, 3))
    assert 0.35 < R.cross_validated_accuracy(noise, y, np.arange(200)) < 0.65
    with pytest.raises(ValueError):
        R.cross_validated_accuracy(x, y, np.zeros(200), folds=5)  # one group cannot make 5 folds


@pytest.fixture(scope="module")
def real_futures(mocap_dir):
    """Real 48-frame futures (un-normalised body3d features) of three walking / hopping CMU clips."""
    cfg = DatasetConfig(stride=4)
    futures = []
    for rel in ("cmu/131_01.bvh", "cmu/131_02.bvh", "cmu/131_03.bvh", "cmu/02_01.bvh"):
        ds = build_dataset(mocap_dir / rel, cfg)
        futures.append(ds.windows("all").raw[:, cfg.observed:])
    return np.concatenate(futures)


def test_two_sample_test_on_real_windows(real_futures):
    real = real_futures
    assert len(real) >= 60
    # the control: real against real of the same windows, split in two halves
    same = R.two_sample_realism(real, real, dim=3)
    assert abs(same.control - 0.5) < 0.15
    assert same.accuracy == pytest.approx(0.5, abs=0.05)  # identical futures cannot be told apart
    # frozen futures (the first future frame held) are told apart from the real ones of the same windows
    frozen = np.repeat(real[:, :1], real.shape[1], axis=1)
    assert R.two_sample_realism(real, frozen, dim=3).accuracy > 0.95
    # the same futures played at half speed (the first half of each, stretched) are told apart too
    half = np.linspace(0, real.shape[1] / 2, real.shape[1])
    lo = np.floor(half).astype(int)
    w = (half - lo)[None, :, None]
    slow = (1 - w) * real[:, lo] + w * real[:, np.minimum(lo + 1, real.shape[1] - 1)]
    assert R.two_sample_realism(real, slow, dim=3).accuracy > 0.8
    with pytest.raises(ValueError):
        R.two_sample_realism(real, real[:-1], dim=3)


def test_feature_families_say_what_gives_fakes_away(real_futures):
    """Futures whose points jitter (same mean path, frame-to-frame noise) differ in acceleration far more than
    in positional spread."""
    rng = np.random.default_rng(0)
    jitter = real_futures + rng.normal(0.0, 0.01, real_futures.shape)
    test = R.two_sample_realism(real_futures, jitter, dim=3)
    assert set(test.by_family) == set(R.FAMILIES)
    assert test.by_family["acceleration"] > 0.95 and test.accuracy > 0.95
    assert test.by_family["spread"] < test.by_family["acceleration"]
