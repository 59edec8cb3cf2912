"""Motion-model checkpoints: safetensors weights + a self-describing JSON metadata record. No pickles.

A checkpoint ``NAME.safetensors`` holds the model's ``state_dict`` and two metadata strings:
``format`` = ``"motion2video-motion"`` and ``motion2video`` = the JSON record::

    {"model": "mtvae-add", "kind": "stochastic", "config": {...model config dataclass...},
     "data": {"config": {...DatasetConfig...}, "layout": "body3d", "num_features": 51,
              "stats": {"mean": [...], "std": [...]}, "split": {"train": [...], "val": [...], "test": [...]},
              "summary": {...}},
     "skeleton": "h36m-17", "version": "0.1.0",
     "training": {"steps": 3000, "seed": 0, "config": {...TrainConfig...}, "wall_time_s": ..., ...}}

:func:`load_model` rebuilds any of them from a path or a shipped name (``motion2video/weights/<name>.safetensors``).
Optimizer state for resuming lives in a sidecar file written by :mod:`motion2video.models.training`.
"""

from __future__ import annotations

import json
import re
import sys
from dataclasses import asdict, dataclass, field, is_dataclass
from pathlib import Path

import torch
from safetensors import SafetensorError, safe_open
from safetensors.torch import save_file

import motion2video.models  # noqa: F401  (registers the learned models and the baselines)
from motion2video import __version__
from motion2video.core.atomic import atomic_output
from motion2video.data.dataset import DatasetConfig, Split
from motion2video.data.licences import licence_note, model_licences
from motion2video.data.windows import FeatureLayout, NormStats
from motion2video.core.errors import CHECKPOINT_FORMAT_VERSION, check_format_version
from motion2video.core.errors import InputError
from motion2video.core.skeletons import SKELETON_VERSION, check_skeleton_version
from motion2video.models.base import MODEL_REGISTRY, build_model
from motion2video.models.baselines import RULES

FORMAT = "motion2video-motion"
WEIGHTS_DIR = Path(__file__).resolve().parents[1] / "weights"
SUFFIX = ".safetensors"
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
# Formats written by other parts of the project, for a helpful wrong-kind message.
OTHER_FORMATS = {"motion2video-frames": "a frame-generator checkpoint"}


@dataclass
class CheckpointMeta:
    """What a checkpoint says about itself (the decoded metadata record)."""

    model: str
    kind: str
    config: dict
    data_config: DatasetConfig
    stats: NormStats
    split: Split | None
    skeleton: str | None
    version: str
    data_summary: dict = field(default_factory=dict)
    training: dict = field(default_factory=dict)
    # The canonical skeleton definition the joints followed (core.skeletons.SKELETON_VERSION); None: a
    # checkpoint written before versions were recorded (version 1), or a model of no body skeleton.
    skeleton_version: int | None = None

    @property
    def layout(self) -> FeatureLayout:
        return self.data_config.feature_layout

    def to_json(self) -> str:
        return json.dumps({
            "model": self.model,
            "kind": self.kind,
            "config": self.config,
            "data": {
                "config": self.data_config.to_dict(),
                "layout": self.data_config.layout,
                "num_features": self.data_config.feature_layout.num_features,
                "stats": self.stats.to_dict(),
                "split": None if self.split is None else self.split.to_dict(),
                "summary": self.data_summary,
            },
            "skeleton": self.skeleton,
            "skeleton_version": self.skeleton_version,
            "version": self.version,
            "training": self.training,
        })

    @staticmethod
    def from_json(text: str) -> "CheckpointMeta":
        d = json.loads(text)
        data = d["data"]
        return CheckpointMeta(
            model=d["model"], kind=d["kind"], config=d["config"],
            data_config=DatasetConfig.from_dict(data["config"]), stats=NormStats.from_dict(data["stats"]),
            split=None if data.get("split") is None else Split.from_dict(data["split"]),
            skeleton=d.get("skeleton"), version=d["version"], data_summary=data.get("summary", {}),
            training=d.get("training", {}), skeleton_version=d.get("skeleton_version"),
        )


@dataclass
class ModelBundle:
    """A rebuilt model (eval mode) with what it needs to read and write motion.

    Attributes:
        model: the torch module (features in, features out).
        stats: its normalisation statistics.
        meta: the checkpoint metadata (data config, split, training record).
        path: the checkpoint file (None for a baseline built on the fly).
    """

    model: torch.nn.Module
    stats: NormStats
    meta: CheckpointMeta
    path: Path | None = None

    @property
    def name(self) -> str:
        return self.meta.model

    @property
    def label(self) -> str:
        """What tables call it: the checkpoint's file name (``mtvae-add-dlow``), or the model name for a
        baseline built on the fly."""
        if self.path is None:
            return self.meta.model
        name = Path(self.path).name
        return name[: -len(".safetensors")] if name.endswith(".safetensors") else name

    @property
    def kind(self) -> str:
        return self.meta.kind

    @property
    def licences(self) -> dict | None:
        """The licences of the files it was trained on (:func:`motion2video.data.licences.licence_record`):
        the checkpoint's own record, else the shipped record of its name; None for neither."""
        return model_licences(self.label, self.meta.data_summary.get("licences"))

    @property
    def data_config(self) -> DatasetConfig:
        return self.meta.data_config

    @property
    def layout(self) -> FeatureLayout:
        return self.meta.layout


