"""`motion2video evaluate-frames`: PSNR / SSIM of a frame generator and the baselines on held-out pairs."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from motion2video.commands.common import add_command, check_at_least

HELP = "score a frame generator against copy-reference and limb-warp on held-out pairs"

DESCRIPTION = """\
Render (or reuse from the cache) the held-out split (held-out identities and clips) for the model's domain and
size, and report whole-frame PSNR and SSIM (scikit-image) and person metrics (PSNR, SSIM and sharpness ratio
inside the target's silhouette, PSNR and sharpness where the person moved) for the generator, copy-reference,
limb-warp and the previous generator on the same pairs.
"""

EXAMPLES = """\
examples:
  motion2video evaluate-frames --model frames-body-128 --json out/eval_frames_body.json
  motion2video evaluate-frames --model out/frames-face-128.safetensors --contact-sheet out/face_sheet.png
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
    loaded = load_frame_model(args.model)
    cfg = loaded.config
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
        other = load_frame_model(name)
        if other.path.resolve() == loaded.path.resolve():
            continue
        same = (other.config.domain, other.config.image_size) == (cfg.domain, cfg.image_size)
        if not same and not explicit:  # the default baseline only goes with models of its size
            continue
        if not same:
            raise InputError(f"baseline model is {other.config.domain}/{other.config.image_size}, the evaluated "
                             f"model {cfg.domain}/{cfg.image_size}", other.path)
        baselines[other.path.name.removesuffix(".safetensors")] = other.model
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
