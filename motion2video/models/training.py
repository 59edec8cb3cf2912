"""One training loop for every motion model.

AdamW, gradient-norm clipping, a cosine learning-rate decay, seeded batches, a tqdm progress bar, a
validation loss, periodic checkpoints and ``resume``; the final checkpoint carries the model config,
normalisation statistics, the split and a training record (see :mod:`motion2video.models.checkpoint`).

Models with extra training protocol (documented in :mod:`motion2video.models.behavior`):

- ``parameter_groups() -> {"main": [...], "auxiliary": [...]}``: one optimiser per group; each step runs
  ``loss(...).total.backward()`` for the main group, then ``auxiliary_loss(obs, future).total.backward()``
  for the auxiliary group (alternating optimisation);
- ``fit_flow(latents, steps=..., seed=...)`` with ``posterior_latents(obs, future)``: after the main loop
  the flow is fitted to posterior latents of training windows.

Determinism: batch ``step`` is drawn from ``numpy.random.default_rng([seed, step])`` and the torch RNG is
re-seeded with ``(seed, step)`` before each step, so a resumed run draws the same batches and noise as an
uninterrupted one.

Files: ``-o out.safetensors`` is the final checkpoint; every ``checkpoint_every`` steps (and at the end)
``out.last.safetensors`` (model) and ``out.last.optim.safetensors`` (optimiser state, step, history) are
written beside it; ``resume`` continues from them.
"""

from __future__ import annotations

import dataclasses
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from safetensors import safe_open
from safetensors.torch import save_file
from tqdm import tqdm

from motion2video import __version__
from motion2video.core.atomic import atomic_output
from motion2video.models.checkpoint import CheckpointMeta, config_dict, read_meta, save_checkpoint
from motion2video.core.skeletons import SKELETON_VERSION
from motion2video.data.dataset import MotionDataset
from motion2video.core.errors import InputError
from motion2video.models.base import MODEL_REGISTRY, build_model
from motion2video.core.schedule import learning_rate

SUFFIX = ".safetensors"


@dataclass(frozen=True)
class TrainConfig:
    """Optimisation settings.

    Attributes:
        steps: optimisation steps (batches).
        batch_size: windows per batch.
        lr: peak learning rate (AdamW); decays with a cosine to ``lr * final_lr_fraction``.
        final_lr_fraction: learning rate at the last step relative to ``lr``.
        warmup_steps: linear warm-up steps.
        weight_decay: AdamW weight decay.
        grad_clip: maximum global gradient norm (0 disables clipping).
        checkpoint_every: steps between periodic checkpoints.
        val_every: steps between validation losses (0: only at the end).
        val_windows: at most this many validation windows (evenly spaced) per validation.
        flow_steps: steps of the post-training flow fit (models with ``fit_flow``).
        flow_windows: training windows whose posterior latents the flow is fitted to.
        seed: seeds batches, augmentation, initialisation and the model's noise.
        augment: use the dataset's augmentation (mirroring, rotation, speed).
        max_minutes: a wall-time budget (0: none). The learning-rate schedule then follows whichever of
            steps and time is further along (:func:`schedule_step`), and the run ends, annealed, when the budget
            is spent or ``steps`` are done; the checkpoint records the steps actually done. On a shared
            machine this keeps a run inside its budget, at the price of a step count that depends on the load.
    """

    steps: int = 3000
    batch_size: int = 64
    lr: float = 1e-3
    final_lr_fraction: float = 0.05
    warmup_steps: int = 100
    weight_decay: float = 1e-4
    grad_clip: float = 1.0
    checkpoint_every: int = 500
    val_every: int = 500
    val_windows: int = 512
    flow_steps: int = 1000
    flow_windows: int = 4096
    seed: int = 0
    augment: bool = True
    max_minutes: float = 0.0

    def __post_init__(self) -> None:
        if self.max_minutes < 0:
            raise ValueError(f"max_minutes must be >= 0, got {self.max_minutes}")
        if self.steps < 1 or self.batch_size < 1:
            raise ValueError(f"steps and batch_size must be >= 1, got {self.steps}, {self.batch_size}")
        if self.checkpoint_every < 1:
            raise ValueError(f"checkpoint_every must be >= 1, got {self.checkpoint_every}")


