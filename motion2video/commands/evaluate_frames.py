"""`motion2video evaluate-frames`: PSNR / SSIM of a frame generator and the baselines on held-out pairs."""

from __future__ import annotations

import argparse
import json
import sys
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
real frame; akd_missing: generated frames where it finds none).
"""

EXAMPLES = """\
examples:
  motion2video evaluate-frames --model frames-body-128 --json out/eval_frames_body.json
  motion2video evaluate-frames --model out/frames-face-128.safetensors --contact-sheet out/face_sheet.png
  motion2video evaluate-frames --model frames-body-128 --video ../shared/data/video/dancer.avi --json out/dancer.json
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
    p.add_argument("--no-progress", action="store_true", help="hide progress bars")


DEFAULT_BASELINE = {"body": "frames-body-128-v1"}  # the previous body generator, scored next to every new one


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    import imageio.v3 as iio

    from motion2video.core.errors import InputError
    from motion2video.frames.checkpoint import load_frame_model
    from motion2video.frames.data import default_cache_dir, load_or_generate
    from motion2video.frames.specs import default_spec
    from motion2video.frames.evaluate import evaluate_sequences, evaluation_contact_sheet, write_json

    if args.pairs is not None:
        check_at_least("--pairs", args.pairs)
    if args.video is not None:
        check_at_least("--video-frames", args.video_frames)
        if args.video_stride is not None:
            check_at_least("--video-stride", args.video_stride)
        if not Path(args.video).is_file():
            raise InputError("no such video file", args.video)
    loaded = load_frame_model(args.model)
    cfg = loaded.config
    if args.video is not None and cfg.domain != "body":
        raise InputError("--video scores body frame generators (this one makes face frames)", loaded.path)
    spec = default_spec(cfg.domain, "test", cfg.image_size)
    if args.test_sequences is not None:
        check_at_least("--test-sequences", args.test_sequences)
        spec = replace(spec, num_sequences=args.test_sequences,
                       num_identities=min(spec.num_identities, args.test_sequences))
    cache = Path(args.cache) if args.cache else default_cache_dir()
    names = args.baseline_model
    explicit = names is not None
    if names is None:
        names = [DEFAULT_BASELINE[cfg.domain]] if cfg.domain in DEFAULT_BASELINE else []
    baselines = {}
    for name in names:
        try:
            other = load_frame_model(name)
        except InputError as err:
            if explicit:
                raise
            print(f"motion2video evaluate-frames: note: default baseline left out ({err})", file=sys.stderr)
            continue
        if other.path.resolve() == loaded.path.resolve():
            continue
        same = (other.config.domain, other.config.image_size) == (cfg.domain, cfg.image_size)
        if not same and not explicit:  # the default baseline only goes with models of its size
            continue
        if not same:
            raise InputError(f"baseline model is {other.config.domain}/{other.config.image_size}, the evaluated "
                             f"model {cfg.domain}/{cfg.image_size}", other.path)
        baselines[other.path.name.removesuffix(".safetensors")] = other.model
    if args.video is not None:
        return _run_video(args, loaded, baselines)
    seqs = load_or_generate(spec, cache_dir=cache, data_root=args.data_root, progress=not args.no_progress)
    evaluation = evaluate_sequences(loaded.model, seqs, max_pairs=args.pairs, baseline_models=baselines)
    payload = evaluation.to_dict()
    payload["targets_met"] = evaluation.targets_met()
    payload["model"] = str(loaded.path)
    payload["model_kind"] = loaded.kind
    payload["model_step"] = loaded.step
    print(json.dumps(payload, indent=2, sort_keys=True))
    if args.json:
        write_json(evaluation, args.json, extra={"model": str(loaded.path), "model_kind": loaded.kind,
                                                 "model_step": loaded.step})
    if args.contact_sheet:
        out = Path(args.contact_sheet)
        out.parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(out, evaluation_contact_sheet(evaluation))
        print(f"wrote {out}")
    return 0


def _run_video(args: argparse.Namespace, loaded, baselines: dict) -> int:
    """``--video``: the reconstruction protocol (:mod:`motion2video.evaluation.video_frames`)."""
    import imageio.v3 as iio

    from motion2video.core.atomic import write_json
    from motion2video.evaluation.video_frames import evaluate_video
    from motion2video.frames.evaluate import evaluation_contact_sheet

    result = evaluate_video(loaded.model, args.video, size=loaded.config.image_size, targets=args.video_frames,
                            stride=args.video_stride, baseline_models=baselines)
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
