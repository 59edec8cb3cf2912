"""`motion2video evaluate`: a model and the three baselines on the same windows (DLow protocol)."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from motion2video.core.atomic import write_json
from motion2video.commands.common import CHARACTER_HELP, add_command, add_threads_argument, check_at_least, set_threads
from motion2video.core.errors import InputError

HELP = "score a motion model and the zero-velocity / last-step / sequence-motion baselines"

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
  motion2video evaluate --model mixture-periodic --data ../shared/data/mocap --data ../shared/data/bandai \
      --split subjects --stride 64

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
    p = add_command(sub, "evaluate", run, help=HELP, description=DESCRIPTION, examples=EXAMPLES)
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
    from motion2video.models.checkpoint import baseline_bundle, load_model
    from motion2video.data.dataset import build_dataset
    from motion2video.evaluation.forecasting import EvalProtocol, evaluate_bundles
    from motion2video.models.baselines import BASELINES
    from motion2video.models.periodic import RULES

    set_threads(args.threads)
    check_at_least("--samples", args.samples)
    check_at_least("--stride", args.stride)
    for option in ("json", "plot"):
        target = getattr(args, option)
        if target is not None:
            Path(target).parent.mkdir(parents=True, exist_ok=True)
    if args.plot is not None and not args.plot.lower().endswith(".png"):
        raise InputError("--plot writes a .png file", args.plot)
    rules = [name for name in args.model if name in RULES]
    learned = [name for name in args.model if name not in RULES]
    if not learned:
        raise InputError(f"{rules[0]} is a rule: name a trained model too, whose windows, statistics and split it "
                         "is scored on")
    models = [load_model(name) for name in learned]
    bundle = models[0]
    for other in models[1:]:  # the split rule aside (the first model's split, or --split subjects, picks the clips)
        if dataclasses.replace(other.data_config, held_out="corpus") != dataclasses.replace(bundle.data_config,
                                                                                           held_out="corpus"):
            raise InputError(f"{other.label} was trained with other data settings than {bundle.label}: "
                             "compare models of one layout and window length", other.path)
    names = [m.label for m in models]
    if len(set(names)) != len(names):
        raise InputError(f"two models share the name {names!r}: give checkpoints with distinct file names")
    cfg = bundle.data_config
    if rules and cfg.feature_layout.kind != "body3d":
        raise InputError(f"{rules[0]} works on 3D body motion, not the {cfg.feature_layout.kind} layout of "
                         f"{bundle.label}")
    data = args.data[0] if len(args.data) == 1 else args.data
    if args.split == "subjects":
        if cfg.feature_layout.kind != "body3d":
            raise InputError(f"--split subjects holds out body-motion performers, not the {cfg.feature_layout.kind} "
                             f"layout of {bundle.label}")
        dataset, windows, train_actions = subject_windows(data, cfg, models, stride=args.stride,
                                                          character=args.character)
    else:
        dataset = build_dataset(data, cfg, split=bundle.meta.split, stats=bundle.stats,
                                recorded_only=args.recorded_only, character=args.character)
        windows = dataset.windows(args.split, stride=args.stride)
    if len(windows) == 0:
        longest = max((c.num_frames for c in dataset.clips_of(args.split)), default=0)
        raise InputError(f"no clip of the {args.split} split is long enough: a window needs {cfg.length} frames "
                         f"at {cfg.fps:g} fps ({cfg.observed} observed + {cfg.future} future), the longest has "
                         f"{longest}", args.data)
    bundles = models + [baseline_bundle(name, cfg, stats=bundle.stats) for name in tuple(rules) + BASELINES]
    protocol = EvalProtocol(samples=args.samples, stride=args.stride, split=args.split, seed=args.seed,
                            rigid_bones=args.rigid_bones, continue_motion=not args.raw_futures)
    val = dataset.windows("val", stride=args.stride) if args.extended else None
    result = evaluate_bundles(bundles, windows, protocol=protocol, extended=args.extended, val_windows=val)
    result.protocol["checkpoint"] = str(bundle.path)
    result.protocol["data"] = " + ".join(args.data)
    columns = ("ade", "fde", "mmade", "mmfde", "apd") + (("s_mse", "r_mse", "cll") if args.extended else ())
    print(f"{len(windows)} windows from {len(result.protocol['clips'])} clip(s), best of {args.samples}, "
          f"units: {result.protocol['units']}")
    if args.split == "subjects":
        report = print_subject_split(result, models, train_actions)
        if args.json is not None:
            print(f"wrote {write_json(args.json, {**result.to_json(), 'subjects': report})}")
        return 0
    print(result.table(columns))
    actions = result.protocol["actions"]
    print(f"\nmacro average over {len(actions)} action(s) (each action counts once):")
    print(result.macro_table(columns))
    print("\nper action (windows):")
    print(result.per_action_table(columns))
    if args.json is not None:
        out = write_json(args.json, result.to_json())
        print(f"wrote {out}")
    if args.plot is not None:
        from motion2video.evaluation.plots import plot_ade_per_frame

        out = plot_ade_per_frame(result.ade_per_frame, args.plot, fps=cfg.fps, units=result.protocol["units"].split(" (")[0],
                                 best_of=args.samples,
                                 title=f"{len(windows)} {args.split} windows from {len(result.protocol['clips'])} clips")
        print(f"wrote {out}")
    return 0


def subject_windows(data, cfg, models, *, stride: int, character: str | None):
    """The subject split's test windows (labels ``"action @ family"``, :func:`~motion2video.evaluation.per_action.family_key`),
    its dataset and the actions its training clips perform. Raises InputError when a model trained on a test clip."""
    from motion2video.data.corpus import BANDAI_SOURCES, source_of
    from motion2video.data.dataset import build_dataset
    from motion2video.evaluation.per_action import family_key

    bundle = models[0]
    dataset = build_dataset(data, dataclasses.replace(cfg, held_out="subjects"), stats=bundle.stats,
                            character=character)
    test = set(dataset.split.test)
    for model in models:
        if model.meta.split is not None:
            seen = test & (set(model.meta.split.train) | set(model.meta.split.val))
            if seen:
                raise InputError(f"it trained on {len(seen)} clip(s) the subject split holds out (e.g. "
                                 f"{sorted(seen)[0]}): score it with its own --split test", model.path)
    windows = dataset.windows("test", stride=stride)
    windows.labels = tuple(family_key(label, "bandai" if source_of(name) in BANDAI_SOURCES else "mocap")
                           for label, name in zip(windows.labels, windows.clip_names))
    train_actions = {c.label or "unlabelled" for c in dataset.clips_of("train")}
    return dataset, windows, train_actions


def trained_on_bandai(bundle) -> bool:
    """Whether a model's recorded training clips include any Bandai-Namco clip (False for rules and baselines)."""
    from motion2video.data.corpus import BANDAI_SOURCES, source_of

    split = bundle.meta.split
    return split is not None and any(source_of(n) in BANDAI_SOURCES for n in split.train)