@dataclass
class TrainResult:
    """What a training run produced.

    Attributes:
        path: the final checkpoint.
        steps: total steps done (including those before a resume).
        wall_time_s: seconds spent in this process (plus earlier runs when resumed).
        train_loss: mean total loss over the last 50 steps.
        val_loss: the last validation loss (None without validation windows).
        history: per-validation records ``{"step", "train_loss", "val_loss", ...}``.
    """

    path: Path
    steps: int
    wall_time_s: float
    train_loss: float
    val_loss: float | None
    history: list[dict] = field(default_factory=list)


def last_paths(out: str | Path) -> tuple[Path, Path]:
    """The periodic checkpoint and its optimiser sidecar for final checkpoint ``out``."""
    out = Path(out)
    stem = out.name[: -len(SUFFIX)] if out.name.endswith(SUFFIX) else out.name
    return out.with_name(stem + ".last" + SUFFIX), out.with_name(stem + ".last.optim" + SUFFIX)


def make_optimizers(model: torch.nn.Module, config: TrainConfig) -> dict[str, torch.optim.Optimizer]:
    """One AdamW per parameter group (``{"main": all parameters}`` for models without groups)."""
    groups = model.parameter_groups() if hasattr(model, "parameter_groups") else {"main": list(model.parameters())}
    if not any(len(g) for g in groups.values()):
        raise InputError(f"model {type(model).__name__} has no parameters to train")
    return {name: torch.optim.AdamW(params, lr=config.lr, weight_decay=config.weight_decay)
            for name, params in groups.items() if params}


def _seed_step(seed: int, step: int) -> np.random.Generator:
    torch.manual_seed((seed * 1_000_003 + step) % (2 ** 63))
    return np.random.default_rng([seed, step])


def schedule_step(step: int, config: TrainConfig, elapsed_s: float) -> int:
    """The step the learning-rate schedule is at: ``step``, or with a time budget the share of
    ``config.max_minutes`` spent times ``config.steps`` when that is further along (at most ``steps - 1``)."""
    if config.max_minutes <= 0:
        return step
    by_time = int(elapsed_s / (60.0 * config.max_minutes) * config.steps)
    return min(max(step, by_time), config.steps - 1)


def _to_tensor(x: np.ndarray, device: torch.device) -> torch.Tensor:
    return torch.from_numpy(np.ascontiguousarray(x, dtype=np.float32)).to(device)


def validation_loss(model: torch.nn.Module, dataset: MotionDataset, *, step: int, max_windows: int,
                    batch_size: int = 256, seed: int = 0) -> dict[str, float] | None:
    """Mean loss terms over (at most ``max_windows`` evenly spaced) validation windows, eval mode, no
    gradient; None when the validation split has no window."""
    windows = dataset.windows("val")
    if len(windows) == 0:
        return None
    idx = np.unique(np.linspace(0, len(windows) - 1, min(max_windows, len(windows))).round().astype(int))
    device = next(model.parameters()).device
    was_training = model.training
    model.eval()
    torch.manual_seed(seed)
    sums: dict[str, float] = {}
    with torch.no_grad():
        for i in range(0, len(idx), batch_size):
            batch = windows.features[idx[i:i + batch_size]]
            obs = _to_tensor(batch[:, : dataset.config.observed], device)
            fut = _to_tensor(batch[:, dataset.config.observed:], device)
            out = model.loss(obs, fut, step=step)
            terms = {"total": float(out.total), **out.terms}
            for k, v in terms.items():
                sums[k] = sums.get(k, 0.0) + v * len(batch)
    model.train(was_training)
    return {k: v / len(idx) for k, v in sums.items()}


