"""Evaluate motion models on the same windows with the DLow protocol (and MT-VAE's R-MSE / S-MSE / CLL).

:func:`evaluate_bundles` runs every model on every window of a split, K samples each, and computes the
metrics of :mod:`motion2video.evaluation.metrics` on un-normalised, root-relative frame vectors
(:func:`motion2video.data.windows.metric_vectors`: metres for body3d, virtual-camera image heights for
body2d, parameter units for faces). :func:`evaluate_models` is the ``evaluate`` command's work (models loaded
by name, their windows built from a data folder, the results written as JSON and a plot);
``scripts/make_results.py`` calls :func:`evaluate_bundles` directly.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from motion2video.core.atomic import write_json
from motion2video.core.errors import InputError
from motion2video.core.skeletons import bone_lengths, with_bone_lengths
from motion2video.evaluation import metrics as M
from motion2video.evaluation.plots import plot_ade_per_frame
from motion2video.models.baselines import BASELINES, RULES
from motion2video.models.checkpoint import ModelBundle, baseline_bundle, load_model
from motion2video.data.corpus import BANDAI_SOURCES, source_of
from motion2video.data.dataset import WindowSet, build_dataset
from motion2video.data.windows import FeatureLayout, metric_vectors
from motion2video.evaluation.per_action import (COUNT_KEY, family_key, group_by_action, macro_average, per_action_means,
                                                subject_split_report)
from motion2video.stages.sampling import as_model_input
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
        return rows_table(self.results, columns)

    def macro_table(self, columns: tuple[str, ...] = MAIN_METRICS) -> str:
        """The macro average over actions, one row per method."""
        return rows_table(self.macro, columns)

    def per_action_table(self, columns: tuple[str, ...] = MAIN_METRICS) -> str:
        """One row per (action, method), the actions in the order of ``per_action`` (most windows first)."""
        methods = list(self.per_action)
        actions = list(next(iter(self.per_action.values()))) if methods else []
        rows = {f"{a} ({self.per_action[methods[0]][a][COUNT_KEY]}) {m}": self.per_action[m][a]
                for a in actions for m in methods}
        return rows_table(rows, columns, first="action (windows) method")


def rows_table(rows: dict[str, dict[str, float]], columns: tuple[str, ...], *, first: str = "method") -> str:
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
    (:func:`motion2video.core.skeletons.with_bone_lengths`, as ``sample --rigid-bones``; bone lengths do not
    depend on the root)."""
    def joints(v: np.ndarray) -> np.ndarray:  # (..., 48) -> (..., 17, 3), the root at the origin
        j = v.reshape(*v.shape[:-1], -1, 3)
        return np.concatenate([np.zeros_like(j[..., :1, :]), j], axis=-2)

    pred = np.asarray(pred, np.float64)
    lengths = bone_lengths(joints(np.asarray(last_observed, np.float64)))[:, None, None]  # (N, 1, 1, 17)
    return with_bone_lengths(joints(pred), lengths)[..., 1:, :].reshape(pred.shape)


def dlow_metrics_per_window(pred: np.ndarray, gt: np.ndarray, last_observed: np.ndarray, *,
                            threshold: float) -> dict[str, np.ndarray]:
    """ADE, FDE, MMADE, MMFDE and APD of each window: metric-space samples pred (N, K, T, D) against gt
    (N, T, D), the multimodal ground truth drawn from all N windows -> name -> (N,)."""
    groups = M.multimodal_ground_truth(last_observed, threshold=threshold)
    return _dlow_block(pred, gt, groups, M.best_of_k_displacements(M.displacement(pred, gt)))


