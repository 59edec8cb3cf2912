"""`motion2video train`: train a motion model on a folder of BVH files (or face captures)."""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from motion2video.commands.common import CHARACTER_HELP, add_command, add_threads_argument, check_at_least, set_threads
from motion2video.core.errors import InputError

HELP = "train a motion model (pred-lstm, cvae, mtvae-concat, mtvae-add, lcpvae, behavior)"

DESCRIPTION = """\
Train a stochastic motion model on real motion capture. Writes a safetensors checkpoint with the model config,
normalisation statistics and data split in its metadata; periodic checkpoints (OUT.last.safetensors +
OUT.last.optim.safetensors) make the run resumable.
"""

EXAMPLES = """\
examples:
  motion2video train --model mtvae-add --data ../shared/data/mocap -o runs/mtvae-add.safetensors --steps 3000
  motion2video train --model cvae --data ../shared/data/mocap -o runs/cvae.safetensors --resume
  motion2video train --model mtvae-add --data ../shared/data/mocap --layout body2d -o runs/mtvae-add-2d.safetensors
  motion2video train --model mtvae-add --data ../shared/data/face -o runs/mtvae-add-face.safetensors
  motion2video train --model lcpvae --data ../shared/data/mocap -o runs/lcp.safetensors \\
      --config '{"model": {"hidden_dim": 128}, "data": {"observed": 16, "future": 48}, "train": {"lr": 5e-4}}'

--config takes a JSON object (inline or a file path) with up to three sections: "model" (fields of the
model's config dataclass), "data" (DatasetConfig: observed, future, stride, mirror, speed, split_seed, ...)
and "train" (TrainConfig: batch_size, lr, weight_decay, grad_clip, checkpoint_every, val_every, ...).
--steps and --seed override the "train" section.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "train", run, help=HELP, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--model", required=True, help="registered model name, e.g. mtvae-add")
    p.add_argument("--data", required=True, action="append",
                   help="folder of BVH files (with manifest.csv), or face captures; repeat to join mocap folders into "
                   "one corpus (e.g. --data ../shared/data/mocap --data ../shared/data/bandai)")
    p.add_argument("--character", metavar="FILE", default=None, help=CHARACTER_HELP)
    p.add_argument("-o", "--output", required=True, help="final checkpoint (.safetensors)")
    p.add_argument("--base", default=None,
                   help="--model dlow only: the trained checkpoint (path or shipped name) DLow samples from; its "
                   "data settings, statistics and split are reused")
    p.add_argument("--config", default=None, help="JSON object or JSON file: {\"model\": .., \"data\": .., \"train\": ..}")
    p.add_argument("--steps", type=int, default=None, help="optimisation steps (default 3000)")
    p.add_argument("--seed", type=int, default=None, help="random seed (default 0)")
    p.add_argument("--layout", choices=("auto", "body3d", "body2d", "face"), default="auto",
                   help="feature layout; auto: face for a folder of .csv face captures, else body3d")
    p.add_argument("--resume", action="store_true", help="continue from OUTPUT's last periodic checkpoint")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_threads_argument(p)


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


def detect_layout(data: str) -> str:
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
    import dataclasses

    from safetensors import safe_open

    from motion2video.models.checkpoint import read_meta, resolve_checkpoint

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


def run(args: argparse.Namespace) -> int:
    import motion2video.models.checkpoint  # noqa: F401  (registers every model)
    from motion2video.data.dataset import DatasetConfig, build_dataset
    from motion2video.models.base import MODEL_REGISTRY
    from motion2video.models.training import TrainConfig, train_model

    set_threads(args.threads)
    if args.model not in MODEL_REGISTRY:
        raise InputError(f"unknown model {args.model!r}; known: {', '.join(sorted(MODEL_REGISTRY))}")
    if MODEL_REGISTRY[args.model].kind == "baseline":
        raise InputError(f"{args.model!r} is a baseline: it has no parameters to train")
    if args.model == "mixture":
        from motion2video.models.mixture import NOT_TRAINED

        raise InputError(NOT_TRAINED)
    if not Path(args.output).name.endswith(".safetensors"):
        raise InputError("the output must be a .safetensors file", args.output)
    if args.steps is not None:
        check_at_least("--steps", args.steps)
    cfg = parse_config(args.config)
    init_state = None
    if args.model == "dlow":
        cfg, init_state = _dlow_base(args.base, cfg)
    elif args.base is not None:
        raise InputError("--base is only for --model dlow")
    _dataclass(MODEL_REGISTRY[args.model].config_cls, cfg["model"], "model")  # check before loading data
    data_values = dict(cfg["data"])
    if args.layout != "auto":
        data_values["layout"] = args.layout
    data_values.setdefault("layout", detect_layout(args.data[0]))
    data = args.data[0] if len(args.data) == 1 else args.data
    data_config = _dataclass(DatasetConfig, data_values, "data")
    train_values = dict(cfg["train"])
    if args.steps is not None:
        train_values["steps"] = args.steps
    if args.seed is not None:
        train_values["seed"] = args.seed
    train_config = _dataclass(TrainConfig, train_values, "train")
    base_meta = cfg.get("base_meta")
    if base_meta is not None:  # DLow: the base model's split and statistics, so its decoder sees its own units
        dataset = build_dataset(data, data_config, split=base_meta.split, stats=base_meta.stats,
                                character=args.character)
    else:
        dataset = build_dataset(data, data_config, character=args.character)
    print(f"data: {dataset.summary['clips']} clips, {dataset.summary['frames']} frames at {data_config.fps:g} fps; "
          f"train/val/test clips {len(dataset.split.train)}/{len(dataset.split.val)}/{len(dataset.split.test)}; "
          f"layout {data_config.layout} ({dataset.num_features} features)")
    result = train_model(model_name=args.model, model_config=cfg["model"], dataset=dataset, config=train_config,
                         out=args.output, resume=args.resume, progress=not args.no_progress, init_state=init_state)
    val = "n/a" if result.val_loss is None else f"{result.val_loss:.4g}"
    print(f"wrote {result.path} ({result.steps} steps, {result.wall_time_s:.1f} s, "
          f"train loss {result.train_loss:.4g}, val loss {val})")
    return 0
