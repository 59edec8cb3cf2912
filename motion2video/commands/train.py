"""`motion2video train`: train a motion model on a folder of BVH files (or face captures)."""

from __future__ import annotations

import argparse

from motion2video.apps.train import LAYOUTS, MotionTrainingSettings, train_motion_model
from motion2video.commands.common import CHARACTER_HELP, add_command, add_threads_argument, check_at_least, set_threads

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
    p = add_command(sub, "train", run, description=DESCRIPTION, examples=EXAMPLES)
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
    p.add_argument("--layout", choices=LAYOUTS, default="auto",
                   help="feature layout; auto: face for a folder of .csv face captures, else body3d")
    p.add_argument("--resume", action="store_true", help="continue from OUTPUT's last periodic checkpoint")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_threads_argument(p)


def run(args: argparse.Namespace) -> int:
    set_threads(args.threads)
    if args.steps is not None:
        check_at_least("--steps", args.steps)
    settings = MotionTrainingSettings(model=args.model, data=tuple(args.data), output=args.output, config=args.config,
                                      base=args.base, steps=args.steps, seed=args.seed, layout=args.layout,
                                      resume=args.resume, progress=not args.no_progress, character=args.character)
    result = train_motion_model(settings)
    val = "n/a" if result.val_loss is None else f"{result.val_loss:.4g}"
    print(f"wrote {result.path} ({result.steps} steps, {result.wall_time_s:.1f} s, "
          f"train loss {result.train_loss:.4g}, val loss {val})")
    return 0