def _dlow_block(pred: np.ndarray, futures: np.ndarray, groups: list[np.ndarray], best: dict[str, np.ndarray]
                ) -> dict[str, np.ndarray]:
    """ADE, FDE, MMADE, MMFDE and APD of a block of n windows: samples pred (n, K, T, D), the true futures of all
    windows (N, T, D), the block's multimodal groups (n) and its :func:`~motion2video.evaluation.metrics.
    best_of_k_displacements` -> name -> (n,)."""
    return {
        "ade": best["ade"],
        "fde": best["fde"],
        "mmade": M.multimodal_per_window(pred, futures, groups, final=False),
        "mmfde": M.multimodal_per_window(pred, futures, groups, final=True),
        "apd": M.apd_per_window(pred),
    }


def dlow_metrics(pred: np.ndarray, gt: np.ndarray, last_observed: np.ndarray, *, threshold: float) -> dict[str, float]:
    """ADE, FDE, MMADE, MMFDE and APD of metric-space samples pred (N, K, T, D) against gt (N, T, D): the
    means over windows of :func:`dlow_metrics_per_window`."""
    per_window = dlow_metrics_per_window(pred, gt, last_observed, threshold=threshold)
    return {k: float(v.mean()) for k, v in per_window.items()}


def liveliness_ratios(samples: tuple[np.ndarray, np.ndarray], truth: tuple[np.ndarray, np.ndarray],
                      groups: dict[str, np.ndarray]) -> tuple[dict[str, float], dict[str, dict[str, float]]]:
    """How lively samples are against the true futures: ``velocity_ratio`` and ``acceleration_ratio`` of their
    mean absolute velocity / acceleration over all windows and over each group of window indices (name -> (M,)).

    Args:
        samples, truth: per window (N,) each, the mean absolute velocity and acceleration of the samples
            (N, K, T, F) and of the true futures (N, T, F), un-normalised features
            (:func:`motion2video.evaluation.metrics.liveliness_per_window`).
    Returns:
        (all windows' ratios, group name -> its ratios).
    """
    (v, a), (v_true, a_true) = samples, truth

    def ratios(idx) -> dict[str, float]:
        return {"velocity_ratio": float(v[idx].mean() / v_true[idx].mean()),
                "acceleration_ratio": float(a[idx].mean() / a_true[idx].mean())}

    return ratios(slice(None)), {name: ratios(idx) for name, idx in groups.items()}


# Windows scored at a time: a block's float64 samples stay under this many bytes. Arrays this small are reused from
# the heap block after block, where whole-test-set arrays (300 MB at 301 windows x 50 samples) were fresh pages
# every time: a third of evaluate's time went to the kernel, and its peak memory was several of them.
BLOCK_BYTES = 16 << 20


