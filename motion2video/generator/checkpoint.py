"""Frame-generator checkpoints: safetensors weights with the config and a training summary in the metadata.

A checkpoint ``NAME.safetensors`` holds only what inference needs (weights + metadata, no pickle). Training
writes a second file beside it, ``NAME.state.safetensors``, with the optimiser (and discriminator) state so a
run can resume; it is never shipped.

Metadata keys (all strings): ``format`` = ``"motion2video-frames"``, ``kind`` (``"analogy"``: the feature-analogy
:class:`FrameGenerator`; ``"warp"``: the warping :class:`~motion2video.generator.warp.WarpGenerator`; ``"mesh"``: the mesh-correspondence
:class:`~motion2video.generator.mesh_warp.MeshWarpGenerator`; absent in
older checkpoints, which are analogy models), ``config`` (the kind's config as JSON), ``version`` (package version), ``step`` (training steps done), ``train`` (JSON summary: training
config, data summary, wall time, ...).
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from pathlib import Path

import torch
from safetensors import SafetensorError, safe_open
from safetensors.torch import save_file

from motion2video import __version__
from motion2video.core.atomic import atomic_output
from motion2video.core.errors import CHECKPOINT_FORMAT_VERSION, check_format_version
from motion2video.core.errors import InputError
from motion2video.core.skeletons import SKELETON_VERSION, check_skeleton_version
from motion2video.data.licences import licence_note, model_licences
from motion2video.generator.mesh_warp import MeshWarpConfig, MeshWarpGenerator
from motion2video.generator.model import FrameGenerator, FrameGeneratorConfig
from motion2video.generator.warp import WarpGenerator, WarpGeneratorConfig

FORMAT = "motion2video-frames"
WEIGHTS_DIR = Path(__file__).resolve().parents[1] / "weights"
SUFFIX = ".safetensors"
MODEL_KINDS = {"analogy": (FrameGenerator, FrameGeneratorConfig), "warp": (WarpGenerator, WarpGeneratorConfig),
               "mesh": (MeshWarpGenerator, MeshWarpConfig)}


def model_kind(model: torch.nn.Module) -> str:
    """``"mesh"`` for a MeshWarpGenerator, ``"warp"`` for a WarpGenerator, ``"analogy"`` for a FrameGenerator."""
    if isinstance(model, MeshWarpGenerator):
        return "mesh"
    return "warp" if isinstance(model, WarpGenerator) else "analogy"


def build_model(kind: str, config) -> torch.nn.Module:
    """A fresh generator of ``kind`` (see :data:`MODEL_KINDS`) with ``config`` (its config dataclass)."""
    if kind not in MODEL_KINDS:
        raise ValueError(f"unknown model kind {kind!r}; known: {', '.join(MODEL_KINDS)}")
    return MODEL_KINDS[kind][0](config)


@dataclass
class LoadedFrameModel:
    """A rebuilt generator (eval mode) and what its checkpoint says about itself."""

    model: FrameGenerator | WarpGenerator
    path: Path
    step: int
    train: dict = field(default_factory=dict)

    @property
    def config(self) -> FrameGeneratorConfig | WarpGeneratorConfig:
        return self.model.config

    @property
    def kind(self) -> str:
        return model_kind(self.model)


def state_path(path: str | Path) -> Path:
    """The resume-state file that goes with checkpoint ``path``."""
    path = Path(path)
    stem = path.name[: -len(SUFFIX)] if path.name.endswith(SUFFIX) else path.name
    return path.with_name(stem + ".state" + SUFFIX)


def _atomic_save(tensors: dict[str, torch.Tensor], path: Path, metadata: dict[str, str]) -> None:
    with atomic_output(path) as tmp:
        save_file({k: v.detach().contiguous().cpu() for k, v in tensors.items()}, str(tmp), metadata=metadata)


def save_frame_model(model: FrameGenerator | WarpGenerator, path: str | Path, *, step: int, train: dict | None = None) -> Path:
    """Write the generator's weights and metadata to ``path`` (atomically: tmp file + rename)."""
    path = Path(path)
    metadata = {
        "format": FORMAT,
        "format_version": str(CHECKPOINT_FORMAT_VERSION),
        "kind": model_kind(model),
        "config": model.config.to_json(),
        "version": __version__,
        "step": str(int(step)),
        "train": json.dumps(train or {}, sort_keys=True),
    }
    if model.config.domain == "body":  # its control points are canonical H36M-17 joints
        metadata["skeleton_version"] = str(SKELETON_VERSION)
    _atomic_save(dict(model.state_dict()), path, metadata)
    return path


def resolve_model_path(path_or_name: str | Path) -> Path:
    """A checkpoint path, or a shipped name (``frames-body-128``) looked up in ``motion2video/weights``."""
    path = Path(path_or_name)
    if path.is_file():
        return path
    name = str(path_or_name)
    shipped = WEIGHTS_DIR / (name if name.endswith(SUFFIX) else name + SUFFIX)
    if shipped.is_file():
        return shipped
    known = sorted(p.name[: -len(SUFFIX)] for p in WEIGHTS_DIR.glob("frames-*" + SUFFIX)
                   if not p.name.endswith(".state" + SUFFIX))
    hint = f"shipped frame models: {', '.join(known)}" if known else "no frame models are shipped yet"
    raise InputError(f"no such checkpoint file or shipped frame model ({hint})", name)


