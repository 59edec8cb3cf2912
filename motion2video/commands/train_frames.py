"""`motion2video train-frames`: train the keypoint-conditioned frame generator on synthetic Anny renders."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from motion2video.commands.common import add_command, add_threads_argument, check_at_least, set_threads

HELP = "train the keypoint-conditioned frame generator (body or face)"

DESCRIPTION = """\
Render (or reuse from the cache) a synthetic appearance dataset with the Anny body or face renderer, posed by
real captures, then train the frame generator with L1 + SSIM. Checkpoints (safetensors) are written
periodically; --resume continues an interrupted run.

With --video V --init-from M (personalisation): fine-tune the body generator M on one person's video instead.
The video is tracked once (BlazePose, cached in ~/.cache/motion2video/pose); its first 80% of frames
(--train-fraction) are the training data (pairs of its frames with their estimated poses and person masks, cut
to one square around the person and resized to the model's size, as evaluate-frames --video cuts them). The
last 20% is never trained on: it is then scored by the reconstruction protocol of evaluate-frames --video
--video-start-fraction 0.8 (frame 0 the reference, targets from the tail only) for the fine-tuned model and for
M on the same pairs; both are printed (l1, person_psnr, akd) with the ratio of their L1, and written to --json.
"""

EXAMPLES = """\
examples:
  motion2video train-frames --domain body -o out/frames-body-128.safetensors --steps 4000 --cache /tmp/m2v-cache
  motion2video train-frames --domain face -o out/frames-face-128.safetensors --steps 3500 --resume
  motion2video train-frames --domain body -o out/tiny.safetensors --steps 50 --train-sequences 16
  motion2video train-frames --video ../shared/data/video/dancer.avi --init-from frames-body-128 \\
      -o out/dancer-body-128.safetensors --steps 600 --json out/dancer_personalised.json
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "train-frames", run, help=HELP, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--domain", choices=("body", "face"), default=None,
                   help="body or face frames (required, except with --video: body)")
    p.add_argument("-o", "--output", required=True, help="checkpoint to write (.safetensors)")
    p.add_argument("--steps", type=int, default=None, help="optimisation steps (default 3000; with --video 600)")
    p.add_argument("--size", type=int, default=128, choices=(64, 128, 256), help="frame size (default 128)")
    p.add_argument("--batch-size", type=int, default=8, help="pairs per step (default 8)")
    p.add_argument("--lr", type=float, default=None, help="peak learning rate (default 1e-3; with --video 5e-4)")
    p.add_argument("--cache", default=None,
                   help="directory for the rendered npz shards (default ~/.cache/motion2video/frames)")
    p.add_argument("--data-root", default=None,
                   help="folder with mocap/ and face/ captures (default ../shared/data beside the repository)")
    p.add_argument("--train-sequences", type=int, default=None,
                   help="rendered training sequences (default 240, 12 frames each)")
    p.add_argument("--crop", type=int, default=None,
                   help="train on CROP x CROP windows holding both poses of a pair (0: whole frames; "
                   "default size/2, about 8x less compute per step than whole frames for the same quality; "
                   "with --video 0)")
    p.add_argument("--model-kind", choices=("analogy", "warp", "mesh"), default=None,
                   help="analogy (default): the feature-analogy generator; warp: the generator that warps the "
                   "reference person along per-limb transforms (body only); mesh: the generator that moves it "
                   "along the correspondence of one Anny mesh in both poses (body, or face: the head mesh); with --video: the "
                   "--init-from model's")
    p.add_argument("--net-scale", type=int, default=None, choices=(1, 2, 4),
                   help="warp or mesh model: its network works at 1/NET_SCALE of the resolution (default: warp 4; mesh size/64, 2 at 128 and 4 at 256)")
    p.add_argument("--flow-correction", action="store_true",
                   help="warp model: the network also predicts a dense residual of the person's flow")
    p.add_argument("--sample-mode", choices=("bilinear", "bicubic"), default=None,
                   help="warp model: how the reference is sampled by the flow (default bilinear; bicubic is sharper)")
    p.add_argument("--init-from", default=None,
                   help="start from this checkpoint's weights (same kind), with a fresh optimiser and schedule")
    p.add_argument("--edge-weight", type=float, default=None,
                   help="weight of the gradient (Sobel) L1 inside the target silhouette (default 1 for warp, 0 else; "
                   "with --video 2)")
    p.add_argument("--person-weight", type=float, default=None,
                   help="weight of the L1 inside the target silhouette (default 2 for warp, 0 else)")
    p.add_argument("--adversarial", action="store_true", help="add the patch discriminator (slow on CPU)")
    p.add_argument("--silhouette-erosion", type=int, default=0, metavar="PX",
                   help="mesh model: erode half of the target silhouettes by 1 to PX pixels (robustness to a "
                   "body fitted to a real person; default 0)")
    p.add_argument("--checkpoint-every", type=int, default=250, help="steps between checkpoints (default 250)")
    p.add_argument("--resume", action="store_true", help="continue from OUTPUT and its .state file")
    p.add_argument("--seed", type=int, default=0, help="seed of the data and the training (default 0)")
    p.add_argument("--video", default=None,
                   help="personalisation: fine-tune --init-from on this video of one person (module help above)")
    p.add_argument("--train-fraction", type=float, default=None,
                   help="--video: the share of its frames trained on, from frame 0 (default 0.8); the rest is scored")
    p.add_argument("--video-frames", type=int, default=None,
                   help="--video: tail frames scored against frame 0 (default 64, spread over the tail)")
    p.add_argument("--json", default=None, help="--video: write the generic and personalised scores here as JSON")
    add_threads_argument(p)
    p.add_argument("--no-progress", action="store_true", help="hide progress bars")