def window_blocks(n: int, row_bytes: int) -> list[slice]:
    """``n`` windows in blocks of at most :data:`BLOCK_BYTES` at ``row_bytes`` a window (at least one each)."""
    size = max(1, BLOCK_BYTES // max(1, row_bytes))
    return [slice(i, min(n, i + size)) for i in range(0, n, size)]


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
    true_moves = M.liveliness_per_window(windows.raw[:, obs_len:])  # the true futures' (all features)
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
                                 continue_motion=protocol.continue_motion)  # (N, K, T, F) normalised
        rec, bandwidth = None, None
        if extended:
            rec = posterior_futures(bundle.model, renorm(windows.obs), renorm(windows.future), num_samples=protocol.samples,
                                    seed=protocol.seed, batch_size=protocol.batch_size)
            if val_windows is not None and len(val_windows) > 0:
                val_pred = to_metric(sample_futures(bundle.model, renorm(val_windows.obs), num_samples=protocol.samples,
                                                    horizon=horizon, seed=protocol.seed + 1,
                                                    batch_size=protocol.batch_size,
                                                    continue_motion=protocol.continue_motion))
                val_gt = metric_vectors(val_windows.raw[:, obs_len:], layout)
                bandwidth = M.select_parzen_bandwidth(val_pred, val_gt)
        blocks: dict[str, list[np.ndarray]] = {}
        per_frame = np.zeros(horizon)  # the best sample's displacement at each frame, summed over windows
        for b in window_blocks(len(windows), 8 * samples[0].size):
            lively = own.denormalize(samples[b])  # (n, K, T, F) un-normalised features, float64
            pred = metric_vectors(lively, layout)
            if protocol.rigid_bones and layout.kind == "body3d":
                pred = rigid_vectors(pred, last[b])
            best = M.best_of_k_displacements(M.displacement(pred, gt[b]))  # once for ADE, FDE and ADE per frame
            per_frame += best["ade_per_frame"] * len(pred)
            block = _dlow_block(pred, gt, groups[b], best)
            if extended:
                block["s_mse"] = M.best_of_k_mse_per_window(pred, gt[b])
                if rec is not None:
                    block["r_mse"] = M.best_of_k_mse_per_window(to_metric(rec[b]), gt[b])
                if bandwidth is not None:
                    block["cll"] = M.parzen_log_likelihood(pred, gt[b], bandwidth=bandwidth)
            # how lively the samples are (all features, root included; before rigid_bones)
            block["velocity"], block["acceleration"] = M.liveliness_per_window(lively)
            for name, values in block.items():
                blocks.setdefault(name, []).append(values)
        per_window = {name: np.concatenate(values) for name, values in blocks.items()}
        moves = per_window.pop("velocity"), per_window.pop("acceleration")
        row = {k: float(v.mean()) for k, v in per_window.items()}
        if bandwidth is not None:
            row["parzen_bandwidth"] = bandwidth
        by_action = per_action_means(per_window, actions)
        pooled, per_action = liveliness_ratios(moves, true_moves, actions)
        row.update(pooled)
        for action, ratios in per_action.items():
            by_action[action].update(ratios)
        result.ade_per_frame[bundle.label] = [float(v) for v in per_frame / len(windows)]
        result.results[bundle.label] = {k: float(v) for k, v in row.items()}
        result.per_action[bundle.label] = by_action
        result.macro[bundle.label] = macro_average(by_action)
    return result


@dataclass(frozen=True)
class ForecastEvalSettings:
    """One ``evaluate`` run: the models, the data and the protocol.

    Attributes:
        models: checkpoint paths or shipped names (the first one's split and statistics pick the windows);
            ``mirror-periodic``, a rule with no weights, is scored in the first trained model's windows.
        data: BVH folder or motion file (face models: .csv / .npz captures), or several mocap folders joined into
            one corpus.
        samples, stride, split, seed, rigid_bones: as in :class:`EvalProtocol`.
        raw_futures: score the networks' futures as they come out (``EvalProtocol.continue_motion`` off).
        recorded_only: only the clips the checkpoint's recorded split names.
        extended: also S-MSE, R-MSE and the Parzen conditional log-likelihood (needs the val windows).
        json: write the results as JSON here (None: no file).
        plot: draw ADE per future frame into this PNG (None: no plot).
        character: DeepMimic motion files' character file.
    """

    models: tuple[str, ...]
    data: str | Path | tuple[str | Path, ...]
    samples: int = 50
    stride: int = 16
    split: str = "test"
    seed: int = 0
    rigid_bones: bool = False
    raw_futures: bool = False
    recorded_only: bool = False
    extended: bool = False
    json: str | Path | None = None
    plot: str | Path | None = None
    character: str | Path | None = None


@dataclass
class ForecastEvaluation:
    """What :func:`evaluate_models` measured: the results (protocol, pooled, macro and per-action tables), the
    number of windows, and the files written (None where not asked for)."""

    result: EvalResult
    windows: int
    json: Path | None
    plot: Path | None
    subjects: SubjectSplitTables | None = None


