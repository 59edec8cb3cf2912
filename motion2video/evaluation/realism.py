"""Realism as a two-sample test on the same observed windows.

The retired realism classifier (``metrics.quality`` on the full sequence descriptor) told real motion of the
held-out subjects from the validation subjects' real motion with accuracy 0.99: it measured who moves and what
they do, not whether motion is real. Here both classes come from the SAME windows, so who moves and what they do
are the same on both sides:

- test: for every window, its real future (class 1) and a generated future of the same observed frames
  (class 0); a small logistic regression on simple per-window motion features (:func:`motion_features`),
  cross-validated with the windows split into folds (both futures of a window in the same fold), reports its
  held-out accuracy: 0.5 = the generated futures move like the real ones, 1.0 = always told apart;
- control: the real futures of one half of the windows against the real futures of the other half (a random
  split), the same classifier and folds: about 0.5 by construction, so it shows how far from 0.5 the test
  strays by chance with this many windows.

Pure numpy, deterministic for a seed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


FAMILIES = ("speed", "acceleration", "spread")  # the blocks of motion_features, in order


def motion_features(seq: np.ndarray, *, dim: int) -> np.ndarray:
    """Simple per-window motion features of un-normalised feature sequences.

    The F numbers of a frame are read as G = F / dim points of ``dim`` coordinates (body3d: 17 points of 3, the
    16 root-relative joints and the root; body2d: 17 of 2; faces: dim = 1, each parameter its own point). Per
    point: the mean speed, the mean acceleration magnitude and the spread of its position over the window
    (the norm of the per-coordinate standard deviations).

    Args:
        seq: (N, T, F) sequences, T >= 3.
        dim: coordinates per point; must divide F.
    Returns:
        (N, 3 * G) float64: all points' speeds, then accelerations, then spreads.
    """
    s = np.asarray(seq, np.float64)
    n, t, f = s.shape
    if t < 3 or f % dim:
        raise ValueError(f"need (N, T >= 3, F) with F a multiple of {dim}, got {s.shape}")
    p = s.reshape(n, t, f // dim, dim)  # (N, T, G, dim)
    vel = np.linalg.norm(np.diff(p, axis=1), axis=-1)  # (N, T-1, G)
    acc = np.linalg.norm(np.diff(p, 2, axis=1), axis=-1)  # (N, T-2, G)
    spread = np.linalg.norm(p.std(axis=1), axis=-1)  # (N, G)
    return np.concatenate([vel.mean(axis=1), acc.mean(axis=1), spread], axis=1)


@dataclass(frozen=True)
class LogisticModel:
    """A binary logistic regression on standardised inputs: p(y = 1 | x) = sigmoid(z(x) . w + b)."""

    mean: np.ndarray  # (P,)
    scale: np.ndarray  # (P,)
    weights: np.ndarray  # (P + 1,), the bias last

    def probability(self, x: np.ndarray) -> np.ndarray:
        """(M,) p(y = 1) for inputs x (M, P)."""
        z = (np.asarray(x, np.float64) - self.mean) / self.scale
        logits = np.concatenate([z, np.ones((len(z), 1))], axis=1) @ self.weights
        return 1.0 / (1.0 + np.exp(-np.clip(logits, -40.0, 40.0)))

    def predict(self, x: np.ndarray) -> np.ndarray:
        """(M,) int labels 0 / 1."""
        return (self.probability(x) > 0.5).astype(np.int64)


def fit_logistic(x: np.ndarray, y: np.ndarray, *, l2: float = 1.0, iterations: int = 25) -> LogisticModel:
    """L2-regularised logistic regression (bias not penalised) by Newton's method on standardised inputs.

    Args:
        x: (N, P) inputs; y: (N,) labels 0 / 1.
        l2: penalty on the squared weights (in units of the summed log-loss).
    """
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    mean, scale = x.mean(axis=0), x.std(axis=0) + 1e-8
    a = np.concatenate([(x - mean) / scale, np.ones((len(x), 1))], axis=1)  # (N, P + 1)
    reg = l2 * np.eye(a.shape[1])
    reg[-1, -1] = 0.0
    w = np.zeros(a.shape[1])
    for _ in range(iterations):
        p = 1.0 / (1.0 + np.exp(-np.clip(a @ w, -40.0, 40.0)))
        grad = a.T @ (p - y) + reg @ w
        hess = (a * (p * (1.0 - p))[:, None]).T @ a + reg + 1e-9 * np.eye(a.shape[1])
        step = np.linalg.solve(hess, grad)
        w -= step
        if np.abs(step).max() < 1e-8:
            break
    return LogisticModel(mean, scale, w)


def cross_validated_accuracy(x: np.ndarray, y: np.ndarray, groups: np.ndarray, *, folds: int = 5, seed: int = 0,
                             l2: float = 1.0) -> float:
    """Held-out accuracy of :func:`fit_logistic`, ``folds``-fold cross-validated over ``groups`` (items of one
    group, the two futures of one window, are always in the same fold); the share of all items predicted right.

    Args:
        x: (N, P) inputs; y: (N,) labels 0 / 1; groups: (N,) int group of each item.
    """
    groups = np.asarray(groups)
    ids = np.unique(groups)
    if len(ids) < folds:
        raise ValueError(f"{len(ids)} groups are too few for {folds} folds")
    fold_of = dict(zip(np.random.default_rng(seed).permutation(ids).tolist(), np.arange(len(ids)) % folds))
    fold = np.array([fold_of[g] for g in groups.tolist()])
    right = 0
    for k in range(folds):
        test = fold == k
        model = fit_logistic(x[~test], y[~test], l2=l2)
        right += int((model.predict(x[test]) == np.asarray(y)[test]).sum())
    return right / len(y)


@dataclass(frozen=True)
class TwoSampleRealism:
    """The two-sample realism test of one set of generated futures.

    Attributes:
        accuracy: held-out accuracy of real vs generated futures of the same windows (0.5 = indistinguishable).
        control: the same classifier on real vs real, the windows split in two random halves (about 0.5).
        windows: N; folds: cross-validation folds.
        by_family: the test on one family of :func:`motion_features` alone: ``speed``, ``acceleration``,
            ``spread`` -> held-out accuracy (which kind of difference tells the generated futures apart).
    """

    accuracy: float
    control: float
    windows: int
    folds: int
    by_family: dict


def real_vs_real_control(real_features: np.ndarray, *, folds: int = 5, seed: int = 0, l2: float = 1.0) -> float:
    """Held-out accuracy between the real futures of two random halves of the windows: real_features (N, P)
    -> about 0.5 (the chance level of :func:`cross_validated_accuracy` with N / 2 items per class)."""
    n = len(real_features)
    order = np.random.default_rng(seed + 1).permutation(n)
    y = np.zeros(n, np.int64)
    y[order[: n // 2]] = 1
    return cross_validated_accuracy(real_features, y, np.arange(n), folds=folds, seed=seed, l2=l2)


def two_sample_realism(real: np.ndarray, fake: np.ndarray, *, dim: int, folds: int = 5, seed: int = 0,
                       l2: float = 1.0) -> TwoSampleRealism:
    """Real futures (N, T, F) against generated futures (N, T, F) of the same N >= 4 observed windows (item i
    of both belongs to window i), un-normalised features with ``dim`` coordinates per point
    (:func:`motion_features`): held-out accuracy and the real-vs-real control (``folds``, at most N // 2)."""
    real, fake = np.asarray(real, np.float64), np.asarray(fake, np.float64)
    if real.shape != fake.shape:
        raise ValueError(f"real and generated futures must pair up window by window: {real.shape} vs {fake.shape}")
    if len(real) < 4:
        raise ValueError(f"the two-sample test needs at least 4 windows, got {len(real)}")
    folds = min(folds, len(real) // 2)  # the control's halves need at least one window per fold
    fr, ff = motion_features(real, dim=dim), motion_features(fake, dim=dim)
    n, g = len(fr), fr.shape[1] // len(FAMILIES)
    x = np.concatenate([fr, ff])
    y = np.concatenate([np.ones(n, np.int64), np.zeros(n, np.int64)])
    window = np.concatenate([np.arange(n), np.arange(n)])
    by_family = {name: cross_validated_accuracy(x[:, i * g:(i + 1) * g], y, window, folds=folds, seed=seed, l2=l2)
                 for i, name in enumerate(FAMILIES)}
    return TwoSampleRealism(accuracy=cross_validated_accuracy(x, y, window, folds=folds, seed=seed, l2=l2),
                            control=real_vs_real_control(fr, folds=folds, seed=seed, l2=l2), windows=n, folds=folds,
                            by_family=by_family)


def point_dim(layout_kind: str) -> int:
    """Coordinates per point of a feature layout for :func:`motion_features`: body3d 3, body2d 2, face 1."""
    return {"body3d": 3, "body2d": 2, "face": 1}[layout_kind]
