"""Training a motion model from the command's settings (the ``train`` command's work): the ``--config`` JSON
read and checked field by field against the model's, the data's and the training loop's dataclasses, the feature
layout found from the data, DLow's base checkpoint folded in, the dataset built, and
:func:`motion2video.models.training.train_model` run."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from safetensors import safe_open

from motion2video.core.errors import InputError
from motion2video.data.dataset import DatasetConfig, MotionDataset, build_dataset
from motion2video.models.base import MODEL_REGISTRY
from motion2video.models.checkpoint import read_meta, resolve_checkpoint  # importing it registers every model
from motion2video.models.mixture import NOT_TRAINED
from motion2video.models.training import TrainConfig, TrainResult, train_model

LAYOUTS = ("auto", "body3d", "body2d", "face")


@dataclass(frozen=True)
class MotionTrainingSettings:
    """One training run of a motion model.

    Attributes:
        model: registered model name (``mtvae-add``, ``dlow``, ...).
        data: folder of BVH files (with manifest.csv) or face captures, or one file; or several mocap folders
            joined into one corpus.
        output: the final checkpoint (``.safetensors``).
        config: a JSON object, inline or a file's path: ``{"model": .., "data": .., "train": ..}``.
        base: ``dlow`` only: the trained checkpoint (path or shipped name) DLow samples from.
        steps, seed: override the ``train`` section's (None: keep it).
        layout: feature layout; ``auto``: face for face captures, else body3d.
        resume: continue from the output's last periodic checkpoint.
        progress: show the progress bar.
        character: DeepMimic motion files' character file.
    """

    model: str
    data: str | Path | tuple[str | Path, ...]
    output: str | Path
    config: str | None = None
    base: str | None = None
    steps: int | None = None
    seed: int | None = None
    layout: str = "auto"
    resume: bool = False
    progress: bool = True
    character: str | Path | None = None


def parse_config(text: str | None) -> dict:
    """The --config JSON (inline or a file) as {"model": {}, "data": {}, "train": {}}."""
    if text is None:
        return {"model": {}, "data": {}, "train": {}}
    source = None
    if not text.lstrip().startswith("{"):
        source = Path(text)
        if not source.is_file():
            raise InputError("--config is neither a JSON object nor an existing file", text)
        text = source.read_text()
    try:
        cfg = json.loads(text)
    except json.JSONDecodeError as err:
        raise InputError(f"--config is not valid JSON ({err})", source) from None
    if not isinstance(cfg, dict):
        raise InputError("--config must be a JSON object", source)
    unknown = set(cfg) - {"model", "data", "train"}
    if unknown:
        raise InputError(f"--config has unknown section(s) {sorted(unknown)}; use model, data, train", source)
    out = {k: cfg.get(k, {}) for k in ("model", "data", "train")}
    for k, v in out.items():
        if not isinstance(v, dict):
            raise InputError(f"--config section {k!r} must be a JSON object", source)
    return out


def detect_layout(data: str | Path) -> str:
    """face when ``data`` is a face capture or a folder holding face captures but no BVH, else body3d."""
    path = Path(data)
    if path.is_file():
        return "face" if path.suffix.lower() == ".csv" else "body3d"
    if (path.is_dir() and not any(path.rglob("*.bvh")) and not any(path.rglob("*.bvh.xz"))
            and any(path.rglob("*.csv"))):
        return "face"
    return "body3d"


def _dataclass(cls, values: dict, section: str):
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = set(values) - fields
    if unknown:
        raise InputError(f"--config {section!r} has unknown field(s) {sorted(unknown)}; known: {sorted(fields)}")
    try:
        return cls(**values)
    except (TypeError, ValueError) as err:
        raise InputError(f"--config {section!r}: {err}") from None


def _dlow_base(base: str | None, cfg: dict) -> tuple[dict, dict]:
    """--model dlow: the config completed from the base checkpoint, and the base weights under ``base.``."""
    if base is None:
        raise InputError("--model dlow needs --base CHECKPOINT (the trained model to sample from)")
    path = resolve_checkpoint(base)
    meta = read_meta(path)
    if meta.kind != "stochastic" or meta.model == "dlow":
        raise InputError(f"--base must be a trained latent-variable model, not {meta.model!r}", path)
    if cfg["data"]:
        raise InputError("--model dlow reuses the base model's data settings; drop the 'data' section of --config")
    model = {**cfg["model"], "base_model": meta.model,
             "base_config": {k: v for k, v in meta.config.items() if k != "feature_dim"}}
    with safe_open(str(path), framework="pt") as f:
        state = {"base." + k: f.get_tensor(k) for k in f.keys()}
    data = {f.name: getattr(meta.data_config, f.name) for f in dataclasses.fields(meta.data_config)}
    return {**cfg, "model": model, "data": data, "base_meta": meta}, state


def dataset_line(dataset: MotionDataset) -> str:
    """One line on the data a run trains on: clips, frames, rate, split sizes, layout and features."""
    cfg = dataset.config
    return (f"data: {dataset.summary['clips']} clips, {dataset.summary['frames']} frames at {cfg.fps:g} fps; "
            f"train/val/test clips {len(dataset.split.train)}/{len(dataset.split.val)}/{len(dataset.split.test)}; "
            f"layout {cfg.layout} ({dataset.num_features} features)")


def train_motion_model(settings: MotionTrainingSettings, *,
                       note: Callable[[str], None] = print) -> TrainResult:
    """Check ``settings`` (InputError before any data is read), build the dataset, say what it holds through
    ``note`` and train; the checkpoint is written atomically at ``settings.output``."""
    name = settings.model
    if name not in MODEL_REGISTRY:
        raise InputError(f"unknown model {name!r}; known: {', '.join(sorted(MODEL_REGISTRY))}")
    if MODEL_REGISTRY[name].kind == "baseline":
        raise InputError(f"{name!r} is a baseline: it has no parameters to train")
    if name == "mixture":
        raise InputError(NOT_TRAINED)
    if not Path(settings.output).name.endswith(".safetensors"):
        raise InputError("the output must be a .safetensors file", settings.output)
    if settings.layout not in LAYOUTS:
        raise InputError(f"unknown layout {settings.layout!r}; choose one of {', '.join(LAYOUTS)}")
    cfg = parse_config(settings.config)
    init_state = None
    if name == "dlow":
        cfg, init_state = _dlow_base(settings.base, cfg)
    elif settings.base is not None:
        raise InputError("--base is only for --model dlow")
    _dataclass(MODEL_REGISTRY[name].config_cls, cfg["model"], "model")  # check before loading data
    data_values = dict(cfg["data"])
    if settings.layout != "auto":
        data_values["layout"] = settings.layout
    folders = [settings.data] if isinstance(settings.data, (str, Path)) else list(settings.data)
    data = folders[0] if len(folders) == 1 else folders
    data_values.setdefault("layout", detect_layout(folders[0]))
    data_config = _dataclass(DatasetConfig, data_values, "data")
    train_values = dict(cfg["train"])
    if settings.steps is not None:
        train_values["steps"] = settings.steps
    if settings.seed is not None:
        train_values["seed"] = settings.seed
    train_config = _dataclass(TrainConfig, train_values, "train")
    base_meta = cfg.get("base_meta")
    if base_meta is not None:  # DLow: the base model's split and statistics, so its decoder sees its own units
        dataset = build_dataset(data, data_config, split=base_meta.split, stats=base_meta.stats,
                                character=settings.character)
    else:
        dataset = build_dataset(data, data_config, character=settings.character)
    note(dataset_line(dataset))
    return train_model(model_name=name, model_config=cfg["model"], dataset=dataset, config=train_config,
                       out=settings.output, resume=settings.resume, progress=settings.progress,
                       init_state=init_state)
