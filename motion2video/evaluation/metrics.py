"""Metrics of stochastic motion prediction: pure numpy functions, float64 throughout.

Shapes: ``pred`` is (N, K, T, D): K sampled futures of T frames for each of N test windows, each frame a
D-vector; ``gt`` is (N, T, D). For body motion the frame vector is the root-relative pose of the 16
non-root joints flattened (D = 48, metres; the DLow protocol), so a "distance" is the L2 norm of that
48-vector, not a per-joint mean. For faces it is the 58 face parameters (coefficient units).

- DLow protocol (Yuan & Kitani 2020): :func:`apd`, :func:`ade`, :func:`fde`, :func:`mmade`,
  :func:`mmfde` with :func:`multimodal_ground_truth`.
- MT-VAE (Yan et al. 2018): :func:`best_of_k_mse` (R-MSE when the K samples come from the recognition
  model, S-MSE when they come from the prior), :func:`parzen_log_likelihood` with the bandwidth chosen by
  :func:`select_parzen_bandwidth` on validation data.
- Behaviour-driven synthesis (Blattmann et al. 2021): :func:`transfer_displacement_error` (TDE),
  :func:`latent_distance` (d_beta), :func:`asd`, :func:`fsd`.
- LCP-VAE (Aliakbarian et al. 2020): :func:`diversity`, :func:`quality` (accuracy of a real/fake
  classifier: 0.5 means indistinguishable), :func:`context` (mean class accuracy of an action classifier
  trained on ground truth, tested on the generated futures). The classifier is a closed-form ridge
  regression on :func:`sequence_descriptor` (deterministic, no training loop).
- Known-answer multimodal benchmark: :func:`nearest_template`, :func:`mode_coverage`,
  :func:`mode_precision`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _f64(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def pairwise_distances(x: np.ndarray) -> np.ndarray:
    """Euclidean distances between all rows: x (..., K, P) -> (..., K, K), via the Gram matrix of the
    centred rows (no (K, K, P) intermediate), exact zeros on the diagonal."""
    x = _f64(x)
    x = x - x.mean(axis=-2, keepdims=True)  # centring keeps the Gram trick accurate (equal rows -> exactly 0)
    sq = (x * x).sum(axis=-1)  # (..., K)
    gram = x @ np.swapaxes(x, -1, -2)  # (..., K, K)
    d2 = np.maximum(sq[..., :, None] + sq[..., None, :] - 2.0 * gram, 0.0)
    k = x.shape[-2]
    d2[..., np.arange(k), np.arange(k)] = 0.0
    return np.sqrt(d2)


def _check_pred_gt(pred: np.ndarray, gt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pred, gt = _f64(pred), _f64(gt)
    if pred.ndim != 4 or gt.ndim != 3 or pred.shape[0] != gt.shape[0] or pred.shape[2:] != gt.shape[1:]:
        raise ValueError(f"need pred (N, K, T, D) and gt (N, T, D), got {pred.shape} and {gt.shape}")
    return pred, gt


# --- DLow protocol -----------------------------------------------------------------------------------------


def displacement(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Per-frame L2 distances: pred (N, K, T, D), gt (N, T, D) -> (N, K, T)."""
    pred, gt = _check_pred_gt(pred, gt)
    return np.linalg.norm(pred - gt[:, None], axis=-1)