def _save_sidecar(path: Path, optimizers: dict[str, torch.optim.Optimizer], record: dict,
                  model: torch.nn.Module | None = None) -> None:
    """Optimiser states as tensors ``<group>/<param index>/<key>``, the model's weights as ``model/<name>``;
    param groups and the record as JSON. One file, written atomically, so a run killed at any moment resumes
    from weights and optimiser state of the same step."""
    tensors, groups = {}, {}
    if model is not None:
        for key, value in model.state_dict().items():
            tensors[f"model/{key}"] = value.detach().contiguous().cpu()
    for name, opt in optimizers.items():
        sd = opt.state_dict()
        for pid, state in sd["state"].items():
            for key, value in state.items():
                tensors[f"{name}/{pid}/{key}"] = torch.as_tensor(value).detach().contiguous().cpu()
        groups[name] = sd["param_groups"]
    with atomic_output(path) as tmp:
        save_file(tensors, str(tmp), metadata={"format": "motion2video-optim", "param_groups": json.dumps(groups),
                                               "record": json.dumps(record)})


def _load_sidecar(path: Path, optimizers: dict[str, torch.optim.Optimizer]) -> dict:
    with safe_open(str(path), framework="pt") as f:
        meta = f.metadata() or {}
        if meta.get("format") != "motion2video-optim":
            raise InputError("not an optimiser-state file", path)
        groups = json.loads(meta["param_groups"])
        states: dict[str, dict[int, dict]] = {name: {} for name in optimizers}
        for key in f.keys():
            if key.startswith("model/"):
                continue
            name, pid, item = key.split("/", 2)
            states.setdefault(name, {}).setdefault(int(pid), {})[item] = f.get_tensor(key)
    if set(groups) != set(optimizers):
        raise InputError(f"optimiser groups differ: saved {sorted(groups)}, model has {sorted(optimizers)}", path)
    for name, opt in optimizers.items():
        opt.load_state_dict({"state": states[name], "param_groups": groups[name]})
    return json.loads(meta["record"])


