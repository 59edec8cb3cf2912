"""Training a frame generator on synthetic Anny renders from the command's settings (the ``train-frames``
command's work): the generator's config checked before the data, the appearance dataset rendered (or read from
the cache), and :func:`motion2video.generator.training.train_frames` run. Fine-tuning on one person's video is
:func:`motion2video.evaluation.personalise.personalise`."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from motion2video.core.errors import InputError
from motion2video.data.licences import licence_record
from motion2video.formats.manifest import read_manifest
from motion2video.generator.data import default_cache_dir, load_or_generate, structure_channels
from motion2video.generator.mesh_warp import MeshWarpConfig
from motion2video.generator.specs import default_data_root, default_spec
from motion2video.generator.training import TrainFramesConfig, TrainFramesResult, train_frames
from motion2video.generator.warp import WarpGeneratorConfig

MODEL_KINDS = ("analogy", "warp", "mesh")


def sequence_licences(seqs, *, data_root: str | Path | None) -> dict:
    """The licence record (:func:`motion2video.data.licences.licence_record`) of the captures that posed or
    animated the training sequences, from the ``manifest.csv`` of ``mocap/`` (bodies) or ``face/`` (faces)."""
    root = Path(data_root) if data_root is not None else default_data_root()
    manifest_path = root / ("mocap" if seqs.domain == "body" else "face") / "manifest.csv"
    entries = read_manifest(manifest_path) if manifest_path.is_file() else {}
    return licence_record([entries[c].licence if c in entries else None for c in seqs.summary()["clips"]])


@dataclass(frozen=True)
class FrameTrainingSettings:
    """One training run of a frame generator.

    Attributes:
        domain: ``body`` or ``face``.
        output: the checkpoint (``.safetensors``; its ``.state`` resume file beside it).
        steps, batch_size, lr, adversarial, checkpoint_every, seed: as
            :class:`motion2video.generator.training.TrainFramesConfig` (``seed`` also seeds the rendered data).
        size: frame size (64, 128 or 256).
        cache: folder of the rendered npz shards (None: :func:`motion2video.generator.data.default_cache_dir`).
        data_root: folder with mocap/ and face/ captures (None: ../shared/data beside the repository).
        train_sequences: rendered training sequences (None: the spec's 240).
        crop: training crop (0: whole frames; None: half the frame).
        model_kind: ``analogy``, ``warp`` (body only) or ``mesh``.
        net_scale: warp or mesh: the network works at 1/net_scale of the resolution (None: warp 4, mesh size/64).
        flow_correction: warp: the network also predicts a dense residual of the flow.
        sample_mode: warp or mesh: ``bilinear`` or ``bicubic`` (None: warp bilinear, mesh bicubic).
        init_from: start from this checkpoint's weights (same kind).
        edge_weight, person_weight: loss weights inside the target silhouette (None: 1 and 2 for warp and mesh,
            0 else).
        silhouette_erosion: mesh: erode half of the target silhouettes by 1 to this many pixels.
        resume: continue from the output and its ``.state`` file.
        progress: show progress bars.
    """

    domain: str
    output: str | Path
    steps: int = 3000
    size: int = 128
    batch_size: int = 8
    lr: float = 1e-3
    cache: str | Path | None = None
    data_root: str | Path | None = None
    train_sequences: int | None = None
    crop: int | None = None
    model_kind: str = "analogy"
    net_scale: int | None = None
    flow_correction: bool = False
    sample_mode: str | None = None
    init_from: str | Path | None = None
    edge_weight: float | None = None
    person_weight: float | None = None
    adversarial: bool = False
    silhouette_erosion: int = 0
    checkpoint_every: int = 250
    resume: bool = False
    seed: int = 0
    progress: bool = True


def default_crop(domain: str, size: int) -> int:
    """Training crop: half the frame (measured: body, 400 steps on 64 crops reach the PSNR of 400 steps on
    whole 128 frames in 1/8 of the time; faces train well on them too)."""
    return size // 2


def _model_config(s: FrameTrainingSettings, crop: int) -> MeshWarpConfig | WarpGeneratorConfig | None:
    """The warp or mesh generator's config (None: the analogy generator's default), InputError for settings of
    another kind."""
    if s.model_kind == "mesh":
        if s.flow_correction:
            raise InputError("--model-kind mesh: its flow residual is always on (leave out --flow-correction)")
        net_scale = s.net_scale or max(1, s.size // 64)  # the network at 64 px: 2 at 128, 4 at 256
        if crop % (net_scale * 8):
            raise InputError(f"--crop {crop} must be a multiple of {net_scale * 8} at --net-scale {net_scale}")
        return MeshWarpConfig(domain=s.domain, image_size=s.size, structure_channels=structure_channels(s.domain),
                              net_scale=net_scale, sample_mode=s.sample_mode or "bicubic")
    if s.model_kind == "warp":
        return WarpGeneratorConfig(image_size=s.size, structure_channels=structure_channels("body"),
                                   net_scale=s.net_scale or 4, flow_correction=s.flow_correction,
                                   sample_mode=s.sample_mode or "bilinear")
    if s.net_scale is not None or s.flow_correction or s.sample_mode is not None:
        raise InputError("--net-scale, --flow-correction and --sample-mode are settings of --model-kind warp or mesh")
    return None


def train_frame_generator(settings: FrameTrainingSettings) -> TrainFramesResult:
    """Check ``settings`` (InputError before any data is rendered), render or read the training split and
    train; the checkpoint is written at ``settings.output``."""
    s = settings
    if s.model_kind not in MODEL_KINDS:
        raise InputError(f"unknown --model-kind {s.model_kind!r}; choose one of {', '.join(MODEL_KINDS)}")
    if s.model_kind == "warp" and s.domain != "body":
        raise InputError(f"--model-kind {s.model_kind} makes body frames only (use --domain body)")
    if s.silhouette_erosion < 0 or (s.silhouette_erosion and s.model_kind != "mesh"):
        raise InputError("--silhouette-erosion is a setting of --model-kind mesh (0 or more pixels)")
    output = Path(s.output)
    if output.suffix != ".safetensors":
        raise InputError("the checkpoint name must end in .safetensors", output)
    spec = default_spec(s.domain, "train", s.size, seed=s.seed)
    if s.train_sequences is not None:
        spec = replace(spec, num_sequences=s.train_sequences,
                       num_identities=min(spec.num_identities, s.train_sequences))
    crop = default_crop(s.domain, s.size) if s.crop is None else s.crop
    if crop < 0 or crop > s.size or crop % 16:
        raise InputError(f"--crop must be 0 or a multiple of 16 up to --size, got {crop}")
    model_config = _model_config(s, crop)  # checked before the data, which may take minutes to render
    if s.model_kind == "mesh":
        spec = replace(spec, vertices=True)  # the mesh correspondence of every frame
    warp = s.model_kind in ("warp", "mesh")
    edge = s.edge_weight if s.edge_weight is not None else (1.0 if warp else 0.0)
    person = s.person_weight if s.person_weight is not None else (2.0 if warp else 0.0)
    cache = Path(s.cache) if s.cache else default_cache_dir()
    seqs = load_or_generate(spec, cache_dir=cache, data_root=s.data_root, progress=s.progress)
    config = TrainFramesConfig(steps=s.steps, batch_size=s.batch_size, lr=s.lr, crop=crop,
                               adversarial=s.adversarial, checkpoint_every=s.checkpoint_every, seed=s.seed,
                               model_kind=s.model_kind, edge_weight=edge, person_weight=person,
                               silhouette_erosion=s.silhouette_erosion)
    return train_frames(seqs, output=output, config=config, model_config=model_config, resume=s.resume,
                        progress=s.progress, init_from=s.init_from,
                        extra_metadata={"dataset_spec": spec.key(),
                                        "licences": sequence_licences(seqs, data_root=s.data_root)})