def _load_models(names: tuple[str, ...]) -> tuple[list[ModelBundle], list[str]]:
    """The trained models of ``names`` (InputError unless they share data settings and have distinct names) and
    the rules among the names."""
    rules = [name for name in names if name in RULES]
    learned = [name for name in names if name not in RULES]
    if not learned:
        raise InputError(f"{rules[0]} is a rule: name a trained model too, whose windows, statistics and split it "
                         "is scored on")
    models = [load_model(name) for name in learned]
    bundle = models[0]
    for other in models[1:]:  # the split rule aside (the first model's split, or the subject split, picks the clips)
        if (dataclasses.replace(other.data_config, held_out="corpus")
                != dataclasses.replace(bundle.data_config, held_out="corpus")):
            raise InputError(f"{other.label} was trained with other data settings than {bundle.label}: "
                             "compare models of one layout and window length", other.path)
    labels = [m.label for m in models]
    if len(set(labels)) != len(labels):
        raise InputError(f"two models share the name {labels!r}: give checkpoints with distinct file names")
    layout = bundle.data_config.feature_layout.kind
    if rules and layout != "body3d":
        raise InputError(f"{rules[0]} works on 3D body motion, not the {layout} layout of {bundle.label}")
    return models, rules


def evaluate_models(settings: ForecastEvalSettings) -> ForecastEvaluation:
    """Score ``settings.models`` and the three baselines on the same windows of ``settings.data`` and write the
    JSON and the plot asked for. InputError for models that cannot be compared, a plot that is not a .png, or no
    window long enough."""
    for target in (settings.json, settings.plot):
        if target is not None:
            Path(target).parent.mkdir(parents=True, exist_ok=True)
    if settings.plot is not None and not str(settings.plot).lower().endswith(".png"):
        raise InputError("--plot writes a .png file", settings.plot)
    models, rules = _load_models(tuple(settings.models))
    bundle = models[0]
    cfg = bundle.data_config
    data = settings.data if isinstance(settings.data, (str, Path)) or len(settings.data) > 1 else settings.data[0]
    train_actions: set[str] = set()
    if settings.split == "subjects":
        if cfg.feature_layout.kind != "body3d":
            raise InputError(f"--split subjects holds out body-motion performers, not the "
                             f"{cfg.feature_layout.kind} layout of {bundle.label}")
        dataset, windows, train_actions = subject_windows(data, cfg, models, stride=settings.stride,
                                                          character=settings.character)
    else:
        dataset = build_dataset(data, cfg, split=bundle.meta.split, stats=bundle.stats,
                                recorded_only=settings.recorded_only, character=settings.character)
        windows = dataset.windows(settings.split, stride=settings.stride)
    if len(windows) == 0:
        longest = max((c.num_frames for c in dataset.clips_of(settings.split)), default=0)
        raise InputError(f"no clip of the {settings.split} split is long enough: a window needs {cfg.length} "
                         f"frames at {cfg.fps:g} fps ({cfg.observed} observed + {cfg.future} future), the longest "
                         f"has {longest}", settings.data)
    bundles = models + [baseline_bundle(name, cfg, stats=bundle.stats) for name in tuple(rules) + BASELINES]
    protocol = EvalProtocol(samples=settings.samples, stride=settings.stride, split=settings.split,
                            seed=settings.seed, rigid_bones=settings.rigid_bones,
                            continue_motion=not settings.raw_futures)
    val = dataset.windows("val", stride=settings.stride) if settings.extended else None
    result = evaluate_bundles(bundles, windows, protocol=protocol, extended=settings.extended, val_windows=val)
    result.protocol["checkpoint"] = str(bundle.path)
    result.protocol["data"] = str(data) if isinstance(data, (str, Path)) else " + ".join(map(str, data))
    subjects = subject_split_tables(result, models, train_actions) if settings.split == "subjects" else None
    record = result.to_json() if subjects is None else {**result.to_json(), "subjects": subjects.json}
    json_out = write_json(settings.json, record) if settings.json is not None else None
    plot_out = None
    if settings.plot is not None:
        plot_out = plot_ade_per_frame(result.ade_per_frame, settings.plot, fps=cfg.fps,
                                      units=result.protocol["units"].split(" (")[0], best_of=settings.samples,
                                      title=f"{len(windows)} {settings.split} windows from "
                                            f"{len(result.protocol['clips'])} clips")
    return ForecastEvaluation(result=result, windows=len(windows), json=json_out, plot=plot_out, subjects=subjects)