def config_dict(config) -> dict:
    """A frozen config dataclass as a plain dict."""
    if not is_dataclass(config):
        raise TypeError(f"model config must be a dataclass, got {type(config).__name__}")
    return asdict(config)


# Shipped names whose weights were removed, and what to use instead (a user's command line may still name them).
RETIRED = {
    "mixer-dct": "retired on 2026-11-27: mixer-cvae-dlow is better on every action; the weights and their card are "
                 "in git history at 696e72f, and `motion2video train --model mixer-dct` still trains one",
}


def shipped_names() -> list[str]:
    """Names of the checkpoints shipped in ``motion2video/weights``."""
    if not WEIGHTS_DIR.is_dir():
        return []
    return sorted(p.name[: -len(SUFFIX)] for p in WEIGHTS_DIR.glob("*" + SUFFIX)
                  if ".last" not in p.name and ".optim" not in p.name)


def resolve_checkpoint(path_or_name: str | Path) -> Path:
    """A checkpoint path, or a shipped name -> ``motion2video/weights/<name>.safetensors``.

    Raises InputError naming the argument when neither exists.
    """
    path = Path(path_or_name)
    if path.is_file():
        return path
    text = str(path_or_name)
    if _NAME.match(text):
        shipped = WEIGHTS_DIR / (text + SUFFIX)
        if shipped.is_file():
            return shipped
    if path.exists():
        raise InputError("is not a checkpoint file", path)
    if text in RETIRED:
        raise InputError(f"this shipped model was {RETIRED[text]}", path_or_name)
    known = shipped_names()
    hint = f"shipped models: {', '.join(known)}" if known else "no models are shipped in motion2video/weights yet"
    raise InputError(f"no such checkpoint file or shipped model name ({hint})", path_or_name)


def save_checkpoint(path: str | Path, *, model: torch.nn.Module, meta: CheckpointMeta) -> Path:
    """Write ``model``'s weights and ``meta`` atomically (temporary file + rename)."""
    path = Path(path)
    tensors = {k: v.detach().contiguous().cpu() for k, v in model.state_dict().items()}
    with atomic_output(path) as tmp:
        save_file(tensors, str(tmp), metadata={"format": FORMAT, "format_version": str(CHECKPOINT_FORMAT_VERSION),
                                               "motion2video": meta.to_json()})
    return path


def read_meta(path: str | Path) -> CheckpointMeta:
    """The metadata of a motion-model checkpoint; InputError for other files or other checkpoint kinds."""
    path = Path(path)
    try:
        with safe_open(str(path), framework="pt") as f:
            metadata = f.metadata() or {}
    except (SafetensorError, OSError, ValueError) as err:
        raise InputError(f"not a readable safetensors checkpoint ({str(err).splitlines()[0]})", path) from None
    fmt = metadata.get("format")
    if fmt != FORMAT:
        what = OTHER_FORMATS.get(fmt, "not a motion2video checkpoint" if fmt is None else f"a {fmt!r} file")
        raise InputError(f"wrong kind of checkpoint: this is {what}, not a motion model", path)
    check_format_version(metadata, path)
    if "motion2video" not in metadata:
        raise InputError("damaged checkpoint metadata: the 'motion2video' record is missing", path)
    try:
        return CheckpointMeta.from_json(metadata["motion2video"])
    except (KeyError, TypeError, ValueError, AttributeError, json.JSONDecodeError) as err:
        raise InputError(f"damaged checkpoint metadata ({type(err).__name__}: {err})", path) from None


def load_model(path_or_name: str | Path, *, device: str | torch.device = "cpu") -> ModelBundle:
    """Rebuild a motion model from a checkpoint path or a shipped name.

    Returns:
        A :class:`ModelBundle` with the model in eval mode on ``device``.
    Raises:
        InputError: no such file / name, not a motion-model checkpoint, an unknown model name, or weights
        that do not fit the recorded config.
    """
    path = resolve_checkpoint(path_or_name)
    meta = read_meta(path)
    check_skeleton_version(meta.skeleton, meta.skeleton_version, path)
    if meta.model not in MODEL_REGISTRY:
        raise InputError(f"the checkpoint's model {meta.model!r} is not a known model "
                         f"(known: {', '.join(sorted(MODEL_REGISTRY))})", path)
    try:
        model = build_model(meta.model, meta.config)
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"cannot rebuild model {meta.model!r} from the recorded config ({err})", path) from None
    with safe_open(str(path), framework="pt") as f:
        state = {k: f.get_tensor(k) for k in f.keys()}
    try:
        model.load_state_dict(state, strict=True)
    except RuntimeError as err:
        raise InputError(f"the weights do not fit model {meta.model!r}: {str(err).splitlines()[0]}", path) from None
    model.to(device).eval()
    bundle = ModelBundle(model=model, stats=meta.stats, meta=meta, path=path)
    note = licence_note(bundle.label, bundle.licences)
    if note is not None:
        print(f"motion2video: note: {note}", file=sys.stderr)
    return bundle


