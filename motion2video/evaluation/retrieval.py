"""Retrieved futures: real motion of the training windows, as a reference point for forecasting and realism.

For every observed window, the K training windows whose last observed frames look most alike (motion matching)
lend their real futures, moved to start where the observed window ends. It has no parameters and no training;
it answers two questions about the evaluation rather than being a model to ship:

- how far the corpus's own motion, retrieved for the context, gets on the best-of-K protocol of ``evaluate``;
- what the two-sample realism test (:mod:`motion2video.evaluation.realism`) says about *real* motion that
  continues each window, captured from other people: the target a generator is held to is only meaningful if
  real motion meets it.

docs/results_transfer.md ("Realism") reports both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from motion2video.data.windows import NormStats


@dataclass(frozen=True)
class RetrievalConfig:
    """How windows are matched.

    Attributes:
        match_frames: the last observed frames compared (their root-relative joints and frame-to-frame steps).
        step_weight: weight of the steps against the positions (a step is about 1/25 of a pose's spread).
        separation: two retrieved windows of one clip start at least this many frames apart (else the K nearest
            are mostly one moment of one clip, shifted by a frame).
        decay_frames: the offset between the observed last frame and the retrieved one fades as exp(-t / decay),
            as :func:`motion2video.stages.sampling.continue_observed` fades the learned models' correction.
    """

    match_frames: int = 8
    step_weight: float = 5.0
    separation: int = 12
    decay_frames: float = 16.0


def match_descriptor(raw: np.ndarray, *, observed: int, config: RetrievalConfig) -> np.ndarray:
    """(N, L, 51) un-normalised body3d windows -> (N, D) descriptors of their last ``match_frames`` observed
    frames: the 16 root-relative joints (48 numbers per frame) and their steps times ``step_weight``."""
    last = np.asarray(raw, np.float64)[:, observed - config.match_frames:observed]  # (N, n, 51)
    joints = last[..., :48]
    steps = np.diff(last, axis=1)  # the root's step too: how fast the body travels
    return np.concatenate([joints.reshape(len(last), -1), config.step_weight * steps.reshape(len(last), -1)], axis=1)


class RetrievedFutures(nn.Module):
    """A sampler over a fixed database of real windows (normalised features in and out, as every model).

    Args:
        windows: (M, L, F) un-normalised body3d training windows (L = observed + future).
        clip_ids: (M,) an id per window's clip; starts: (M,) its first frame in the clip.
        observed: observed frames per window. stats: the normalisation of the features it is given.
    """

    is_baseline = True  # its futures are real motion: stages.sampling.sample_futures leaves them as they are

    def __init__(self, windows: np.ndarray, clip_ids: np.ndarray, starts: np.ndarray, *, observed: int,
                 stats: NormStats, config: RetrievalConfig = RetrievalConfig()) -> None:
        super().__init__()
        self.windows = np.asarray(windows, np.float64)
        self.clip_ids = np.asarray(clip_ids)
        self.starts = np.asarray(starts, np.int64)
        self.observed = observed
        self.stats = stats
        self.config = config
        self.keys = match_descriptor(self.windows, observed=observed, config=config)  # (M, D)
        self.key_norms = (self.keys ** 2).sum(axis=1)

    def nearest(self, query: np.ndarray, k: int) -> np.ndarray:
        """(k,) database rows nearest one (D,) descriptor, no two of one clip within ``separation`` frames."""
        d2 = self.key_norms - 2.0 * self.keys @ query
        chosen: list[int] = []
        apart = self.config.separation
        for j in np.argsort(d2):
            if any(self.clip_ids[j] == self.clip_ids[c] and abs(self.starts[j] - self.starts[c]) < apart for c in chosen):
                continue
            chosen.append(int(j))
            if len(chosen) == k:
                break
        return np.array(chosen, np.int64)

    @torch.no_grad()
    def sample(self, obs: torch.Tensor, *, num_samples: int, horizon: int,
               generator: torch.Generator | None = None) -> torch.Tensor:
        """obs (B, To, F) normalised -> (B, K, horizon, F) normalised: the K nearest windows' futures, each moved by
        the difference of the last observed frames (fading with ``decay_frames``; the root's x, y are both 0
        there). ``generator`` is unused: retrieval is deterministic."""
        if horizon > self.windows.shape[1] - self.observed:
            raise ValueError(f"the database's futures have {self.windows.shape[1] - self.observed} frames, "
                             f"not {horizon}")
        raw = self.stats.denormalize(obs.double().cpu().numpy())  # (B, To, F)
        queries = match_descriptor(raw, observed=raw.shape[1], config=self.config)
        fade = np.exp(-np.arange(1, horizon + 1) / self.config.decay_frames)[:, None]  # (horizon, 1)
        out = np.empty((len(raw), num_samples, horizon, raw.shape[2]))
        for b, query in enumerate(queries):
            rows = self.nearest(query, num_samples)
            rows = np.resize(rows, num_samples)  # a tiny database repeats its windows
            futures = self.windows[rows, self.observed:self.observed + horizon]  # (K, horizon, F)
            offset = raw[b, -1] - self.windows[rows, self.observed - 1]  # (K, F)
            out[b] = futures + fade[None] * offset[:, None]
        return torch.from_numpy(self.stats.normalize(out)).float()


def training_database(train, stats: NormStats, config: RetrievalConfig = RetrievalConfig()) -> RetrievedFutures:
    """The retrieval database of a split's training windows (a :class:`motion2video.data.dataset.WindowSet`), in the
    normalisation ``stats``; windows of one clip share an id, so that the K retrieved keep apart in it."""
    clips = {name: i for i, name in enumerate(sorted(set(train.clip_names)))}
    return RetrievedFutures(train.raw, np.array([clips[c] for c in train.clip_names]), train.starts,
                            observed=train.observed, stats=stats, config=config)


@torch.no_grad()
def posterior_means(model: nn.Module, windows: np.ndarray, *, observed: int, batch_size: int = 512) -> torch.Tensor:
    """(M, Z) the recognition model's mean latent of each (M, L, F) normalised window (its first ``observed``
    frames the past, the rest the future)."""
    model.eval()
    x = torch.from_numpy(np.ascontiguousarray(windows, np.float32))
    return torch.cat([model.encode(b[:, :observed], b[:, observed:]).mu for b in x.split(batch_size)])


@torch.no_grad()
def retrieved_latent_futures(model: nn.Module, database: RetrievedFutures, latents: torch.Tensor, obs: np.ndarray,
                             *, num_samples: int, horizon: int) -> np.ndarray:
    """A latent model's futures decoded from real latents: for each observed window, the recognition model's mean
    latents of the K database windows whose last observed frames are nearest (:meth:`RetrievedFutures.nearest`),
    decoded from the window's own observed frames.

    It asks whether a sampler could do better by drawing the latents that the training futures of similar moments
    have, instead of learning a map from noise (the decoder's ceiling).

    Args:
        model: a latent model with ``decode`` (its latents ``latents``, from :func:`posterior_means`).
        database: the training windows and their matching keys; latents: (M, Z), one per database window.
        obs: (N, To, F) normalised observed windows in the database's normalisation.
    Returns:
        (N, K, horizon, F) normalised futures (float32).
    """
    model.eval()
    raw = database.stats.denormalize(np.asarray(obs, np.float64))
    queries = match_descriptor(raw, observed=raw.shape[1], config=database.config)
    out = np.empty((len(obs), num_samples, horizon, obs.shape[2]), np.float32)
    for i, query in enumerate(queries):
        rows = np.resize(database.nearest(query, num_samples), num_samples)
        past = torch.from_numpy(np.ascontiguousarray(obs[i:i + 1], np.float32)).repeat(num_samples, 1, 1)
        out[i] = model.decode(past, latents[torch.from_numpy(rows)], horizon=horizon).numpy()
    return out
