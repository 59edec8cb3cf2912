"""Training loop of the frame generator: L1 + SSIM (+ an optional LSGAN patch discriminator), Adam with
warm-up and cosine decay, periodic resumable checkpoints.

Batches are drawn on the fly from rendered sequences (:mod:`motion2video.generator.data`): any two frames of a
sequence make a pair. The batch at step ``s`` depends only on ``(seed, s)``, so a resumed run sees the same
batches as an uninterrupted one.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from motion2video.core.errors import InputError
from motion2video.core.schedule import learning_rate  # the one schedule of both training loops
from motion2video.generator.checkpoint import (build_model, load_frame_model, load_train_state, model_kind,
                                            save_frame_model, save_train_state, state_path)
from motion2video.generator.specs import FrameSequences
from motion2video.generator.data import make_pairs, sample_pair_index, structure_channels
from motion2video.generator.model import (FrameGeneratorConfig, PatchDiscriminator, count_parameters,
                                       images_to_tensor, reconstruction_loss)
from motion2video.generator.mesh_warp import MeshWarpConfig, MeshWarpGenerator, mesh_inputs, mesh_source_mask
from motion2video.generator.warp import WarpGenerator, WarpGeneratorConfig


@dataclass(frozen=True)
class TrainFramesConfig:
    """Optimisation settings.

    Attributes:
        steps: total optimisation steps.
        batch_size: pairs per step.
        lr: peak learning rate (Adam).
        warmup_steps: linear warm-up length.
        final_lr_fraction: the cosine decay ends at ``lr * final_lr_fraction``.
        ssim_weight: weight of (1 - SSIM) next to L1.
        adversarial: add a conditional patch discriminator (LSGAN); off by default (slow on CPU).
        adv_weight: weight of the generator's adversarial term.
        flip: random left-right mirroring of pairs.
        crop: train on ``crop`` x ``crop`` windows holding both poses of each pair (0: whole frames). The
            network is fully convolutional, so it still runs on whole frames; crops put the compute where
            the person is (a body fills a small part of the frame).
        checkpoint_every: write the checkpoint and resume state every this many steps.
        log_every: record the losses every this many steps.
        seed: seeds the initialisation and the batches.
        model_kind: ``"analogy"`` (:class:`FrameGenerator`) or ``"warp"`` (:class:`WarpGenerator`).
        edge_weight: weight of the L1 between Sobel gradients of the output and the truth inside the
            target person's silhouette (needs sequences with masks); it pushes towards sharp people.
        person_weight: weight of an extra L1 inside the target person's silhouette.
        silhouette_erosion: mesh model: half of the pairs get their target silhouette input eroded by 1 to this
            many pixels (a fitted body thinner than the person: the generator learns to carry the person past
            the mesh's silhouette, along the flow's band); 0 = off.
    """

    steps: int = 3000
    batch_size: int = 8
    lr: float = 1e-3
    warmup_steps: int = 100
    final_lr_fraction: float = 0.05
    ssim_weight: float = 1.0
    adversarial: bool = False
    adv_weight: float = 0.01
    flip: bool = True
    crop: int = 0
    checkpoint_every: int = 250
    log_every: int = 25
    seed: int = 0
    model_kind: str = "analogy"
    silhouette_erosion: int = 0
    edge_weight: float = 0.0
    person_weight: float = 0.0

    def __post_init__(self) -> None:
        if self.steps < 1 or self.batch_size < 1 or self.checkpoint_every < 1 or self.log_every < 1:
            raise ValueError("steps, batch_size, checkpoint_every and log_every must be >= 1")
        if not self.lr > 0:
            raise ValueError("lr must be > 0")
        if self.crop < 0:
            raise ValueError("crop must be >= 0")
        if self.model_kind not in ("analogy", "warp", "mesh"):
            raise ValueError(f"model_kind must be analogy, warp or mesh, got {self.model_kind!r}")


@dataclass
class TrainFramesResult:
    """What a run did: the checkpoint, steps done in total, wall time of this call and in total (over
    resumes), steps per second of this call, and the logged losses ``{"step", "loss", "l1", "ssim", ...}``."""

    path: Path
    steps: int
    wall_s: float
    total_wall_s: float
    steps_per_second: float
    history: list[dict] = field(default_factory=list)


def _batch_tensors(seqs: FrameSequences, index: np.ndarray, flip: np.ndarray | None, *, crop: int = 0,
                   rng: np.random.Generator | None = None):
    pairs = make_pairs(seqs, index, flip=flip, crop=crop, rng=rng)
    x_ref = images_to_tensor(pairs.ref_images)  # (B, 3, H, W)
    x_tgt = images_to_tensor(pairs.tgt_images)
    p_ref = torch.from_numpy(pairs.ref_structures)  # (B, S, H, W)
    p_tgt = torch.from_numpy(pairs.tgt_structures)
    return x_ref, x_tgt, p_ref, p_tgt, pairs


def eroded_silhouettes(masks: np.ndarray, rng: np.random.Generator, most: int) -> np.ndarray:
    """(B, H, W) bool silhouettes, half of them (drawn with ``rng``) eroded by 1 to ``most`` pixels."""
    from scipy.ndimage import binary_erosion

    out = np.array(masks, bool, copy=True)
    for k in range(len(out)):
        if rng.random() < 0.5:
            out[k] = binary_erosion(out[k], iterations=int(rng.integers(1, most + 1)))
    return out


def sobel(x: torch.Tensor) -> torch.Tensor:
    """(B, C, H, W) -> (B, 2C, H, W) horizontal and vertical Sobel responses (zero padding)."""
    k = torch.tensor([[-1.0, 0.0, 1.0], [-2.0, 0.0, 2.0], [-1.0, 0.0, 1.0]], dtype=x.dtype, device=x.device) / 8.0
    c = x.shape[1]
    kx = k.view(1, 1, 3, 3).expand(c, 1, 3, 3)
    ky = k.t().contiguous().view(1, 1, 3, 3).expand(c, 1, 3, 3)
    return torch.cat([torch.nn.functional.conv2d(x, kx, padding=1, groups=c),
                      torch.nn.functional.conv2d(x, ky, padding=1, groups=c)], dim=1)


def person_terms(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """L1 and Sobel-gradient L1 inside a (B, 1, H, W) mask (means over the masked pixels)."""
    area = mask.sum().clamp_min(1.0)
    l1 = ((pred - target).abs() * mask).sum() / (3 * area)
    edge = ((sobel(pred) - sobel(target)).abs() * mask).sum() / (6 * area)
    return l1, edge


def grown_state(source: dict[str, torch.Tensor], target: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """``source`` weights fitted to a model whose layers may have *more output channels* (a head that
    gained outputs): such a tensor keeps its trained leading rows and takes the new model's initial values
    for the added ones; every other tensor is the source's (a mismatch of any other kind is left for
    ``load_state_dict`` to report).

    Args:
        source: the trained state dict; target: the new model's state dict (its initial values).
    Returns:
        a state dict with the target's shapes where only the first dimension grew.
    """
    out = dict(source)
    for name, new in target.items():
        old = source.get(name)
        if old is not None and old.dim() == new.dim() and old.shape[1:] == new.shape[1:] \
                and old.shape[0] < new.shape[0]:
            grown = new.clone()
            grown[: old.shape[0]] = old
            out[name] = grown
    return out


def train_frames(
    seqs: FrameSequences,
    *,
    output: str | Path,
    config: TrainFramesConfig = TrainFramesConfig(),
    model_config: FrameGeneratorConfig | None = None,
    resume: bool = False,
    progress: bool = True,
    extra_metadata: dict | None = None,
    init_from: str | Path | None = None,
) -> TrainFramesResult:
    """Train a frame generator on ``seqs`` and write ``output`` (+ its ``.state`` resume file).

    Args:
        seqs: training sequences (one domain, one image size).
        output: checkpoint path (``.safetensors``).
        config: optimisation settings.
        model_config: the architecture (default: the defaults for the data's domain and size).
        resume: continue from ``output`` and its resume state when they exist (the architecture is then
            the checkpoint's); without them training starts from scratch (a note is printed).
        progress: show a tqdm progress bar.
        extra_metadata: merged into the checkpoint's ``train`` summary.
        init_from: start from the weights of this checkpoint (same kind, same parameter shapes; its
            config may differ in settings without weights, e.g. the warp network's ``net_scale``, or add
            output channels, e.g. the warp network's ``flow_correction``: see :func:`grown_state`), with a
            fresh optimiser and schedule. Ignored when resuming.
    """
    output = Path(output)
    warp = config.model_kind in ("warp", "mesh")
    if model_config is None and config.model_kind == "mesh":
        model_config = MeshWarpConfig(domain=seqs.domain, image_size=seqs.image_size,
                                      structure_channels=structure_channels(seqs.domain))
    elif model_config is None and warp:
        model_config = WarpGeneratorConfig(domain=seqs.domain, image_size=seqs.image_size,
                                           structure_channels=structure_channels(seqs.domain))
    elif model_config is None:
        model_config = FrameGeneratorConfig(domain=seqs.domain, image_size=seqs.image_size,
                                            structure_channels=structure_channels(seqs.domain))
    if config.model_kind == "mesh" and seqs.vertex_uv is None:
        raise ValueError("the mesh generator trains on sequences that keep their mesh vertices (DatasetSpec.vertices)")
    if (config.edge_weight or config.person_weight) and seqs.masks is None:
        raise ValueError("edge_weight / person_weight need sequences with person masks")
    if config.model_kind == "mesh":  # the network's 4 levels at 1 / net_scale of the crop
        factor = 8 * model_config.net_scale
    elif warp:
        factor = 8
    else:
        factor = 2 ** (len(model_config.channels) - 1)
    if config.crop and (config.crop > seqs.image_size or config.crop % factor):
        raise ValueError(f"crop {config.crop} must be <= the image size {seqs.image_size} and a multiple of {factor}")
    if (model_config.domain, model_config.image_size) != (seqs.domain, seqs.image_size):
        raise ValueError(f"model is {model_config.domain}/{model_config.image_size} but the data is "
                         f"{seqs.domain}/{seqs.image_size}")
    torch.manual_seed(config.seed)
    start_step, past_wall = 0, 0.0
    model = build_model(config.model_kind, model_config)
    have_state = output.is_file() and state_path(output).is_file()
    if resume and have_state:
        loaded = load_frame_model(output)
        if (loaded.config.domain, loaded.config.image_size) != (seqs.domain, seqs.image_size):
            raise InputError(f"cannot resume: the checkpoint is {loaded.config.domain}/{loaded.config.image_size}"
                             f" but the data is {seqs.domain}/{seqs.image_size}", output)
        if loaded.kind != config.model_kind:
            raise InputError(f"cannot resume: the checkpoint is a {loaded.kind} model, not {config.model_kind}",
                             output)
        model = loaded.model
    elif resume:
        print(f"train-frames: nothing to resume at {output} (no checkpoint + .state file); starting from step 0")
    if init_from is not None and not (resume and have_state):
        source = load_frame_model(init_from, any_skeleton=True)  # fine-tuning on new joints is allowed
        if source.kind != config.model_kind:
            raise InputError(f"cannot start from a {source.kind} model when training a {config.model_kind} model",
                             init_from)
        try:
            model.load_state_dict(grown_state(source.model.state_dict(), model.state_dict()))
        except RuntimeError as err:
            raise InputError(f"its weights do not fit the model being trained ({str(err).splitlines()[0]})",
                             init_from) from None
    model.train()
    optimizer = torch.optim.Adam(model.parameters(), lr=config.lr, betas=(0.9, 0.99))
    disc = disc_opt = None
    if config.adversarial:
        disc = PatchDiscriminator(model.config.structure_channels)
        disc_opt = torch.optim.Adam(disc.parameters(), lr=config.lr, betas=(0.5, 0.99))
    if resume and have_state:
        start_step, extra = load_train_state(output, optimizer=optimizer, discriminator=disc,
                                             disc_optimizer=disc_opt, model=model)
        past_wall = float(extra.get("total_wall_s", 0.0))
    if start_step >= config.steps:
        print(f"train-frames: {output} has already done {start_step} >= {config.steps} steps")

    summary_base = {
        "train_config": dataclasses.asdict(config),
        "data": seqs.summary(),
        "parameters": count_parameters(model),
        "model_kind": model_kind(model),
        "init_from": None if init_from is None else str(init_from),
        **(extra_metadata or {}),
    }
    history: list[dict] = []
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=config.steps, initial=start_step, desc=f"train-frames {seqs.domain}", unit="step")
    t0 = time.perf_counter()

    def checkpoint(step: int) -> None:
        total = past_wall + time.perf_counter() - t0
        train_meta = {**summary_base, "steps": step, "total_wall_s": round(total, 1),
                      "last_losses": history[-1] if history else {}}
        save_frame_model(model, output, step=step, train=train_meta)
        save_train_state(output, optimizer=optimizer, step=step, discriminator=disc, disc_optimizer=disc_opt,
                         extra={"total_wall_s": total}, model=model)

    running: dict[str, float] = {}
    step = start_step
    for step in range(start_step, config.steps):
        rng = np.random.default_rng([config.seed, step])
        torch.manual_seed((config.seed * 1_000_003 + step) % (2 ** 63))  # any torch randomness: a function of the step
        index = sample_pair_index(rng, seqs, config.batch_size)
        flip = rng.random(config.batch_size) < 0.5 if config.flip else None
        x_ref, x_tgt, p_ref, p_tgt, pairs = _batch_tensors(seqs, index, flip, crop=config.crop, rng=rng)
        lr = learning_rate(step, config)
        for group in optimizer.param_groups:
            group["lr"] = lr

        if isinstance(model, MeshWarpGenerator):
            if config.silhouette_erosion:
                pairs.mesh_tgt_masks = eroded_silhouettes(pairs.tgt_masks, rng, config.silhouette_erosion)
            pred = model(x_ref, *mesh_inputs(pairs), p_tgt, source_mask=mesh_source_mask(pairs))
        elif isinstance(model, WarpGenerator):
            pred = model(x_ref, torch.from_numpy(pairs.ref_points), torch.from_numpy(pairs.tgt_points), p_tgt)
        else:
            pred = model(x_ref, p_ref, p_tgt)  # (B, 3, H, W)
        rec = reconstruction_loss(pred, x_tgt, ssim_weight=config.ssim_weight)
        total = rec.total
        terms = {"loss": float(rec.total.detach()), "l1": rec.l1, "ssim": rec.ssim}
        if config.edge_weight or config.person_weight:
            mask = torch.from_numpy(pairs.tgt_masks)[:, None].float()
            p_l1, p_edge = person_terms(pred, x_tgt, mask)
            total = total + config.person_weight * p_l1 + config.edge_weight * p_edge
            terms.update(person_l1=float(p_l1.detach()), person_edge=float(p_edge.detach()))
        if disc is not None:
            g_adv = ((disc(pred, p_tgt) - 1.0) ** 2).mean()
            total = total + config.adv_weight * g_adv
            terms["g_adv"] = float(g_adv.detach())
        optimizer.zero_grad(set_to_none=True)
        total.backward()
        optimizer.step()
        if disc is not None:
            for group in disc_opt.param_groups:
                group["lr"] = lr
            d_loss = ((disc(x_tgt, p_tgt) - 1.0) ** 2).mean() + (disc(pred.detach(), p_tgt) ** 2).mean()
            disc_opt.zero_grad(set_to_none=True)
            d_loss.backward()
            disc_opt.step()
            terms["d"] = float(d_loss.detach())

        for k, v in terms.items():
            running[k] = running.get(k, 0.0) + v
        done = step + 1
        if done % config.log_every == 0 or done == config.steps:
            count = config.log_every if done % config.log_every == 0 else done % config.log_every
            record = {"step": done, "lr": lr, **{k: v / count for k, v in running.items()}}
            history.append(record)
            running = {}
            if bar is not None:
                bar.set_postfix(loss=f"{record['loss']:.4f}", ssim=f"{record['ssim']:.3f}")
        if bar is not None:
            bar.update(1)
        if done % config.checkpoint_every == 0 or done == config.steps:
            checkpoint(done)
    if bar is not None:
        bar.close()
    wall = time.perf_counter() - t0
    steps_done = max(0, config.steps - start_step)
    return TrainFramesResult(path=output, steps=max(start_step, config.steps), wall_s=wall,
                             total_wall_s=past_wall + wall,
                             steps_per_second=steps_done / wall if wall > 0 else 0.0, history=history)