def print_subject_split(result, models, train_actions: set[str]) -> dict:
    """Print the subject split's tables (per action, macro, unseen actions, cross-dataset) with ADE / FDE over
    zero-velocity's; returns them as a JSON-able dict."""
    from motion2video.evaluation.forecasting import rows_table
    from motion2video.evaluation.per_action import COUNT_KEY, subject_split_report

    report = {m: subject_split_report(rows, train_actions) for m, rows in result.per_action.items()}
    bandai = {m.label: trained_on_bandai(m) for m in models}
    zv = report.get("zero-velocity")
    columns = ("ade", "fde", "ade_zv", "fde_zv", "apd")

    def with_ratio(row: dict, ref: dict | None) -> dict:
        if not row or ref is None:
            return dict(row)
        return {**row, "ade_zv": row["ade"] / ref["ade"], "fde_zv": row["fde"] / ref["fde"]}

    rows = {}
    for part in ("per_action", "unseen"):
        for action in next(iter(report.values()))[part]:
            for m, r in report.items():
                row = r[part][action]
                tag = "unseen action: " if part == "unseen" else ""
                rows[f"{tag}{action} ({row[COUNT_KEY]}) {m}"] = with_ratio(row, zv[part][action] if zv else None)
    for m, r in report.items():
        rows[f"macro over {len(r['per_action'])} actions {m}"] = with_ratio(r["macro"], zv["macro"] if zv else None)
    for m, r in report.items():
        if r["cross_dataset"] is not None:
            note = "" if m not in bandai else (" (trained with Bandai)" if bandai[m] else " (trained without Bandai)")
            rows[f"cross-dataset: Bandai held-out ({r['cross_dataset'][COUNT_KEY]}) {m}{note}"] = with_ratio(
                r["cross_dataset"], zv["cross_dataset"] if zv else None)
    print(f"\nsubject split: actions in training: {', '.join(sorted(train_actions))}")
    print(rows_table(rows, columns, first="row (windows) method"))
    return {"report": report, "trained_on_bandai": bandai, "train_actions": sorted(train_actions)}