def train_model(
    *,
    model_name: str,
    model_config: dict,
    dataset: MotionDataset,
    config: TrainConfig,
    out: str | Path,
    resume: bool = False,
    progress: bool = True,
    device: str | torch.device = "cpu",
    init_state: dict[str, torch.Tensor] | None = None,
) -> TrainResult:
    """Train ``model_name`` on ``dataset`` and write the final checkpoint to ``out``.

    Args:
        model_name: a registered learned model (baselines have nothing to train).
        model_config: fields of its config dataclass (``feature_dim`` is set from the dataset).
        dataset: the training data (split, statistics, augmentation).
        config: optimisation settings.
        out: final checkpoint path (``.safetensors``).
        resume: continue from ``out.last.safetensors`` + ``out.last.optim.safetensors``.
        progress: show a tqdm progress bar.
        init_state: weights loaded before training (e.g. the frozen ``base.`` model of ``dlow``); every
            key must exist in the model.
    Returns:
        A :class:`TrainResult`.
    """
    entry = MODEL_REGISTRY.get(model_name)
    if entry is None:
        raise InputError(f"unknown model {model_name!r}; known: {', '.join(sorted(MODEL_REGISTRY))}")
    if entry.kind == "baseline":
        raise InputError(f"{model_name!r} is a baseline: it has no parameters to train")
    out = Path(out)
    last, sidecar = last_paths(out)
    full_config = {**model_config, "feature_dim": dataset.num_features}
    fields = {f.name for f in dataclasses.fields(entry.config_cls)}
    if "feature_scale" in fields and not full_config.get("feature_scale"):
        # models that measure their loss in data units (mixer-dct) get the training set's feature scales
        full_config["feature_scale"] = [float(v) for v in dataset.stats.std]
    torch.manual_seed(config.seed)
    try:
        model = build_model(model_name, full_config)
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"bad config for model {model_name!r}: {err}") from None
    if init_state is not None:
        unexpected = model.load_state_dict(init_state, strict=False).unexpected_keys
        if unexpected:
            raise InputError(f"initial weights do not fit model {model_name!r}: unexpected {unexpected[:3]}")
    model.to(device)
    optimizers = make_optimizers(model, config)
    start_step, history, wall_before = 0, [], 0.0
    if resume:
        start_step, history, wall_before = _resume(model, optimizers, last=last, sidecar=sidecar,
                                                   model_name=model_name, dataset=dataset)
    obs_len = dataset.config.observed
    recent: list[float] = []
    t0 = time.perf_counter()
    val = history[-1].get("val_loss") if history else None

    def record_meta(step: int) -> CheckpointMeta:
        return CheckpointMeta(
            model=model_name, kind=entry.kind, config=config_dict(model.config), data_config=dataset.config,
            stats=dataset.stats, split=dataset.split, skeleton="h36m-17" if dataset.layout.is_body else None,
            version=__version__, data_summary=dataset.describe(),
            training={"steps": step, "seed": config.seed, "config": dataclasses.asdict(config),
                      "wall_time_s": round(wall_before + time.perf_counter() - t0, 2),
                      "val_loss": val, "train_loss": float(np.mean(recent)) if recent else None,
                      "torch": torch.__version__},
            skeleton_version=SKELETON_VERSION if dataset.layout.is_body else None,
        )

    def periodic(step: int) -> None:
        save_checkpoint(last, model=model, meta=record_meta(step))
        _save_sidecar(sidecar, optimizers, {"step": step, "history": history,
                                            "wall_time_s": wall_before + time.perf_counter() - t0}, model)

    model.train()
    bar = tqdm(range(start_step, config.steps), initial=start_step, total=config.steps, disable=not progress,
               desc=f"train {model_name}", unit="step", dynamic_ncols=True)
    final_step = config.steps
    for step in bar:
        elapsed = wall_before + time.perf_counter() - t0
        if config.max_minutes > 0 and step > start_step and elapsed >= 60.0 * config.max_minutes:
            final_step = step  # the time budget is spent: end here, annealed by the time-based schedule
            break
        rng = _seed_step(config.seed, step)
        batch = dataset.sample_batch(rng, config.batch_size, augment=config.augment)  # (B, L, F)
        obs = _to_tensor(batch[:, :obs_len], device)
        fut = _to_tensor(batch[:, obs_len:], device)
        lr = learning_rate(schedule_step(step, config, elapsed), config)
        for opt in optimizers.values():
            for group in opt.param_groups:
                group["lr"] = lr
        main = optimizers["main"]
        main.zero_grad(set_to_none=True)
        out_loss = model.loss(obs, fut, step=step)
        if not torch.isfinite(out_loss.total):
            raise RuntimeError(f"{model_name}: the loss became {float(out_loss.total)} at step {step}")
        out_loss.total.backward()
        if config.grad_clip > 0:
            torch.nn.utils.clip_grad_norm_([p for g in main.param_groups for p in g["params"]], config.grad_clip)
        main.step()
        if "auxiliary" in optimizers:
            aux = optimizers["auxiliary"]
            aux.zero_grad(set_to_none=True)
            model.auxiliary_loss(obs, fut).total.backward()
            if config.grad_clip > 0:
                torch.nn.utils.clip_grad_norm_([p for g in aux.param_groups for p in g["params"]], config.grad_clip)
            aux.step()
        recent = (recent + [float(out_loss.total.detach())])[-50:]
        done = step + 1
        if progress and (done % 10 == 0 or done == config.steps):
            bar.set_postfix(loss=f"{np.mean(recent):.4g}", lr=f"{lr:.2g}")
        if config.val_every and done % config.val_every == 0 and done < config.steps:
            vl = validation_loss(model, dataset, step=done, max_windows=config.val_windows, seed=config.seed)
            val = None if vl is None else vl["total"]
            history.append({"step": done, "train_loss": float(np.mean(recent)), "val_loss": val,
                            "val_terms": vl})
            if not progress:
                print(f"step {done}/{config.steps}: train loss {np.mean(recent):.4g}, val loss "
                      f"{'n/a' if val is None else f'{val:.4g}'}, {time.perf_counter() - t0:.0f} s", flush=True)
        if done % config.checkpoint_every == 0 and done < config.steps:
            periodic(done)
    bar.close()
    if final_step < config.steps:
        print(f"time budget of {config.max_minutes:g} min spent after {final_step} of {config.steps} steps", flush=True)
    if start_step < final_step or not history or history[-1]["step"] != final_step:
        vl = validation_loss(model, dataset, step=final_step, max_windows=config.val_windows, seed=config.seed)
        val = None if vl is None else vl["total"]
        history.append({"step": final_step, "train_loss": float(np.mean(recent)) if recent else None,
                        "val_loss": val, "val_terms": vl})
    if hasattr(model, "fit_flow") and hasattr(model, "posterior_latents"):
        _fit_flow(model, dataset, config, device=device)
    periodic(final_step)
    path = save_checkpoint(out, model=model, meta=record_meta(final_step))
    return TrainResult(path=path, steps=final_step, wall_time_s=wall_before + time.perf_counter() - t0,
                       train_loss=float(np.mean(recent)) if recent else float("nan"), val_loss=val,
                       history=history)


