"""Evaluate motion models on the same windows with the DLow protocol (and MT-VAE's R-MSE / S-MSE / CLL).

:func:`evaluate_bundles` runs every model on every window of a split, K samples each, and computes the
metrics of :mod:`motion2video.evaluation.metrics` on un-normalised, root-relative frame vectors
(:func:`motion2video.data.windows.metric_vectors`: metres for body3d, virtual-camera image heights for
body2d, parameter units for faces). The ``evaluate`` command and ``scripts/make_results.py`` call it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import torch

from motion2video.evaluation import metrics as M
from motion2video.models.checkpoint import ModelBundle
from motion2video.data.dataset import WindowSet
from motion2video.data.windows import FeatureLayout, metric_vectors
from motion2video.evaluation.per_action import COUNT_KEY, group_by_action, macro_average, per_action_means
from motion2video.stages.sampling import as_model_input, keep_bone_lengths
from motion2video.stages.sampling import sample_futures

# DLow's multimodal threshold is 0.5 m on H36M; the others give a similar share of neighbours here.
MM_THRESHOLDS = {"body3d": 0.5, "body2d": 0.1, "face": 0.25}
MAIN_METRICS = ("ade", "fde", "mmade", "mmfde", "apd")


@dataclass(frozen=True)
class EvalProtocol:
    """How windows are scored.

    Attributes:
        samples: K futures per window (best-of-K for ADE / FDE, pairs for APD).
        stride: frames between evaluated windows.
        split: ``"test"`` (held-out groups, plus clips the checkpoint never saw), ``"val"``, ``"train"`` or
            ``"all"``.
        seed: seeds every model's sampling (the same seed for each method).
        mm_threshold: multimodal ground-truth threshold on the last observed frame vector (None: the
            layout default of :data:`MM_THRESHOLDS`).
        batch_size: windows per model call.
        rigid_bones: 3D body models: score the futures with the last observed frame's bone lengths, as
            ``sample --rigid-bones`` draws them (:func:`rigid_vectors`).
        continue_motion: learned models' futures continue the observed motion, as every command samples them
            (:func:`motion2video.stages.sampling.continue_observed`); False scores the networks' raw futures.
    """

    samples: int = 50
    stride: int = 16
    split: str = "test"
    seed: int = 0
    mm_threshold: float | None = None
    batch_size: int = 32
    rigid_bones: bool = False
    continue_motion: bool = True

    def threshold(self, layout: FeatureLayout) -> float:
        return MM_THRESHOLDS[layout.kind] if self.mm_threshold is None else float(self.mm_threshold)


@dataclass
class EvalResult:
    """Per-method metrics on one set of windows.

    Attributes:
        protocol: a JSON-able description of what was measured.
        results: method name -> metric name -> value, pooled over all windows.
        per_action: method name -> action -> the same metric names, over that action's windows, plus
            ``"windows"`` (their count). Per-window metrics (ADE, FDE, MMADE, MMFDE, APD, S-MSE) are the mean
            over the action's windows (the multimodal ground truth of MMADE / MMFDE still draws on all windows),
            so the pooled value is their window-weighted mean; velocity / acceleration ratios are measured on
            the action's windows alone.
        macro: method name -> metric name -> the unweighted mean over actions of ``per_action``.
        ade_per_frame: method name -> best-of-K displacement at each future frame (see
            :func:`motion2video.evaluation.metrics.ade_per_frame`), the curve ``evaluate --plot`` draws.
    """

    protocol: dict
    results: dict[str, dict[str, float]] = field(default_factory=dict)
    per_action: dict[str, dict[str, dict[str, float]]] = field(default_factory=dict)
    macro: dict[str, dict[str, float]] = field(default_factory=dict)
    ade_per_frame: dict[str, list[float]] = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"protocol": self.protocol, "results": self.results, "per_action": self.per_action,
                "macro": self.macro, "ade_per_frame": self.ade_per_frame}

    def table(self, columns: tuple[str, ...] = MAIN_METRICS) -> str:
        """A fixed-width text table, one row per method (pooled over all windows)."""
        return _rows_table(self.results, columns)

    def macro_table(self, columns: tuple[str, ...] = MAIN_METRICS) -> str:
        """The macro average over actions, one row per method."""
        return _rows_table(self.macro, columns)

    def per_action_table(self, columns: tuple[str, ...] = MAIN_METRICS) -> str:
        """One row per (action, method), the actions in the order of ``per_action`` (most windows first)."""
        methods = list(self.per_action)
        actions = list(next(iter(self.per_action.values()))) if methods else []
        rows = {f"{a} ({self.per_action[methods[0]][a][COUNT_KEY]}) {m}": self.per_action[m][a]
                for a in actions for m in methods}
        return _rows_table(rows, columns, first="action (windows) method")


def _rows_table(rows: dict[str, dict[str, float]], columns: tuple[str, ...], *, first: str = "method") -> str:
    """A fixed-width text table: one row per key of ``rows``, one column per metric name."""
    width = max([len(first)] + [len(n) for n in rows])
    head = f"{first:<{width}}  " + "  ".join(f"{c:>8}" for c in columns)
    lines = [head, "-" * len(head)]
    for n, row in rows.items():
        vals = [row.get(c) for c in columns]
        lines.append(f"{n:<{width}}  " + "  ".join(f"{v:8.4f}" if v is not None else f"{'-':>8}" for v in vals))
    return "\n".join(lines)


@torch.no_grad()
def posterior_futures(model: torch.nn.Module, obs: np.ndarray, future: np.ndarray, *, num_samples: int, seed: int,
                      batch_size: int = 32, from_mean: bool = False) -> np.ndarray | None:
    """K reconstructions per window from latents drawn from the recognition model q(z | obs, future)
    (for R-MSE): (N, K, Tf, F) normalised, or None for models without ``encode`` / ``decode``. ``from_mean``:
    every latent is the recognition model's mean instead (the decoder's ceiling: what the best latents could give)."""
    if not (hasattr(model, "encode") and hasattr(model, "decode")):
        return None
    model.eval()
    gen = torch.Generator().manual_seed(seed)
    out = []
    horizon = future.shape[1]
    for i in range(0, len(obs), batch_size):
        o, f = as_model_input(obs[i:i + batch_size], model), as_model_input(future[i:i + batch_size], model)
        post = model.encode(o, f)
        b, z_dim = post.mu.shape
        eps = torch.randn((b, num_samples, z_dim), generator=gen).to(post.mu.device)
        if from_mean:
            eps = torch.zeros_like(eps)
        z = post.mu[:, None] + torch.exp(0.5 * post.logvar)[:, None] * eps  # (B, K, Z)
        rec = model.decode(o.repeat_interleave(num_samples, 0), z.reshape(b * num_samples, z_dim), horizon=horizon)
        out.append(rec.reshape(b, num_samples, horizon, -1).float().cpu().numpy())
    return np.concatenate(out)


def rigid_vectors(pred: np.ndarray, last_observed: np.ndarray) -> np.ndarray:
    """Body3d metric vectors (root-relative non-root joints) of samples pred (N, K, T, 48) with every frame's
    bones set to the lengths of the window's last observed frame last_observed (N, 48), directions kept
    (:func:`motion2video.stages.sampling.keep_bone_lengths`; bone lengths do not depend on the root)."""
    def joints(v: np.ndarray) -> np.ndarray:  # (..., 48) -> (..., 17, 3), the root at the origin
        j = v.reshape(*v.shape[:-1], -1, 3)
        return np.concatenate([np.zeros_like(j[..., :1, :]), j], axis=-2)

    out = [keep_bone_lengths(joints(p), joints(last))[..., 1:, :].reshape(p.shape)
           for p, last in zip(np.asarray(pred, np.float64), np.asarray(last_observed, np.float64))]
    return np.stack(out)


def dlow_metrics_per_window(pred: np.ndarray, gt: np.ndarray, last_observed: np.ndarray, *,
                            threshold: float) -> dict[str, np.ndarray]:
    """ADE, FDE, MMADE, MMFDE and APD of each window: metric-space samples pred (N, K, T, D) against gt
    (N, T, D), the multimodal ground truth drawn from all N windows -> name -> (N,)."""
    groups = M.multimodal_ground_truth(last_observed, threshold=threshold)
    return {
        "ade": M.ade_per_window(pred, gt),
        "fde": M.fde_per_window(pred, gt),
        "mmade": M.multimodal_per_window(pred, gt, groups, final=False),
        "mmfde": M.multimodal_per_window(pred, gt, groups, final=True),
        "apd": M.apd_per_window(pred),
    }


def dlow_metrics(pred: np.ndarray, gt: np.ndarray, last_observed: np.ndarray, *, threshold: float) -> dict[str, float]:
    """ADE, FDE, MMADE, MMFDE and APD of metric-space samples pred (N, K, T, D) against gt (N, T, D): the
    means over windows of :func:`dlow_metrics_per_window`."""
    per_window = dlow_metrics_per_window(pred, gt, last_observed, threshold=threshold)
    return {k: float(v.mean()) for k, v in per_window.items()}


def liveliness_ratios(samples: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """How lively samples (N, K, T, F) are against the true futures (N, T, F), un-normalised features:
    ``velocity_ratio`` and ``acceleration_ratio`` of their mean absolute velocity / acceleration
    (:func:`motion2video.evaluation.metrics.liveliness`)."""
    (v, a), (v_true, a_true) = M.liveliness(samples), M.liveliness(truth)
    return {"velocity_ratio": v / v_true, "acceleration_ratio": a / a_true}


def evaluate_bundles(bundles: list[ModelBundle], windows: WindowSet, *, protocol: EvalProtocol,
                     extended: bool = False, val_windows: WindowSet | None = None) -> EvalResult:
    """Score every bundle on ``windows`` (all bundles must share the layout; a bundle whose normalisation
    statistics differ from the first one's, which the windows were built with, gets its own normalisation).

    Args:
        bundles: models and baselines; their names key the results.
        windows: from :meth:`MotionDataset.windows`.
        protocol: samples, seed, threshold.
        extended: also compute S-MSE (best-of-K MSE of the prior samples), R-MSE (best-of-K MSE of
            recognition-model reconstructions, latent models only) and the Parzen conditional
            log-likelihood (``cll``, nats per window; needs ``val_windows`` to choose the bandwidth).
    Returns:
        An :class:`EvalResult`: pooled, per action (the windows' ``labels``) and macro over actions.
    """
    if len(windows) == 0:
        raise ValueError("no windows to evaluate")
    layout = bundles[0].layout
    stats = bundles[0].stats
    obs_len = windows.observed
    horizon = windows.features.shape[1] - obs_len
    gt = metric_vectors(windows.raw[:, obs_len:], layout)  # (N, Tf, D)
    last = metric_vectors(windows.raw[:, obs_len - 1], layout)  # (N, D)
    threshold = protocol.threshold(layout)
    groups = M.multimodal_ground_truth(last, threshold=threshold)
    actions = group_by_action(windows.labels)
    result = EvalResult(protocol={
        **dataclasses.asdict(protocol), "mm_threshold": threshold, "layout": layout.kind,
        "units": layout.metric_units, "observed": obs_len, "future": horizon, "windows": len(windows),
        "clips": sorted(set(windows.clip_names)),
        "mean_multimodal_futures": float(np.mean([len(g) for g in groups])),
        "best_of": protocol.samples,
        "actions": {a: int(len(idx)) for a, idx in actions.items()},
        "metric_space": "root-relative non-root joints" if layout.is_body else "face parameters",
    })

    for bundle in bundles:
        if bundle.layout.kind != layout.kind:
            raise ValueError(f"{bundle.label} works on {bundle.layout.kind}, not {layout.kind}")
        own = bundle.stats

        def to_metric(samples_norm: np.ndarray, own=own) -> np.ndarray:
            return metric_vectors(own.denormalize(samples_norm), layout)

        def renorm(x: np.ndarray, own=own) -> np.ndarray:
            return x if own.same_as(stats) else own.normalize(stats.denormalize(x))

        samples = sample_futures(bundle.model, renorm(windows.obs), num_samples=protocol.samples,
                                 horizon=horizon, seed=protocol.seed, batch_size=protocol.batch_size,
                                 continue_motion=protocol.continue_motion)
        pred = to_metric(samples)
        if protocol.rigid_bones and layout.kind == "body3d":
            pred = rigid_vectors(pred, last)
        per_window = dlow_metrics_per_window(pred, gt, last, threshold=threshold)
        bandwidth = None
        if extended:
            per_window["s_mse"] = M.best_of_k_mse_per_window(pred, gt)
            rec = posterior_futures(bundle.model, renorm(windows.obs), renorm(windows.future), num_samples=protocol.samples,
                                    seed=protocol.seed, batch_size=protocol.batch_size)
            if rec is not None:
                per_window["r_mse"] = M.best_of_k_mse_per_window(to_metric(rec), gt)
            if val_windows is not None and len(val_windows) > 0:
                val_pred = to_metric(sample_futures(bundle.model, renorm(val_windows.obs), num_samples=protocol.samples,
                                                    horizon=horizon, seed=protocol.seed + 1,
                                                    batch_size=protocol.batch_size,
                                                    continue_motion=protocol.continue_motion))
                val_gt = metric_vectors(val_windows.raw[:, obs_len:], layout)
                bandwidth = M.select_parzen_bandwidth(val_pred, val_gt)
                per_window["cll"] = M.parzen_log_likelihood(pred, gt, bandwidth=bandwidth)
        row = {k: float(v.mean()) for k, v in per_window.items()}
        if bandwidth is not None:
            row["parzen_bandwidth"] = bandwidth
        by_action = per_action_means(per_window, actions)
        # how lively the samples are against the true futures (all features, root included; before rigid_bones)
        lively, truth = own.denormalize(samples), windows.raw[:, obs_len:]
        row.update(liveliness_ratios(lively, truth))
        for action, idx in actions.items():
            by_action[action].update(liveliness_ratios(lively[idx], truth[idx]))
        result.ade_per_frame[bundle.label] = [float(v) for v in M.ade_per_frame(pred, gt)]
        result.results[bundle.label] = {k: float(v) for k, v in row.items()}
        result.per_action[bundle.label] = by_action
        result.macro[bundle.label] = macro_average(by_action)
    return result