def load_frame_model(path_or_name: str | Path, *, any_skeleton: bool = False) -> LoadedFrameModel:
    """Rebuild a generator from a checkpoint file or shipped name; raises InputError for a bad file.

    A body generator trained on another canonical skeleton definition (its control points, see
    :func:`motion2video.core.skeletons.check_skeleton_version`) is refused unless ``any_skeleton`` (fine-tuning
    it on the new joints with ``train-frames --init-from``).
    """
    path = resolve_model_path(path_or_name)
    try:
        with safe_open(str(path), framework="pt") as f:
            metadata = f.metadata() or {}
            tensors = {k: f.get_tensor(k) for k in f.keys()}
    except (OSError, SafetensorError) as err:
        raise InputError(f"cannot read the checkpoint ({type(err).__name__}: {err})", path) from None
    if metadata.get("format") != FORMAT:
        raise InputError(f"not a frame-generator checkpoint (format {metadata.get('format')!r})", path)
    check_format_version(metadata, path)
    kind = metadata.get("kind", "analogy")
    if kind not in MODEL_KINDS:
        raise InputError(f"unknown frame-model kind {kind!r} (known: {', '.join(MODEL_KINDS)})", path)
    model_cls, config_cls = MODEL_KINDS[kind]
    try:
        config = config_cls.from_dict(json.loads(metadata["config"]))
    except (KeyError, ValueError, TypeError, AttributeError) as err:
        raise InputError(f"damaged checkpoint metadata: bad frame-model config ({type(err).__name__}: {err})",
                         path) from None
    try:
        model = model_cls(config)
    except (ValueError, TypeError, RuntimeError) as err:
        raise InputError(f"damaged checkpoint metadata: cannot build the {kind} model ({err})", path) from None
    if config.domain == "body" and not any_skeleton:
        try:
            version = int(metadata["skeleton_version"]) if "skeleton_version" in metadata else None
        except ValueError:
            raise InputError("damaged checkpoint metadata: bad skeleton_version", path) from None
        check_skeleton_version("h36m-17", version, path)
    missing, unexpected = model.load_state_dict(tensors, strict=False)
    if missing or unexpected:
        raise InputError(f"checkpoint weights do not match its config (missing {len(missing)}, "
                         f"unexpected {len(unexpected)})", path)
    model.eval()
    try:
        step, train = int(metadata.get("step", "0")), json.loads(metadata.get("train", "{}"))
    except (TypeError, ValueError) as err:
        raise InputError(f"damaged checkpoint metadata (step / train: {err})", path) from None
    stem = path.name[: -len(".safetensors")] if path.name.endswith(".safetensors") else path.name
    note = licence_note(stem, model_licences(stem, train.get("licences")))
    if note is not None:
        print(f"motion2video: note: {note}", file=sys.stderr)
    return LoadedFrameModel(model=model, path=path, step=step, train=train)


def save_train_state(path: str | Path, *, optimizer: torch.optim.Optimizer, step: int,
                     discriminator: torch.nn.Module | None = None,
                     disc_optimizer: torch.optim.Optimizer | None = None, extra: dict | None = None,
                     model: torch.nn.Module | None = None) -> Path:
    """Write the resume state for checkpoint ``path`` to :func:`state_path` (optimiser moments, step, and the
    generator's weights as ``gen.<name>``: one atomic file, so a run killed between writing the checkpoint and
    its state still resumes from weights and optimiser state of the same step)."""
    tensors: dict[str, torch.Tensor] = {}
    if model is not None:
        tensors.update({f"gen.{k}": v.detach().contiguous() for k, v in model.state_dict().items()})
    meta = {"format": FORMAT + "-state", "step": str(int(step)), "extra": json.dumps(extra or {})}
    groups = [("opt", optimizer)]
    if discriminator is not None:
        tensors.update({f"disc.{k}": v for k, v in discriminator.state_dict().items()})
    if disc_optimizer is not None:
        groups.append(("dopt", disc_optimizer))
    for prefix, opt in groups:
        sd = opt.state_dict()
        meta[f"{prefix}.param_groups"] = json.dumps(sd["param_groups"])
        for idx, st in sd["state"].items():
            for key, value in st.items():
                t = value if torch.is_tensor(value) else torch.tensor(value)
                tensors[f"{prefix}.state.{idx}.{key}"] = t
    out = state_path(path)
    _atomic_save(tensors, out, meta)
    return out


def load_train_state(path: str | Path, *, optimizer: torch.optim.Optimizer,
                     discriminator: torch.nn.Module | None = None,
                     disc_optimizer: torch.optim.Optimizer | None = None,
                     model: torch.nn.Module | None = None) -> tuple[int, dict]:
    """Restore what :func:`save_train_state` wrote into the given objects (the generator's weights too, when
    the state holds them); returns (step, extra)."""
    src = state_path(path)
    if not src.is_file():
        raise InputError("no resume state beside the checkpoint (expected " + src.name + ")", path)
    with safe_open(str(src), framework="pt") as f:
        meta = f.metadata() or {}
        tensors = {k: f.get_tensor(k) for k in f.keys()}
    weights = {k[4:]: v for k, v in tensors.items() if k.startswith("gen.")}
    if model is not None and weights:
        model.load_state_dict(weights)
    if discriminator is not None:
        discriminator.load_state_dict({k[5:]: v for k, v in tensors.items() if k.startswith("disc.")})
    groups = [("opt", optimizer)] + ([("dopt", disc_optimizer)] if disc_optimizer is not None else [])
    for prefix, opt in groups:
        state: dict[int, dict] = {}
        for key, value in tensors.items():
            parts = key.split(".")
            if parts[0] != prefix or parts[1] != "state":
                continue
            state.setdefault(int(parts[2]), {})[".".join(parts[3:])] = value
        opt.load_state_dict({"state": state, "param_groups": json.loads(meta[f"{prefix}.param_groups"])})
    return int(meta["step"]), json.loads(meta.get("extra", "{}"))