def ade_per_window(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """(N,) best-of-K average displacement error: min over K of the mean over T of the L2 distance."""
    return best_of_k_displacements(displacement(pred, gt))["ade"]


def fde_per_window(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """(N,) best-of-K final displacement error: min over K of the L2 distance at the last frame."""
    return best_of_k_displacements(displacement(pred[:, :, -1:], gt[:, -1:]))["fde"]


def ade_per_frame(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """(T,) the displacement at each future frame of each window's best-of-K sample (the sample with the
    lowest ADE), averaged over windows; its mean over T is :func:`ade`."""
    return best_of_k_displacements(displacement(pred, gt))["ade_per_frame"]


def best_of_k_displacements(d: np.ndarray) -> dict[str, np.ndarray]:
    """The best-of-K scores of per-frame displacements d (N, K, T) (:func:`displacement`), computed from them
    once: ``ade`` (N,) and ``fde`` (N,) as :func:`ade_per_window` and :func:`fde_per_window`, ``ade_per_frame``
    (T,) as :func:`ade_per_frame`."""
    mean = d.mean(axis=2)  # (N, K)
    best = mean.argmin(axis=1)  # (N,)
    return {"ade": mean.min(axis=1), "fde": d[:, :, -1].min(axis=1),
            "ade_per_frame": d[np.arange(d.shape[0]), best].mean(axis=0)}


def framewise_oracle_ade_per_window(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """(N,) the mean over T of the minimum over K of the displacement at each frame: the ADE of a future stitched
    frame by frame from whichever of the K samples is closest at that frame. No choice of one sample per window
    (best-of-K ADE, :func:`ade_per_window`) can be lower, so it bounds what re-ordering or re-selecting the same K
    samples could reach. pred (N, K, T, D); gt (N, T, D)."""
    return displacement(pred, gt).min(axis=1).mean(axis=1)


def ade(pred: np.ndarray, gt: np.ndarray) -> float:
    """Best-of-K ADE averaged over windows (units of the frame vector)."""
    return float(ade_per_window(pred, gt).mean())


def fde(pred: np.ndarray, gt: np.ndarray) -> float:
    """Best-of-K FDE averaged over windows."""
    return float(fde_per_window(pred, gt).mean())


def apd_per_window(pred: np.ndarray) -> np.ndarray:
    """(N,) average pairwise distance of each window: the mean over sample pairs i < j of the L2 distance
    between whole flattened sequences (T * D); zeros when K = 1.

    Args:
        pred: (N, K, T, D).
    """
    pred = _f64(pred)
    n, k = pred.shape[:2]
    if k < 2:
        return np.zeros(n)
    dist = pairwise_distances(pred.reshape(n, k, -1))  # (N, K, K) between whole flattened sequences
    iu = np.triu_indices(k, 1)
    return dist[:, iu[0], iu[1]].mean(axis=1)


def apd(pred: np.ndarray) -> float:
    """Average pairwise distance: :func:`apd_per_window` averaged over windows; 0 when K = 1.

    Args:
        pred: (N, K, T, D).
    """
    return float(apd_per_window(pred).mean())


def multimodal_ground_truth(last_observed: np.ndarray, *, threshold: float) -> list[np.ndarray]:
    """DLow's multimodal ground truth: for each window, the indices of all windows (itself included)
    whose last observed frame vector lies within ``threshold`` (L2) of its own.

    Args:
        last_observed: (N, D) frame vectors of the last observed frame.
        threshold: distance threshold in the frame vector's units (DLow uses 0.5 m on H36M).
    Returns:
        N integer index arrays.
    """
    x = _f64(last_observed)
    dist = pairwise_distances(x)  # (N, N)
    return [np.flatnonzero(row <= threshold) for row in dist]


def multimodal_per_window(pred: np.ndarray, futures: np.ndarray, groups: list[np.ndarray], *,
                          final: bool) -> np.ndarray:
    """(n,) per window i: the mean over the futures j in ``groups[i]`` of the best-of-K ADE (``final``:
    FDE) against future j. pred (n, K, T, D); futures (N, T, D) the ground-truth futures of all N windows, which
    the groups index; groups from :func:`multimodal_ground_truth`, one per row of pred (pred may hold a block of
    the N windows, with their groups)."""
    pred, futures = _f64(pred), _f64(futures)
    if pred.ndim != 4 or futures.ndim != 3 or pred.shape[2:] != futures.shape[1:]:
        raise ValueError(f"need pred (n, K, T, D) and futures (N, T, D), got {pred.shape} and {futures.shape}")
    if len(groups) != pred.shape[0]:
        raise ValueError(f"need one group per window: {len(groups)} groups for {pred.shape[0]} windows")
    scores = np.empty(len(groups))
    for i, idx in enumerate(groups):
        others = futures[idx]  # (M, T, D)
        if final:  # the last frame only: (K, M)
            err = np.linalg.norm(pred[i][:, None, -1] - others[None, :, -1], axis=-1)
        else:
            err = np.linalg.norm(pred[i][:, None] - others[None], axis=-1).mean(axis=2)  # (K, M, T) -> (K, M)
        scores[i] = err.min(axis=0).mean()  # best sample per ground truth, averaged over them
    return scores


def _multimodal(pred: np.ndarray, futures: np.ndarray, groups: list[np.ndarray], final: bool) -> float:
    return float(np.mean(multimodal_per_window(pred, futures, groups, final=final)))


def mmade(pred: np.ndarray, futures: np.ndarray, groups: list[np.ndarray]) -> float:
    """Multimodal ADE: for each window i, the mean over the futures j in ``groups[i]`` of the best-of-K
    ADE against future j; averaged over windows.

    Args:
        pred: (N, K, T, D) samples; futures: (N, T, D) the ground-truth futures of all windows;
        groups: from :func:`multimodal_ground_truth`.
    """
    return _multimodal(pred, futures, groups, final=False)


def mmfde(pred: np.ndarray, futures: np.ndarray, groups: list[np.ndarray]) -> float:
    """Multimodal FDE (as :func:`mmade`, on the last frame)."""
    return _multimodal(pred, futures, groups, final=True)


# --- MT-VAE ----------------------------------------------------------------------------------------------


def best_of_k_mse(pred: np.ndarray, gt: np.ndarray) -> float:
    """Minimum over K of the mean squared error per coordinate (over T and D), averaged over windows.

    R-MSE (MT-VAE eq. 6) when the K samples decode latents drawn from the recognition model
    q(z | obs, future); S-MSE (eq. 7) when they are drawn from the prior.
    """
    return float(best_of_k_mse_per_window(pred, gt).mean())


def best_of_k_mse_per_window(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """(N,) per window, the minimum over K of the mean squared error per coordinate (:func:`best_of_k_mse`).
    pred (N, K, T, D); gt (N, T, D)."""
    pred, gt = _check_pred_gt(pred, gt)
    return ((pred - gt[:, None]) ** 2).mean(axis=(2, 3)).min(axis=1)


def parzen_log_likelihood(samples: np.ndarray, gt: np.ndarray, *, bandwidth: float) -> np.ndarray:
    """Parzen-window (isotropic Gaussian kernel) estimate of log p(gt | obs) from K samples.

    ``log p = logsumexp_k(-||gt - s_k||^2 / (2 h^2)) - log K - (M / 2) log(2 pi h^2)``.

    Args:
        samples: (N, K, ...) samples; gt: (N, ...) ground truth (both flattened to M numbers).
        bandwidth: kernel standard deviation h > 0.
    Returns:
        (N,) log-likelihoods in nats.
    """
    if bandwidth <= 0:
        raise ValueError(f"bandwidth must be positive, got {bandwidth}")
    s, g = _f64(samples), _f64(gt)
    n, k = s.shape[:2]
    s = s.reshape(n, k, -1)
    g = g.reshape(n, -1)
    m = g.shape[1]
    sq = ((s - g[:, None]) ** 2).sum(axis=-1)  # (N, K)
    a = -sq / (2.0 * bandwidth ** 2)
    amax = a.max(axis=1, keepdims=True)
    lse = amax[:, 0] + np.log(np.exp(a - amax).sum(axis=1))
    return lse - np.log(k) - 0.5 * m * np.log(2.0 * np.pi * bandwidth ** 2)


def select_parzen_bandwidth(samples: np.ndarray, gt: np.ndarray, *, candidates: np.ndarray | None = None) -> float:
    """The bandwidth among ``candidates`` (default: 25 values log-spaced in [1e-3, 10]) that maximises the
    mean Parzen log-likelihood of the (validation) ground truth."""
    cands = np.logspace(-3, 1, 25) if candidates is None else _f64(candidates)
    scores = [parzen_log_likelihood(samples, gt, bandwidth=float(h)).mean() for h in cands]
    return float(cands[int(np.argmax(scores))])


# --- Behaviour-driven synthesis ------------------------------------------------------------------------------


def transfer_displacement_error(reenacted: np.ndarray, source: np.ndarray, *, timesteps) -> np.ndarray:
    """TDE: mean squared error between the re-enactment x_R and the behaviour source x_beta at the given
    (0-based) frame indices, averaged over windows and coordinates.

    Args:
        reenacted, source: (N, T, D).
        timesteps: frame indices, e.g. ``(0, 9, 19, 29, 39, 49)`` for the paper's T = 1, 10, ..., 50.
    Returns:
        (len(timesteps),) float64.
    """
    r, s = _f64(reenacted), _f64(source)
    if r.shape != s.shape or r.ndim != 3:
        raise ValueError(f"need two (N, T, D) arrays of the same shape, got {r.shape} and {s.shape}")
    idx = np.asarray(timesteps, dtype=np.int64)
    return ((r[:, idx] - s[:, idx]) ** 2).mean(axis=(0, 2))


@dataclass(frozen=True)
class MeanStd:
    mean: float
    std: float


def latent_distance(z_a: np.ndarray, z_b: np.ndarray) -> MeanStd:
    """d_beta: Euclidean distance between paired latent codes (N, Z), mean and standard deviation."""
    a, b = _f64(z_a), _f64(z_b)
    if a.shape != b.shape:
        raise ValueError(f"latent shapes differ: {a.shape} vs {b.shape}")
    d = np.linalg.norm(a - b, axis=-1)
    return MeanStd(float(d.mean()), float(d.std()))


def _self_distance(x: np.ndarray) -> float:
    """x (N, K, M): for each sample, the distance to its nearest other sample of the same window; mean."""
    n, k = x.shape[:2]
    if k < 2:
        raise ValueError("ASD/FSD need at least two samples per window")
    dist = pairwise_distances(x)  # (N, K, K)
    dist[:, np.arange(k), np.arange(k)] = np.inf
    return float(dist.min(axis=2).mean())


def asd(pred: np.ndarray) -> float:
    """Average self distance: the mean distance from each sample (whole flattened sequence) to its
    closest other sample of the same window. pred: (N, K, T, D)."""
    p = _f64(pred)
    return _self_distance(p.reshape(p.shape[0], p.shape[1], -1))


def fsd(pred: np.ndarray) -> float:
    """Final self distance: as :func:`asd` on the last frame only. pred: (N, K, T, D)."""
    return _self_distance(_f64(pred)[:, :, -1])


# --- LCP-VAE -------------------------------------------------------------------------------------------------


def diversity(pred: np.ndarray) -> float:
    """LCP diversity: the mean over windows and sample pairs i < j of the per-frame L2 distance averaged
    over time (0 when K = 1). pred: (N, K, T, D)."""
    p = _f64(pred)
    n, k = p.shape[:2]
    if k < 2:
        return 0.0
    dist = pairwise_distances(np.swapaxes(p, 1, 2)).mean(axis=1)  # (N, T, K, K) per frame -> mean over T
    iu = np.triu_indices(k, 1)
    return float(dist[:, iu[0], iu[1]].mean())


def liveliness(seq: np.ndarray) -> tuple[float, float]:
    """How lively motion is: (mean |velocity|, mean |acceleration|) over every feature of (..., T, F)
    sequences, per frame (units of the features per frame, per frame^2)."""
    s = _f64(seq)
    return float(np.abs(np.diff(s, 1, axis=-2)).mean()), float(np.abs(np.diff(s, 2, axis=-2)).mean())


def liveliness_per_window(seq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`liveliness` of each window of (N, ..., T, F) sequences: two (N,) arrays. Every window holds as many
    values, so the mean over any set of windows is :func:`liveliness` of that set (to float rounding)."""
    s = _f64(seq)
    n = s.shape[0]
    vel = np.diff(s, 1, axis=-2)
    acc = np.diff(vel, 1, axis=-2)
    return np.abs(vel).reshape(n, -1).mean(axis=1), np.abs(acc).reshape(n, -1).mean(axis=1)


def sequence_descriptor(seq: np.ndarray) -> np.ndarray:
    """A fixed-length description of sequences for the classifiers: positions at every 4th frame, and the
    mean absolute velocity and acceleration and the standard deviation of each coordinate.

    Args:
        seq: (..., T, D), T >= 3.
    Returns:
        (..., ceil(T / 4) * D + 3 * D).
    """
    s = _f64(seq)
    vel = np.diff(s, axis=-2)
    acc = np.diff(vel, axis=-2)
    lead = s.shape[:-2]
    return np.concatenate([
        s[..., ::4, :].reshape(lead + (-1,)),
        np.abs(vel).mean(axis=-2), np.abs(acc).mean(axis=-2), s.std(axis=-2),
    ], axis=-1)


@dataclass(frozen=True)
class RidgeClassifier:
    """A linear least-squares classifier on standardised inputs (one-vs-rest targets +-1)."""

    mean: np.ndarray  # (P,)
    scale: np.ndarray  # (P,)
    weights: np.ndarray  # (P + 1, C)
    classes: np.ndarray  # (C,)

    def predict(self, x: np.ndarray) -> np.ndarray:
        z = (_f64(x) - self.mean) / self.scale
        scores = np.concatenate([z, np.ones((len(z), 1))], axis=1) @ self.weights
        return self.classes[np.argmax(scores, axis=1)]


def fit_ridge_classifier(x: np.ndarray, y: np.ndarray, *, l2: float = 1.0) -> RidgeClassifier:
    """Closed-form ridge regression onto one-hot (+-1) targets. x: (N, P) features; y: (N,) labels."""
    x, y = _f64(x), np.asarray(y)
    classes = np.unique(y)
    mean, scale = x.mean(axis=0), x.std(axis=0) + 1e-8
    z = np.concatenate([(x - mean) / scale, np.ones((len(x), 1))], axis=1)  # (N, P + 1)
    targets = np.where(y[:, None] == classes[None], 1.0, -1.0)  # (N, C)
    reg = l2 * np.eye(z.shape[1])
    reg[-1, -1] = 0.0  # no penalty on the bias
    if z.shape[0] < z.shape[1]:  # dual form: P + 1 > N
        kernel = z @ z.T + l2 * np.eye(len(z))
        weights = z.T @ np.linalg.solve(kernel, targets)
    else:
        weights = np.linalg.solve(z.T @ z + reg, z.T @ targets)
    return RidgeClassifier(mean, scale, weights, classes)


def mean_class_accuracy(pred: np.ndarray, truth: np.ndarray) -> float:
    """Mean over the classes present in ``truth`` of the share of their items predicted right."""
    pred, truth = np.asarray(pred), np.asarray(truth)
    return float(np.mean([np.mean(pred[truth == c] == c) for c in np.unique(truth)]))


def quality(real: np.ndarray, fake: np.ndarray, *, l2: float = 1.0) -> float:
    """LCP quality: test accuracy of a real/fake classifier (lower is better, 0.5 = indistinguishable).

    Items with even index train the classifier, odd ones test it (deterministic).

    Args:
        real: (N, T, D) ground-truth futures; fake: (M, T, D) generated futures.
    """
    real_d, fake_d = sequence_descriptor(real), sequence_descriptor(fake)
    x = np.concatenate([real_d, fake_d])
    y = np.concatenate([np.ones(len(real_d), np.int64), np.zeros(len(fake_d), np.int64)])
    is_train = np.concatenate([np.arange(len(real_d)) % 2 == 0, np.arange(len(fake_d)) % 2 == 0])
    clf = fit_ridge_classifier(x[is_train], y[is_train], l2=l2)
    return float(np.mean(clf.predict(x[~is_train]) == y[~is_train]))


def context(train_futures: np.ndarray, train_labels: np.ndarray, pred: np.ndarray, labels: np.ndarray,
            *, l2: float = 1.0) -> float:
    """LCP context: an action classifier trained on ground-truth futures, tested on every generated
    future; mean class accuracy over the K x N samples.

    Args:
        train_futures: (M, T, D) ground-truth futures with ``train_labels`` (M,).
        pred: (N, K, T, D) generated futures of windows whose true labels are ``labels`` (N,).
    """
    clf = fit_ridge_classifier(sequence_descriptor(train_futures), np.asarray(train_labels), l2=l2)
    p = _f64(pred)
    n, k = p.shape[:2]
    guesses = clf.predict(sequence_descriptor(p.reshape((n * k,) + p.shape[2:])))
    return mean_class_accuracy(guesses, np.repeat(np.asarray(labels), k))


# --- known-answer multimodal benchmark -------------------------------------------------------------------------


def nearest_template(futures: np.ndarray, templates: np.ndarray, *, max_distance: float | None = None) -> np.ndarray:
    """Mode classifier: the index of the template closest (mean per-frame L2) to each future.

    Args:
        futures: (..., T, D); templates: (M, T, D), one per mode.
        max_distance: when given, a future farther than this from every template gets mode -1 (none).
    Returns:
        (...,) int64 mode indices (-1: no mode).
    """
    f, t = _f64(futures), _f64(templates)
    dist = np.linalg.norm(f[..., None, :, :] - t, axis=-1).mean(axis=-1)  # (..., M)
    best = np.argmin(dist, axis=-1)
    if max_distance is not None:
        best = np.where(np.min(dist, axis=-1) <= max_distance, best, -1)
    return best


def _hits(modes: np.ndarray, num_modes: int) -> np.ndarray:
    """(N, K) mode indices (-1 = none) -> (N, K, M) one-hot (all False for -1)."""
    return np.asarray(modes)[..., None] == np.arange(num_modes)


def mode_coverage(modes: np.ndarray, valid: np.ndarray) -> float:
    """Share of the true possible modes hit by at least one sample, averaged over windows.

    Args:
        modes: (N, K) mode index of each sample (-1: none); valid: (N, M) bool, the modes possible for
            each window.
    """
    valid = np.asarray(valid, bool)
    hit = _hits(modes, valid.shape[1]).any(axis=1)  # (N, M)
    return float(((hit & valid).sum(axis=1) / valid.sum(axis=1)).mean())


def mode_precision(modes: np.ndarray, valid: np.ndarray) -> float:
    """Share of samples whose mode is one of the window's possible modes (-1 never is). Shapes as
    :func:`mode_coverage`."""
    valid = np.asarray(valid, bool)
    return float((_hits(modes, valid.shape[1]) & valid[:, None]).any(axis=2).mean())