def baseline_bundle(name: str, data_config: DatasetConfig, *, stats: NormStats | None = None,
                    config: dict | None = None) -> ModelBundle:
    """A baseline (no weights) as a bundle for ``data_config``'s layout (identity stats unless given;
    baselines are exact under any affine normalisation); ``config``: its config fields other than the feature
    count (a rule's, such as mirror-periodic's half-periods; None: the defaults)."""
    entry = MODEL_REGISTRY.get(name)
    if entry is None or entry.kind != "baseline":
        raise InputError(f"{name!r} is not a baseline")
    num = data_config.feature_layout.num_features
    model = build_model(name, {**(config or {}), "feature_dim": num}).eval()
    stats = stats or NormStats.identity(num)
    if hasattr(model, "use_stats"):  # a rule that needs metres (mirror-periodic), not an affine extrapolation
        model.use_stats(stats.mean, stats.std)
    meta = CheckpointMeta(model=name, kind="baseline", config=config_dict(model.config), data_config=data_config,
                          stats=stats, split=None, skeleton="h36m-17" if data_config.feature_layout.is_body else None,
                          version=__version__,
                          skeleton_version=SKELETON_VERSION if data_config.feature_layout.is_body else None)
    return ModelBundle(model=model, stats=stats, meta=meta, path=None)


def split_record(bundle: ModelBundle) -> dict | None:
    """The recorded train / val / test clip lists of a bundle's checkpoint (None when it records no split)."""
    return None if bundle.meta.split is None else bundle.meta.split.to_dict()


def compose_mixture(bundles: list[ModelBundle], shares: list[float] | None = None) -> ModelBundle:
    """A :mod:`~motion2video.models.mixture` of trained samplers, their weights copied in (nothing is trained).

    Args:
        bundles: two or more loaded stochastic models with the same feature layout, windows, normalisation
            statistics and split (the mixture's checkpoint records them once), or multi-future rules
            (``mirror-periodic``, from :func:`baseline_bundle` with the first bundle's statistics).
        shares: one positive weight per bundle (None: equal shares, future k from bundle k mod C).
    Returns:
        The mixture as a bundle (eval mode, ``path`` None), ready for :func:`save_checkpoint`.
    Raises:
        InputError: fewer than two bundles, a baseline or deterministic model, or components that disagree.
    """
    if len(bundles) < 2:
        raise InputError(f"a mixture needs at least two models, got {len(bundles)}")
    if shares is not None and (len(shares) != len(bundles) or min(shares) <= 0):
        raise InputError(f"a mixture needs one positive share per model ({len(bundles)}), got {list(shares)}")
    first = bundles[0]
    if first.kind != "stochastic":
        raise InputError(f"a mixture's first component must be a trained stochastic model, not {first.kind} "
                         f"{first.name!r}", first.path or first.label)
    for b in bundles:
        where = b.path or b.label
        rule = b.kind == "baseline" and b.name in RULES
        if not (b.kind == "stochastic" or rule) or b.name == "mixture":
            raise InputError(f"a mixture's component must be a trained stochastic model or a multi-future rule, "
                             f"not {b.kind} {b.name!r}", where)
        if b.data_config.to_dict() != first.data_config.to_dict():
            raise InputError(f"its windows or feature layout differ from {first.label}'s", where)
        if not b.stats.same_as(first.stats):
            raise InputError(f"its normalisation statistics differ from {first.label}'s", where)
        if not rule and split_record(b) != split_record(first):  # a rule learned nothing from any split
            raise InputError(f"it was trained on another split than {first.label}", where)
        if b.meta.skeleton_version != first.meta.skeleton_version:
            raise InputError(f"its canonical skeleton version differs from {first.label}'s", where)
    components = [{"name": b.label, "model": b.name, "config": b.meta.config} for b in bundles]
    model = build_model("mixture", {"feature_dim": first.layout.num_features, "components": components,
                                    "shares": tuple(shares or ())})
    for part, b in zip(model.components, bundles):
        part.load_state_dict(b.model.state_dict(), strict=True)
    model.eval()
    meta = CheckpointMeta(model="mixture", kind="stochastic", config=config_dict(model.config),
                          data_config=first.data_config, stats=first.stats, split=first.meta.split,
                          skeleton=first.meta.skeleton, version=__version__, data_summary=first.meta.data_summary,
                          training={"steps": 0, "composed_from": [
                              {"name": b.label, "model": b.name, "steps": b.meta.training.get("steps"),
                               "wall_time_s": b.meta.training.get("wall_time_s")} for b in bundles]},
                          skeleton_version=first.meta.skeleton_version)
    return ModelBundle(model=model, stats=first.stats, meta=meta, path=None)
