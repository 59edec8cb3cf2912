"""Retrieved futures (motion matching over real windows), the reference point of the forecasting and realism
evaluations: on real CMU walks, a window in the database finds itself, and the futures start where the query ends."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.evaluation.retrieval import (RetrievalConfig, RetrievedFutures, match_descriptor, posterior_means,
                                               retrieved_latent_futures)
from motion2video.models.base import build_model
from motion2video.stages.sampling import sample_futures


@pytest.fixture(scope="module")
def walks(mocap_dir):
    """Every window (stride 1) of CMU 131_02 as the database, and the windows of 131_03 (the same subject, another
    walk) as queries, in one normalisation."""
    cfg = DatasetConfig(stride=1)
    db = build_dataset(mocap_dir / "cmu" / "131_02.bvh", cfg, stats=None)
    other = build_dataset(mocap_dir / "cmu" / "131_03.bvh", cfg, stats=db.stats)
    return db.windows("all"), other.windows("all", stride=16), db.stats


def make(db, stats, **config) -> RetrievedFutures:
    return RetrievedFutures(db.raw, np.zeros(len(db), np.int64), db.starts, observed=db.observed, stats=stats,
                            config=RetrievalConfig(**config))


def test_a_window_of_the_database_retrieves_its_own_future(walks):
    db, _, stats = walks
    net = make(db, stats)
    i = len(db) // 2
    out = net.sample(torch.from_numpy(db.obs[i:i + 1]), num_samples=3, horizon=db.future.shape[1])
    assert out.shape == (1, 3, db.future.shape[1], db.raw.shape[2])
    first = stats.denormalize(out[0, 0].double().numpy())
    np.testing.assert_allclose(first, db.raw[i, db.observed:], atol=1e-4)  # itself, with no offset to fade
    rows = net.nearest(match_descriptor(db.raw[i:i + 1], observed=db.observed, config=net.config)[0], 3)
    assert rows[0] == i and np.all(np.abs(np.diff(np.sort(db.starts[rows]))) >= net.config.separation)


def test_retrieved_futures_continue_the_query_and_are_real_motion(walks):
    db, queries, stats = walks
    net = make(db, stats, decay_frames=8.0)
    horizon = 24
    out = sample_futures(net, queries.obs, num_samples=5, horizon=horizon, seed=0)  # left as they are (is_baseline)
    raw = stats.denormalize(out.astype(np.float64))  # (N, 5, 24, 51)
    last = queries.raw[:, queries.observed - 1]  # (N, 51)
    step = np.linalg.norm(raw[:, :, 0, :48] - last[:, None, :48], axis=-1)  # the first future frame's pose change
    observed_step = np.linalg.norm(last[:, :48] - queries.raw[:, queries.observed - 2, :48], axis=-1)
    assert np.median(step) < np.median(observed_step)  # no jump where the future starts (0.09 against 0.13 m)
    # far from the join the futures are a database window's own frames: the offset has faded (0.03 m from the
    # nearest database frame; kept whole, the offset leaves them 0.46 m away)
    late = raw[:, :, -1]
    ends = db.raw[:, db.observed + horizon - 1]
    nearest_gap = np.min(np.linalg.norm(late[:, :, None, :48] - ends[None, None, :, :48], axis=-1), axis=2)
    assert np.median(nearest_gap) < 0.1
    with pytest.raises(ValueError, match="frames"):
        net.sample(torch.from_numpy(queries.obs[:1]), num_samples=1, horizon=db.future.shape[1] + 1)


def test_retrieved_latents_decode_the_nearest_windows_latents(walks):
    """A latent model's futures from retrieved latents (the decoder's ceiling): a database window asks
    for K futures and the first is its own future as the decoder draws it from its own posterior mean; the others
    are the decoder's futures of the same past under the other retrieved windows' latents (an untrained model: its
    zero-initialised head draws the same future for every latent, so the latents are compared, not the futures)."""
    db, queries, stats = walks
    horizon = db.future.shape[1]
    torch.manual_seed(0)
    model = build_model("mixer-cvae", {"feature_dim": db.raw.shape[2], "observed": db.observed, "future": horizon,
                                       "num_coeffs": 8, "hidden_dim": 16, "context_blocks": 1, "encoder_blocks": 1,
                                       "decoder_blocks": 1, "latent_dim": 4}).eval()
    net = make(db, stats)
    latents = posterior_means(model, db.features, observed=db.observed, batch_size=64)
    assert latents.shape == (len(db), 4)
    i = len(db) // 2
    out = retrieved_latent_futures(model, net, latents, db.obs[i:i + 2], num_samples=3, horizon=horizon)
    assert out.shape == (2, 3, horizon, db.raw.shape[2]) and out.dtype == np.float32
    rows = net.nearest(match_descriptor(db.raw[i:i + 1], observed=db.observed, config=net.config)[0], 3)
    past = torch.from_numpy(db.obs[i:i + 1]).repeat(3, 1, 1)
    with torch.no_grad():
        expected = model.decode(past, latents[torch.from_numpy(rows)], horizon=horizon).numpy()
    assert rows[0] == i
    np.testing.assert_allclose(out[0], expected, atol=1e-5)
    assert not torch.allclose(latents[rows[0]], latents[rows[1]])  # each retrieved window lends its own latent
    short = retrieved_latent_futures(model, net, latents, queries.obs[:1], num_samples=2, horizon=10)
    assert short.shape == (1, 2, 10, db.raw.shape[2])
