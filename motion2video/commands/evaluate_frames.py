"""`motion2video evaluate-frames`: PSNR / SSIM of a frame generator and the baselines on held-out pairs."""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path

from motion2video.commands.common import add_command, check_at_least

HELP = "score a frame generator against copy-reference and limb-warp on held-out pairs"

DESCRIPTION = """\
Render (or reuse from the cache) the held-out split (held-out identities and clips) for the model's domain and
size, and report whole-frame PSNR and SSIM (scikit-image) and person metrics (PSNR, SSIM and sharpness ratio
inside the target's silhouette, PSNR and sharpness where the person moved) for the generator, copy-reference,
limb-warp and the previous generator on the same pairs. With --video V (body models): the reconstruction
protocol of FOMM / TPSMM on a real video instead: frame 0 is the reference, the later frames' estimated poses
(BlazePose) drive the generator, the real frames are the truth, all cut to one square around the person; per
method l1 (mean absolute error in [0, 1]), PSNR, SSIM, person PSNR / SSIM / sharpness inside BlazePose's
segmentation of the real frame, and akd (pixels between the poses BlazePose finds on the generated and on the
real frame; akd_missing: generated frames where it finds none). The video is tracked once and cached in
~/.cache/motion2video/pose. --video-start-fraction F takes the targets from the video's tail only (frames from
F of the video on; frame 0 stays the reference): the part train-frames --video --train-fraction F never trains
on.

With --poses PATH (a body motion file or a folder of them, any format the readers know), the pairs come from
real motion instead: the frame test split's held-out identities, posed by windows spread evenly over each clip
(--windows per clip, the test split's 9 frames over 1.2 s each), rendered with the Anny body renderer as the
training data is; frame 0 of a window is the reference, every later frame a target whose truth is its render.
These runs also report head_psnr and head_ssim over the target's visible head (the silhouette of Anny's head
vertices); on the held-out pairs, --head adds them (the split is rendered again with head masks). A named baseline still trained on the previous canonical skeleton is left out, with a note.
"""