def default_crop(domain: str, size: int) -> int:
    """Training crop: half the frame (measured: body, 400 steps on 64 crops reach the PSNR of 400 steps on
    whole 128 frames in 1/8 of the time; faces train well on them too)."""
    return size // 2


def sequence_licences(seqs, *, data_root: str | None) -> dict:
    """The licence record (:func:`motion2video.data.licences.licence_record`) of the captures that posed or
    animated the training sequences, from the ``manifest.csv`` of ``mocap/`` (bodies) or ``face/`` (faces)."""
    from motion2video.data.licences import licence_record
    from motion2video.formats.manifest import read_manifest
    from motion2video.frames.specs import default_data_root

    root = Path(data_root) if data_root is not None else default_data_root()
    manifest_path = root / ("mocap" if seqs.domain == "body" else "face") / "manifest.csv"
    entries = read_manifest(manifest_path) if manifest_path.is_file() else {}
    return licence_record([entries[c].licence if c in entries else None for c in seqs.summary()["clips"]])


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from motion2video.core.errors import InputError
    from motion2video.frames.data import default_cache_dir, load_or_generate
    from motion2video.frames.specs import default_spec
    from motion2video.frames.train import TrainFramesConfig, train_frames

    set_threads(args.threads)
    if args.video is not None:
        return _run_video(args)
    video_only = [name for name, value in (("--train-fraction", args.train_fraction),
                                           ("--video-frames", args.video_frames), ("--json", args.json))
                  if value is not None]
    if video_only:
        raise InputError(f"{', '.join(video_only)}: only with --video")
    if args.domain is None:
        raise InputError("--domain body|face is required (unless fine-tuning on a --video)")
    args.model_kind = args.model_kind or "analogy"
    args.steps = 3000 if args.steps is None else args.steps
    args.lr = 1e-3 if args.lr is None else args.lr
    check_at_least("--steps", args.steps)
    if args.model_kind == "warp" and args.domain != "body":
        raise InputError(f"--model-kind {args.model_kind} makes body frames only (use --domain body)")
    check_at_least("--batch-size", args.batch_size)
    if args.silhouette_erosion < 0 or (args.silhouette_erosion and args.model_kind != "mesh"):
        raise InputError("--silhouette-erosion is a setting of --model-kind mesh (0 or more pixels)")
    output = Path(args.output)
    if output.suffix != ".safetensors":
        raise InputError("the checkpoint name must end in .safetensors", output)
    spec = default_spec(args.domain, "train", args.size, seed=args.seed)
    if args.train_sequences is not None:
        check_at_least("--train-sequences", args.train_sequences)
        spec = replace(spec, num_sequences=args.train_sequences,
                       num_identities=min(spec.num_identities, args.train_sequences))
    crop = default_crop(args.domain, args.size) if args.crop is None else args.crop
    if crop < 0 or crop > args.size or crop % 16:
        raise InputError(f"--crop must be 0 or a multiple of 16 up to --size, got {crop}")
    warp = args.model_kind in ("warp", "mesh")
    edge = args.edge_weight if args.edge_weight is not None else (1.0 if warp else 0.0)
    person = args.person_weight if args.person_weight is not None else (2.0 if warp else 0.0)
    model_config = None  # checked before the data, which may take minutes to render
    if args.model_kind == "mesh":
        from motion2video.frames.data import structure_channels
        from motion2video.frames.mesh_warp import MeshWarpConfig

        if args.flow_correction:
            raise InputError("--model-kind mesh: its flow residual is always on (leave out --flow-correction)")
        net_scale = args.net_scale or max(1, args.size // 64)  # the network at 64 px: 2 at 128, 4 at 256
        if crop % (net_scale * 8):
            raise InputError(f"--crop {crop} must be a multiple of {net_scale * 8} at --net-scale {net_scale}")
        model_config = MeshWarpConfig(domain=args.domain, image_size=args.size,
                                      structure_channels=structure_channels(args.domain),
                                      net_scale=net_scale, sample_mode=args.sample_mode or "bicubic")
        spec = replace(spec, vertices=True)  # the mesh correspondence of every frame
    elif warp:
        from motion2video.frames.data import structure_channels
        from motion2video.frames.warp import WarpGeneratorConfig

        model_config = WarpGeneratorConfig(image_size=args.size, structure_channels=structure_channels("body"),
                                           net_scale=args.net_scale or 4, flow_correction=args.flow_correction,
                                           sample_mode=args.sample_mode or "bilinear")
    elif args.net_scale is not None or args.flow_correction or args.sample_mode is not None:
        raise InputError("--net-scale, --flow-correction and --sample-mode are settings of --model-kind warp or mesh")
    cache = Path(args.cache) if args.cache else default_cache_dir()
    seqs = load_or_generate(spec, cache_dir=cache, data_root=args.data_root, progress=not args.no_progress)
    config = TrainFramesConfig(steps=args.steps, batch_size=args.batch_size, lr=args.lr, crop=crop,
                               adversarial=args.adversarial, checkpoint_every=args.checkpoint_every,
                               seed=args.seed, model_kind=args.model_kind, edge_weight=edge, person_weight=person,
                               silhouette_erosion=args.silhouette_erosion)
    result = train_frames(seqs, output=output, config=config, model_config=model_config, resume=args.resume,
                          progress=not args.no_progress, init_from=args.init_from,
                          extra_metadata={"dataset_spec": spec.key(),
                                          "licences": sequence_licences(seqs, data_root=args.data_root)})
    last = result.history[-1] if result.history else {}
    print(json.dumps({"checkpoint": str(result.path), "steps": result.steps,
                      "wall_s": round(result.wall_s, 1), "total_wall_s": round(result.total_wall_s, 1),
                      "steps_per_second": round(result.steps_per_second, 3),
                      "last_loss": {k: round(v, 5) for k, v in last.items() if k != "step"}}))
    return 0


def _run_video(args: argparse.Namespace) -> int:
    """``--video``: fine-tune ``--init-from`` on the video and score it and the model it started from on the
    video's tail (:mod:`motion2video.evaluation.personalise`)."""
    import sys

    from motion2video.core.atomic import check_output_path, write_json
    from motion2video.core.errors import InputError
    from motion2video.evaluation.personalise import PersonaliseSettings, personalise

    if args.init_from is None:
        raise InputError("--video fine-tunes a trained body generator: give it with --init-from (e.g. "
                         "--init-from frames-body-128)")
    given = {"--domain": args.domain not in (None, "body"), "--model-kind": args.model_kind is not None,
             "--net-scale": args.net_scale is not None, "--flow-correction": args.flow_correction,
             "--sample-mode": args.sample_mode is not None, "--train-sequences": args.train_sequences is not None,
             "--adversarial": args.adversarial, "--cache": args.cache is not None,
             "--silhouette-erosion": args.silhouette_erosion != 0,
             "--data-root": args.data_root is not None}
    ignored = [name for name, yes in given.items() if yes]
    if ignored:
        raise InputError(f"--video fine-tunes the --init-from model as it is, on the video's frames: leave out "
                         f"{', '.join(ignored)}")
    defaults = PersonaliseSettings()
    settings = PersonaliseSettings(
        steps=defaults.steps if args.steps is None else args.steps, batch_size=args.batch_size,
        lr=defaults.lr if args.lr is None else args.lr, crop=defaults.crop if args.crop is None else args.crop,
        edge_weight=defaults.edge_weight if args.edge_weight is None else args.edge_weight,
        person_weight=defaults.person_weight if args.person_weight is None else args.person_weight,
        seed=args.seed, checkpoint_every=args.checkpoint_every,
        train_fraction=defaults.train_fraction if args.train_fraction is None else args.train_fraction,
        targets=defaults.targets if args.video_frames is None else args.video_frames)
    check_at_least("--steps", settings.steps)
    check_at_least("--batch-size", settings.batch_size)
    check_at_least("--video-frames", settings.targets)
    if not 0.0 < settings.train_fraction < 1.0:
        raise InputError(f"--train-fraction must be between 0 and 1, got {settings.train_fraction:g}")
    if settings.crop < 0 or settings.crop % 16:
        raise InputError(f"--crop must be 0 or a multiple of 16 up to the model's size, got {settings.crop}")
    if not settings.lr > 0:
        raise InputError(f"--lr must be > 0, got {settings.lr:g}")
    output = check_output_path(args.output, (".safetensors",))
    if args.json is not None:
        check_output_path(args.json, (".json",))
    if not Path(args.video).is_file():
        raise InputError("no such video file", args.video)
    result = personalise(args.video, init_from=args.init_from, output=output, settings=settings,
                         resume=args.resume, progress=not args.no_progress,
                         note=lambda line: print(f"note: {line}", file=sys.stderr))
    payload = result.to_dict()
    p, g = payload["personalised"], payload["generic"]
    print(json.dumps(payload["train"]))
    print(f"tail of {Path(args.video).name}: frames {payload['train']['tail_start']}..{payload['tail']['frames'][-1]}"
          f" never trained on, {payload['tail']['num_pairs']} pairs against frame 0:")
    def shown(value, digits: int) -> str:
        return "n/a" if value is None else f"{value:.{digits}f}"

    for label, scores in (("generic " + payload["init_from"], g), ("personalised", p)):
        print(f"  {label:<28} l1 {scores['l1']:.4f}  person_psnr {shown(scores['person_psnr'], 2)} dB  "
              f"akd {shown(scores['akd'], 2)} px")
    print(f"  personalised / generic L1: {payload['l1_ratio']:.3f}")
    if args.json:
        write_json(args.json, payload)
        print(f"wrote {args.json}")
    print(f"wrote {result.checkpoint}")
    return 0
