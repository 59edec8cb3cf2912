"""Scoring a frame generator (the ``evaluate-frames`` command's work): on the held-out synthetic pairs, on pairs
posed by real motion (``poses``), or by the reconstruction protocol on a real video (``video``,
:mod:`motion2video.evaluation.reconstruction`), each next to the previous generator as a named baseline."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import imageio.v3 as iio
from tqdm import tqdm

from motion2video.core.atomic import write_json
from motion2video.core.errors import InputError
from motion2video.evaluation.reconstruction import evaluate_video
from motion2video.evaluation.talking_head import evaluate_face_video
from motion2video.generator.checkpoint import load_frame_model
from motion2video.generator.data import default_cache_dir, load_or_generate, load_or_generate_with_heads
from motion2video.generator.scores import (FrameEvaluation, evaluate_sequences, evaluation_contact_sheet,
                                          face_region_masks, json_payload)
from motion2video.generator.scores import write_json as write_evaluation_json
from motion2video.generator.poses import PoseEvalSpec, load_body_clips, render_posed_sequences
from motion2video.generator.specs import SequencesWithHeads, default_spec

# The previous generator, scored next to every new one: the keypoint warp next to the body mesh generator, the
# feature-analogy face generator next to the face mesh generator, the feature-analogy body generator next to the
# keypoint warp.
DEFAULT_BASELINE = {"body": "frames-body-128-v1"}
DEFAULT_BASELINE_BY_KIND = {("mesh", "body"): "frames-body-128", ("mesh", "face"): "frames-face-128"}


@dataclass(frozen=True)
class FrameEvalSettings:
    """One ``evaluate-frames`` run.

    Attributes:
        model: a checkpoint file or a shipped name.
        json: write the results here as JSON (None: no file).
        contact_sheet: also write a PNG of generated frames beside the baselines' (None: no sheet).
        baseline_models: also score these generators as named baselines (None: the default previous one).
        cache: folder of the rendered npz shards (None: the default cache).
        data_root: folder with mocap/ and face/ captures (None: ../shared/data beside the repository).
        pairs: score only the first N pairs (None: all).
        test_sequences: render only this many held-out sequences (None: the spec's).
        poses: pose the held-out identities by the body motion file(s) here instead of the held-out pairs.
        windows: with ``poses``: windows per clip.
        video: a real video of one person: the reconstruction protocol instead (body models; for face models the
            talking-head protocol, :mod:`motion2video.evaluation.talking_head`).
        video_frames, video_stride, video_start_fraction: the protocol's targets, their spacing (None: spread
            over the video) and where they start (a share of the video's frames; frame 0 stays the reference).
        progress: show progress bars.
    """

    model: str | Path
    json: str | Path | None = None
    contact_sheet: str | Path | None = None
    baseline_models: tuple[str, ...] | None = None
    cache: str | Path | None = None
    data_root: str | Path | None = None
    pairs: int | None = None
    test_sequences: int | None = None
    poses: str | Path | None = None
    windows: int = 4
    video: str | Path | None = None
    video_frames: int = 64
    video_stride: int | None = None
    video_start_fraction: float = 0.0
    progress: bool = True


@dataclass
class FrameGeneratorEvaluation:
    """What :func:`evaluate_frame_generator` measured: the JSON report (also what ``--json`` holds) and the
    files written (None where not asked for)."""

    payload: dict
    json: Path | None
    contact_sheet: Path | None


def fits_as_baseline(kind: str, config, evaluated) -> bool:
    """Whether a generator (its kind and config) can be scored beside the ``evaluated`` model's config: the same
    domain, and the same size unless it is a keypoint warp generator (which works at any frame size)."""
    return config.domain == evaluated.domain and (config.image_size == evaluated.image_size or kind == "warp")


def load_baselines(names: list[str] | tuple[str, ...] | None, loaded) -> tuple[dict, dict[str, str]]:
    """Named baseline generators: name -> model, and name -> why it was left out (the default baseline only:
    another size, or refused for its skeleton version). An explicit baseline that cannot be used raises
    InputError. A keypoint warp generator goes with models of any size: it generates the person in a crop at its
    own size and pastes it into the frame, as it does in ``synthesize``."""
    cfg = loaded.config
    explicit = names is not None
    if names is None:
        default = DEFAULT_BASELINE_BY_KIND.get((loaded.kind, cfg.domain), DEFAULT_BASELINE.get(cfg.domain))
        names = [default] if default else []
    baselines, left_out = {}, {}
    for name in names:
        if not explicit:  # the default baseline only goes with models of its size: look before loading it
            peek = load_frame_model(name, any_skeleton=True)
            if not fits_as_baseline(peek.kind, peek.config, cfg):
                continue
        try:
            other = load_frame_model(name)
        except InputError as err:
            if explicit:
                raise
            left_out[str(name)] = str(err)
            continue
        if other.path.resolve() == loaded.path.resolve():
            continue
        if not fits_as_baseline(other.kind, other.config, cfg):
            raise InputError(f"baseline model is {other.config.domain}/{other.config.image_size}, the evaluated "
                             f"model {cfg.domain}/{cfg.image_size}", other.path)
        baselines[other.path.name.removesuffix(".safetensors")] = other.model
    return baselines, left_out


@dataclass
class PosedEvaluation:
    """Scores on pairs posed by real motion: the evaluation, the JSON summary of the clips (name, frames, fps,
    window starts) and the rendered windows."""

    evaluation: FrameEvaluation
    poses: dict
    rendered: SequencesWithHeads


def evaluate_posed(model, clips: list, *, poses_path: str | Path, windows: int, baselines: dict,
                   pairs: int | None = None, progress: bool = True) -> PosedEvaluation:
    """Render ``windows`` windows of each of ``clips`` ((name, Motion) pairs, read from ``poses_path``) on the
    held-out identities and score ``model`` and ``baselines`` on their first ``pairs`` pairs (None: all)."""
    spec = PoseEvalSpec.for_size(model.config.image_size, windows_per_clip=windows)
    with tqdm(total=len(clips) * spec.windows_per_clip, desc="rendering posed windows", unit="window",
              disable=not progress, leave=False) as bar:
        posed = render_posed_sequences(clips, spec, on_window=bar.update)
    evaluation = evaluate_sequences(model, posed.sequences, max_pairs=pairs, baseline_models=baselines,
                                    head_masks=posed.head_masks, pairs="poses")
    seqs = posed.sequences
    summary = {"path": str(poses_path), "windows_per_clip": spec.windows_per_clip,
               "frames_per_window": spec.frames_per_window, "window_seconds": spec.window_seconds,
               "identities": spec.num_identities,
               "clips": [{"name": name, "frames": motion.num_frames, "fps": motion.fps,
                          "window_starts": [int(st) for c, st in zip(seqs.clip, seqs.start) if c == name]}
                         for name, motion in clips]}
    return PosedEvaluation(evaluation, summary, posed)


def _held_out(s: FrameEvalSettings, loaded, baselines: dict) -> FrameEvaluation:
    """The held-out synthetic pairs of the model's domain and size, from the cache; body pairs with the visible
    head of every target (head_psnr / head_ssim)."""
    cfg = loaded.config
    spec = default_spec(cfg.domain, "test", cfg.image_size)
    if loaded.kind == "mesh" or cfg.domain == "face":  # the mesh correspondence; the faces' colour regions
        spec = replace(spec, vertices=True)
    if s.test_sequences is not None:
        spec = replace(spec, num_sequences=s.test_sequences, num_identities=min(spec.num_identities, s.test_sequences))
    cache = Path(s.cache) if s.cache else default_cache_dir()
    heads = regions = None
    if cfg.domain == "body":
        rendered = load_or_generate_with_heads(spec, cache_dir=cache, data_root=s.data_root, progress=s.progress)
        seqs, heads = rendered.sequences, rendered.head_masks
    else:
        seqs = load_or_generate(spec, cache_dir=cache, data_root=s.data_root, progress=s.progress)
        regions = face_region_masks(seqs)  # hair_colour_de, skin_colour_de
    return evaluate_sequences(loaded.model, seqs, max_pairs=s.pairs, baseline_models=baselines, head_masks=heads,
                              region_masks=regions)


def _write_sheet(path: str | Path | None, sheet) -> Path | None:
    if path is None:
        return None
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(out, sheet)
    return out


def evaluate_frame_generator(settings: FrameEvalSettings, *,
                             note: Callable[[str], None] = print) -> FrameGeneratorEvaluation:
    """Score ``settings.model`` and its baselines (held-out pairs, posed pairs or a video, as the settings say)
    and write the JSON and the contact sheet asked for; ``note`` hears the clips and baselines left out.

    Raises:
        InputError: a video that is not a file, a start fraction outside [0, 1), without a video or with a face
            model, a face model with ``poses``, a face video without a face, an unusable explicit
            baseline.
    """
    s = settings
    if s.video is not None:
        if not 0.0 <= s.video_start_fraction < 1.0:
            raise InputError(f"--video-start-fraction must be in [0, 1), got {s.video_start_fraction:g}")
        if not Path(s.video).is_file():
            raise InputError("no such video file", s.video)
    if s.video is None and s.video_start_fraction:
        raise InputError("--video-start-fraction goes with --video")
    loaded = load_frame_model(s.model)
    cfg = loaded.config
    if s.video is not None and cfg.domain == "face" and s.video_start_fraction:
        raise InputError("--video-start-fraction goes with body frame models (a face model is scored on the whole "
                         "face video)", loaded.path)
    if cfg.domain != "body" and s.poses is not None:
        raise InputError("--poses needs a body frame model", loaded.path)
    clips = None
    if s.poses is not None:
        clips = load_body_clips(s.poses, on_skip=lambda file, why: note(f"skipped {why}"))
    baselines, left_out = load_baselines(s.baseline_models, loaded)
    for name, why in left_out.items():
        note(f"baseline {name} left out: {why}")
    if s.video is not None and cfg.domain == "face":
        result = evaluate_face_video(loaded.model, s.video, size=cfg.image_size, targets=s.video_frames,
                                     stride=s.video_stride, baseline_models=baselines, note=note)
        payload = result.to_dict()
        payload.update(model=str(loaded.path), model_kind=loaded.kind, model_step=loaded.step)
        json_out = write_json(s.json, payload) if s.json else None
        sheet_of = result.frames
    elif s.video is not None:
        result = evaluate_video(loaded.model, s.video, size=cfg.image_size, targets=s.video_frames,
                                stride=s.video_stride, baseline_models=baselines,
                                start_fraction=s.video_start_fraction)
        payload = result.to_dict()
        payload.update(model=str(loaded.path), model_kind=loaded.kind, model_step=loaded.step)
        json_out = write_json(s.json, payload) if s.json else None
        sheet_of = result.frames
    else:
        extra = {"model": str(loaded.path), "model_kind": loaded.kind, "model_step": loaded.step}
        if left_out:
            extra["baselines_left_out"] = left_out
        if s.poses is not None:
            posed = evaluate_posed(loaded.model, clips, poses_path=s.poses, windows=s.windows, baselines=baselines,
                                   pairs=s.pairs, progress=s.progress)
            evaluation = posed.evaluation
            extra["poses"] = posed.poses
        else:
            evaluation = _held_out(s, loaded, baselines)
        payload = json_payload(evaluation, extra=extra)
        json_out = write_evaluation_json(evaluation, s.json, extra=extra) if s.json else None
        sheet_of = evaluation
    sheet = _write_sheet(s.contact_sheet, evaluation_contact_sheet(sheet_of)) if s.contact_sheet else None
    return FrameGeneratorEvaluation(payload=payload, json=json_out, contact_sheet=sheet)