EXAMPLES = """\
examples:
  motion2video evaluate-frames --model frames-body-128 --json out/eval_frames_body.json
  motion2video evaluate-frames --model out/frames-face-128.safetensors --contact-sheet out/face_sheet.png
  motion2video evaluate-frames --model frames-body-128 --video ../shared/data/video/dancer.avi --json out/dancer.json
  motion2video evaluate-frames --model out/dancer-body-128.safetensors --video ../shared/data/video/dancer.avi \\
      --video-start-fraction 0.8 --json out/dancer_tail.json
  motion2video evaluate-frames --model frames-body-128 --poses ../shared/data/mocap/cmu/08_01.bvh --json out/real.json
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "evaluate-frames", run, help=HELP, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--model", required=True, help="a checkpoint file or a shipped name (frames-body-128)")
    p.add_argument("--json", default=None, help="write the results here as JSON")
    p.add_argument("--cache", default=None,
                   help="directory for the rendered npz shards (default ~/.cache/motion2video/frames)")
    p.add_argument("--data-root", default=None,
                   help="folder with mocap/ and face/ captures (default ../shared/data beside the repository)")
    p.add_argument("--pairs", type=int, default=None, help="evaluate only the first N pairs (default all)")
    p.add_argument("--test-sequences", type=int, default=None,
                   help="render only this many held-out sequences (default 32, 9 frames each: 256 pairs)")
    p.add_argument("--contact-sheet", default=None,
                   help="also write a PNG: reference | target | new | old | copy-reference | limb-warp")
    p.add_argument("--baseline-model", action="append", default=None, metavar="MODEL",
                   help="also score this generator (checkpoint or shipped name) as a named baseline on the same "
                   "pairs; repeatable (default for body models: the previous generator frames-body-128-v1)")
    p.add_argument("--video", default=None,
                   help="a real video of one person: score by the reconstruction protocol (body models)")
    p.add_argument("--video-frames", type=int, default=64,
                   help="--video: later frames scored against frame 0 (default 64, spread over the video)")
    p.add_argument("--video-stride", type=int, default=None,
                   help="--video: video frames between two scored frames (default: spread over the whole video)")
    p.add_argument("--video-start-fraction", type=float, default=0.0, metavar="F",
                   help="--video: take the targets from the tail only, from F of the video's frames on (e.g. 0.8, "
                   "the part train-frames --video leaves out); frame 0 stays the reference (default 0)")
    p.add_argument("--poses", default=None, metavar="PATH",
                   help="pose the held-out identities by the body motion file(s) at PATH (a file or a folder) "
                   "instead of the held-out pairs; adds head_psnr / head_ssim")
    p.add_argument("--windows", type=int, default=4,
                   help="with --poses: windows per clip, spread evenly over it (default 4, 8 pairs each)")
    p.add_argument("--head", action="store_true",
                   help="body models on the held-out pairs: also report head_psnr / head_ssim (renders the held-out "
                   "split again with head masks, bypassing the cache: as long as rendering it, a few minutes)")
    p.add_argument("--no-progress", action="store_true", help="hide progress bars")


# The previous generator, scored next to every new one: the keypoint warp next to the body mesh generator, the
# feature-analogy face generator next to the face mesh generator, the feature-analogy body generator next to the
# keypoint warp.
DEFAULT_BASELINE = {"body": "frames-body-128-v1"}
DEFAULT_BASELINE_BY_KIND = {("mesh", "body"): "frames-body-128", ("mesh", "face"): "frames-face-128"}


def fits_as_baseline(kind: str, config, evaluated) -> bool:
    """Whether a generator (its kind and config) can be scored beside the ``evaluated`` model's config: the same
    domain, and the same size unless it is a keypoint warp generator (which works at any frame size)."""
    return config.domain == evaluated.domain and (config.image_size == evaluated.image_size or kind == "warp")


def load_baselines(names: list[str] | None, loaded) -> tuple[dict, dict[str, str]]:
    """Named baseline generators: name -> model, and name -> why it was left out (the default baseline only:
    another size, or refused for its skeleton version). An explicit --baseline-model that cannot be used
    raises InputError. A keypoint warp generator goes with models of any size: it generates the person in a crop
    at its own size and pastes it into the frame, as it does in ``synthesize``."""
    from motion2video.core.errors import InputError
    from motion2video.frames.checkpoint import load_frame_model

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


def run(args: argparse.Namespace) -> int:
    import sys
    from dataclasses import replace

    import imageio.v3 as iio

    from motion2video.core.errors import InputError
    from motion2video.frames.checkpoint import load_frame_model
    from motion2video.frames.data import default_cache_dir, load_or_generate
    from motion2video.frames.evaluate import (evaluate_sequences, evaluation_contact_sheet, json_payload,
                                              write_json)
    from motion2video.frames.specs import default_spec

    if args.pairs is not None:
        check_at_least("--pairs", args.pairs)
    check_at_least("--windows", args.windows)
    if args.video is not None:
        check_at_least("--video-frames", args.video_frames)
        if args.video_stride is not None:
            check_at_least("--video-stride", args.video_stride)
        if not 0.0 <= args.video_start_fraction < 1.0:
            raise InputError(f"--video-start-fraction must be in [0, 1), got {args.video_start_fraction:g}")
        if not Path(args.video).is_file():
            raise InputError("no such video file", args.video)
    if args.video is None and args.video_start_fraction:
        raise InputError("--video-start-fraction goes with --video")
    loaded = load_frame_model(args.model)
    cfg = loaded.config
    if args.video is not None and cfg.domain != "body":
        raise InputError("--video scores body frame generators (this one makes face frames)", loaded.path)
    if cfg.domain != "body" and (args.poses is not None or args.head):
        raise InputError(f"{'--poses' if args.poses is not None else '--head'} needs a body frame model", loaded.path)
    clips = None
    if args.poses is not None:
        from motion2video.frames.poses import load_body_clips

        clips = load_body_clips(args.poses, on_skip=lambda file, why: print(f"note: skipped {why}", file=sys.stderr))
    baselines, left_out = load_baselines(args.baseline_model, loaded)
    for name, why in left_out.items():
        print(f"note: baseline {name} left out: {why}", file=sys.stderr)
    if args.video is not None:
        return _run_video(args, loaded, baselines)
    extra = {"model": str(loaded.path), "model_kind": loaded.kind, "model_step": loaded.step}
    if left_out:
        extra["baselines_left_out"] = left_out
    if args.poses is not None:
        posed = evaluate_posed(loaded.model, clips, args, baselines)
        evaluation = posed.evaluation
        extra["poses"] = posed.poses
    else:
        spec = default_spec(cfg.domain, "test", cfg.image_size)
        if loaded.kind == "mesh" or cfg.domain == "face":  # the mesh correspondence; the faces' colour regions
            spec = replace(spec, vertices=True)
        if args.test_sequences is not None:
            check_at_least("--test-sequences", args.test_sequences)
            spec = replace(spec, num_sequences=args.test_sequences,
                           num_identities=min(spec.num_identities, args.test_sequences))
        heads = None
        if args.head:
            from tqdm import tqdm

            from motion2video.frames.render_data import render_body_split_with_heads

            with tqdm(total=spec.num_sequences, desc="rendering held-out sequences with heads", unit="seq",
                      disable=args.no_progress, leave=False) as bar:
                rendered = render_body_split_with_heads(spec, data_root=args.data_root, on_sequence=bar.update)
            seqs, heads = rendered.sequences, rendered.head_masks
        else:
            cache = Path(args.cache) if args.cache else default_cache_dir()
            seqs = load_or_generate(spec, cache_dir=cache, data_root=args.data_root, progress=not args.no_progress)
        regions = None
        if cfg.domain == "face":
            from motion2video.frames.evaluate import face_region_masks

            regions = face_region_masks(seqs)  # hair_colour_de, skin_colour_de
        evaluation = evaluate_sequences(loaded.model, seqs, max_pairs=args.pairs, baseline_models=baselines,
                                        head_masks=heads, region_masks=regions)
    print(json.dumps(json_payload(evaluation, extra=extra), indent=2, sort_keys=True))
    if args.json:
        write_json(evaluation, args.json, extra=extra)
    if args.contact_sheet:
        out = Path(args.contact_sheet)
        out.parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(out, evaluation_contact_sheet(evaluation))
        print(f"wrote {out}")
    return 0


@dataclass
class PosedEvaluation:
    """``evaluate-frames --poses``: the evaluation, the JSON summary of the clips (name, frames, fps, window
    starts) and the rendered windows (:class:`motion2video.frames.render_data.SequencesWithHeads`)."""

    evaluation: object
    poses: dict
    rendered: object


def evaluate_posed(model, clips: list, args: argparse.Namespace, baselines: dict) -> PosedEvaluation:
    """Render the --poses pairs of ``clips`` ((name, Motion) pairs) and score them."""
    from tqdm import tqdm

    from motion2video.frames.evaluate import evaluate_sequences
    from motion2video.frames.poses import PoseEvalSpec, render_posed_sequences

    spec = PoseEvalSpec.for_size(model.config.image_size, windows_per_clip=args.windows)
    with tqdm(total=len(clips) * spec.windows_per_clip, desc="rendering posed windows", unit="window",
              disable=args.no_progress, leave=False) as bar:
        posed = render_posed_sequences(clips, spec, on_window=bar.update)
    evaluation = evaluate_sequences(model, posed.sequences, max_pairs=args.pairs, baseline_models=baselines,
                                    head_masks=posed.head_masks, pairs="poses")
    seqs = posed.sequences
    poses = {"path": str(args.poses), "windows_per_clip": spec.windows_per_clip,
             "frames_per_window": spec.frames_per_window, "window_seconds": spec.window_seconds,
             "identities": spec.num_identities,
             "clips": [{"name": name, "frames": motion.num_frames, "fps": motion.fps,
                        "window_starts": [int(st) for c, st in zip(seqs.clip, seqs.start) if c == name]}
                       for name, motion in clips]}
    return PosedEvaluation(evaluation, poses, posed)


def _run_video(args: argparse.Namespace, loaded, baselines: dict) -> int:
    """``--video``: the reconstruction protocol (:mod:`motion2video.evaluation.video_frames`)."""
    import imageio.v3 as iio

    from motion2video.core.atomic import write_json
    from motion2video.evaluation.video_frames import evaluate_video
    from motion2video.frames.evaluate import evaluation_contact_sheet

    result = evaluate_video(loaded.model, args.video, size=loaded.config.image_size, targets=args.video_frames,
                            stride=args.video_stride, baseline_models=baselines,
                            start_fraction=args.video_start_fraction)
    payload = result.to_dict()
    payload.update(model=str(loaded.path), model_kind=loaded.kind, model_step=loaded.step)
    print(json.dumps(payload, indent=2, sort_keys=True))
    if args.json:
        write_json(args.json, payload)
    if args.contact_sheet:
        out = Path(args.contact_sheet)
        out.parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(out, evaluation_contact_sheet(result.frames))
        print(f"wrote {out}")
    return 0
