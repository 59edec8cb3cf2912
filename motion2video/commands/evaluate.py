"""`motion2video evaluate`: a model and the three baselines on the same windows (DLow protocol)."""

from __future__ import annotations

import argparse

from motion2video.commands.common import CHARACTER_HELP, add_command, add_threads_argument, check_at_least, set_threads
from motion2video.evaluation.forecasting import ForecastEvalSettings, evaluate_models, rows_table

DESCRIPTION = """\
Evaluate a motion model against the three data-driven baselines on the same windows: APD, ADE, FDE, MMADE,
MMFDE (DLow protocol), pooled over all windows, as the macro average over actions (every action counts once)
and per action (the action class of each clip's manifest label). Prints the three tables; --json writes
{"protocol": {...}, "results": {"<method>": {"ade": .., "fde": .., "mmade": .., "mmfde": .., "apd": ..,
"velocity_ratio": .., "acceleration_ratio": ..}}, "macro": {"<method>": {same keys}}, "per_action":
{"<method>": {"<action>": {same keys, "windows": n}}}}; the ratios say how lively the samples are (mean
absolute velocity / acceleration of all features over the true futures'). Pooled ADE / FDE / APD / MMADE /
MMFDE are the window-weighted means of the per-action ones.
"""

EXAMPLES = """\
examples:
  motion2video evaluate --model mtvae-add --data ../shared/data/mocap --samples 50 --json out/eval.json
  motion2video evaluate --model mtvae-add --model mtvae-add-dlow --model lcpvae --data ../shared/data/mocap \\
      --plot out/ade_per_frame.png
  motion2video evaluate --model runs/cvae.safetensors --data ../shared/data/mocap/cmu/13_10.bvh
  motion2video evaluate --model mtvae-add-face --data ../shared/data/face/livelinkface/S07-001.csv
  motion2video evaluate --model mixture-periodic --model mirror-periodic --data ../shared/data/mocap
  motion2video evaluate --model mixture-periodic --data ../shared/data/mocap --data ../shared/data/bandai --split subjects

Windows: every (observed + future)-frame window, --stride frames apart, of the clips of --split: by default
the checkpoint's held-out test clips plus any clip it has never seen whose subject it did not train or
validate on, and a single file given as --data whole; --recorded-only keeps the recorded test clips only.
Metrics (best of K for ADE/FDE) on root-relative poses, metres (face models: parameter units).

--split subjects tests what training covers, on the corpus of every --data folder: the test clips are whole
performers (the corpus's test subjects and one Bandai-Namco performer per set, skeleton groups 1B and 2C),
whatever split the checkpoints recorded (a checkpoint that trained on one of them is refused). Per action and
macro over the actions the split's training clips perform; each test action no training clip performs (Indian
dance) in its own "unseen action" row outside the macro; and a cross-dataset row, the macro over the held-out
Bandai performers' actions, marked for each model whether it trained on any Bandai-Namco clip.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "evaluate", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--model", required=True, action="append",
                   help="checkpoint path or shipped model name; repeat to compare models on the same windows "
                   "(they must share the layout and data settings; the first one's split picks the windows); "
                   "mirror-periodic, a rule with no weights, is scored in the first trained model's windows and "
                   "statistics (3D body models)")
    p.add_argument("--data", required=True, action="append",
                   help="BVH folder or motion file (face models: .csv / .npz captures); repeat to join mocap folders "
                   "into one corpus (--split subjects: e.g. ../shared/data/mocap and ../shared/data/bandai)")
    p.add_argument("--character", metavar="FILE", default=None, help=CHARACTER_HELP)
    p.add_argument("--samples", type=int, default=50, help="K futures per window (default 50)")
    p.add_argument("--json", default=None, help="write the results as JSON here")
    p.add_argument("--plot", default=None, help="draw ADE per future frame of every model and baseline into this PNG")
    p.add_argument("--stride", type=int, default=16, help="frames between evaluated windows (default 16)")
    p.add_argument("--split", choices=("test", "val", "train", "all", "subjects"), default="test",
                   help="which clips (default test: held-out clips and clips the checkpoint never saw; subjects: "
                   "whole held-out performers, per action with unseen-action and cross-dataset rows, see above)")
    p.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    p.add_argument("--recorded-only", action="store_true",
                   help="only the clips the checkpoint's recorded split names (reproduces results measured on "
                   "the folder it was trained on, e.g. the 72-clip models on the grown folder)")
    p.add_argument("--rigid-bones", action="store_true",
                   help="score 3D body futures with the last observed frame's bone lengths, as sample --rigid-bones "
                   "draws them")
    p.add_argument("--raw-futures", action="store_true",
                   help="score the networks' futures as they come out, without carrying the observed motion into "
                   "their first frames (what sample and synthesize draw)")
    p.add_argument("--extended", action="store_true",
                   help="also report S-MSE, R-MSE and the Parzen conditional log-likelihood (MT-VAE metrics)")
    add_threads_argument(p)


def run(args: argparse.Namespace) -> int:
    set_threads(args.threads)
    check_at_least("--samples", args.samples)
    check_at_least("--stride", args.stride)
    settings = ForecastEvalSettings(models=tuple(args.model), data=tuple(args.data), samples=args.samples,
                                    stride=args.stride, split=args.split, seed=args.seed,
                                    rigid_bones=args.rigid_bones, raw_futures=args.raw_futures,
                                    recorded_only=args.recorded_only, extended=args.extended, json=args.json,
                                    plot=args.plot, character=args.character)
    evaluation = evaluate_models(settings)
    result = evaluation.result
    columns = ("ade", "fde", "mmade", "mmfde", "apd") + (("s_mse", "r_mse", "cll") if args.extended else ())
    print(f"{evaluation.windows} windows from {len(result.protocol['clips'])} clip(s), best of {args.samples}, "
          f"units: {result.protocol['units']}")
    if evaluation.subjects is not None:
        print(f"\nsubject split: actions in training: {', '.join(evaluation.subjects.train_actions)}")
        print(rows_table(evaluation.subjects.rows, ("ade", "fde", "ade_zv", "fde_zv", "apd"),
                         first="row (windows) method"))
        if evaluation.json is not None:
            print(f"wrote {evaluation.json}")
        return 0
    print(result.table(columns))
    actions = result.protocol["actions"]
    print(f"\nmacro average over {len(actions)} action(s) (each action counts once):")
    print(result.macro_table(columns))
    print("\nper action (windows):")
    print(result.per_action_table(columns))
    for out in (evaluation.json, evaluation.plot):
        if out is not None:
            print(f"wrote {out}")
    return 0