def subject_windows(data, cfg, models: list[ModelBundle], *, stride: int, character: str | Path | None):
    """The subject split's test windows (labels ``"action @ family"``,
    :func:`~motion2video.evaluation.per_action.family_key`), its dataset and the actions its training clips perform.
    InputError when a model trained on a held-out clip."""
    bundle = models[0]
    dataset = build_dataset(data, dataclasses.replace(cfg, held_out="subjects"), stats=bundle.stats,
                            character=character)
    test = set(dataset.split.test)
    for model in models:
        if model.meta.split is not None:
            seen = test & (set(model.meta.split.train) | set(model.meta.split.val))
            if seen:
                raise InputError(f"it trained on {len(seen)} clip(s) the subject split holds out (e.g. "
                                 f"{sorted(seen)[0]}): score it with its own --split test", model.path)
    windows = dataset.windows("test", stride=stride)
    windows.labels = tuple(family_key(label, "bandai" if source_of(name) in BANDAI_SOURCES else "mocap")
                           for label, name in zip(windows.labels, windows.clip_names))
    train_actions = {c.label or "unlabelled" for c in dataset.clips_of("train")}
    return dataset, windows, train_actions


def trained_on_bandai(bundle: ModelBundle) -> bool:
    """Whether a model's recorded training clips include any Bandai-Namco clip (False for rules and baselines)."""
    split = bundle.meta.split
    return split is not None and any(source_of(n) in BANDAI_SOURCES for n in split.train)


@dataclass
class SubjectSplitTables:
    """The subject split's tables: ``rows`` (per action, unseen actions, macro, cross-dataset; each method's
    metrics with ADE / FDE over zero-velocity's as ``ade_zv`` / ``fde_zv``), the actions training covers, and the
    JSON-able record."""

    rows: dict[str, dict[str, float]]
    train_actions: list[str]
    json: dict


def subject_split_tables(result: EvalResult, models: list[ModelBundle], train_actions: set[str]) -> SubjectSplitTables:
    """Per action and macro over the actions the training clips perform, each unseen test action in its own row,
    and the cross-dataset row (the held-out Bandai performers), for every method of ``result``."""
    report = {m: subject_split_report(rows, train_actions) for m, rows in result.per_action.items()}
    bandai = {m.label: trained_on_bandai(m) for m in models}
    zv = report.get("zero-velocity")

    def with_ratio(row: dict, ref: dict | None) -> dict:
        if not row or ref is None:
            return dict(row)
        return {**row, "ade_zv": row["ade"] / ref["ade"], "fde_zv": row["fde"] / ref["fde"]}

    rows: dict[str, dict[str, float]] = {}
    for part in ("per_action", "unseen"):
        for action in next(iter(report.values()))[part]:
            for m, r in report.items():
                row = r[part][action]
                tag = "unseen action: " if part == "unseen" else ""
                rows[f"{tag}{action} ({row[COUNT_KEY]}) {m}"] = with_ratio(row, zv[part][action] if zv else None)
    for m, r in report.items():
        rows[f"macro over {len(r['per_action'])} actions {m}"] = with_ratio(r["macro"], zv["macro"] if zv else None)
    for m, r in report.items():
        if r["cross_dataset"] is not None:
            note = "" if m not in bandai else (" (trained with Bandai)" if bandai[m] else " (trained without Bandai)")
            rows[f"cross-dataset: Bandai held-out ({r['cross_dataset'][COUNT_KEY]}) {m}{note}"] = with_ratio(
                r["cross_dataset"], zv["cross_dataset"] if zv else None)
    record = {"report": report, "trained_on_bandai": bandai, "train_actions": sorted(train_actions)}
    return SubjectSplitTables(rows=rows, train_actions=sorted(train_actions), json=record)