def _fit_flow(model: torch.nn.Module, dataset: MotionDataset, config: TrainConfig, *, device) -> None:
    """Fit a model's sampling flow to posterior latents of ``config.flow_windows`` training windows."""
    rng = np.random.default_rng([config.seed, config.steps, 1])
    obs_len = dataset.config.observed
    model.eval()
    latents = []
    gen = torch.Generator().manual_seed(config.seed)
    remaining = config.flow_windows
    while remaining > 0:
        n = min(remaining, 512)
        batch = dataset.sample_batch(rng, n, augment=config.augment)
        latents.append(model.posterior_latents(_to_tensor(batch[:, :obs_len], device),
                                               _to_tensor(batch[:, obs_len:], device), generator=gen))
        remaining -= n
    model.fit_flow(torch.cat(latents), steps=config.flow_steps, seed=config.seed)
    model.train()


def _resume(model, optimizers, *, last: Path, sidecar: Path, model_name: str, dataset: MotionDataset
            ) -> tuple[int, list[dict], float]:
    """Load the periodic checkpoint and optimiser state; check they belong to this run."""
    if not last.is_file() or not sidecar.is_file():
        raise InputError(f"nothing to resume: {last.name} and {last.name[:-len(SUFFIX)]}.optim{SUFFIX} are "
                         "written by an earlier run every checkpoint_every steps", last)
    meta = read_meta(last)
    if meta.model != model_name:
        raise InputError(f"cannot resume: the periodic checkpoint is a {meta.model!r} model, not {model_name!r}", last)
    if meta.config != config_dict(model.config):
        raise InputError("cannot resume: the model config differs from the periodic checkpoint's", last)
    if meta.data_config != dataset.config or meta.split != dataset.split:
        raise InputError("cannot resume: the data config or split differs from the periodic checkpoint's", last)
    with safe_open(str(sidecar), framework="pt") as f:  # the weights saved with the optimiser state
        state = {k[len("model/"):]: f.get_tensor(k) for k in f.keys() if k.startswith("model/")}
    if not state:  # a sidecar of an older version: the periodic checkpoint's weights
        with safe_open(str(last), framework="pt") as f:
            state = {k: f.get_tensor(k) for k in f.keys()}
    model.load_state_dict(state, strict=True)
    record = _load_sidecar(sidecar, optimizers)
    return int(record["step"]), list(record["history"]), float(record["wall_time_s"])
