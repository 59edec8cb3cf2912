"""Every body model per action and as the macro average over actions, on the same held-out
test windows, as best-of-K ADE / FDE ratios to zero-velocity.

    python scripts/make_results_per_action.py                       # the 5-minute models (git) and the shipped ones
    python scripts/make_results_per_action.py --model new=runs/new.safetensors    # add a model
    python scripts/make_results_per_action.py --no-defaults --model a=PATH --model b=PATH

Each ``--model LABEL=SPEC`` is a shipped name, a checkpoint path, or ``git:REV:PATH`` (a checkpoint file of a
git revision of this repository, written to --cache first). Without ``--no-defaults`` the 5-minute models
(the 72-clip checkpoints of git :data:`OLD_REV`) and the shipped corpus models come first. The windows are
the held-out test windows of ``--windows-from``'s recorded split (default: the shipped ``mtvae-add``, the
corpus's pinned test subjects), the same for every model; each model reads them with its own normalisation.
A model whose recorded training split holds a clip of those windows is scored anyway and flagged.

Writes the section between ``<!-- per-action:begin -->`` and ``<!-- per-action:end -->`` of
docs/results.md and the raw numbers (``motion2video evaluate``'s JSON: pooled, per_action, macro) to --json.
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2video.core.errors import InputError  # noqa: E402
from motion2video.models.checkpoint import baseline_bundle, load_model  # noqa: E402
from motion2video.core.atomic import write_json, write_section  # noqa: E402
from motion2video.data.dataset import DEFAULT_MOCAP, WindowSet, build_dataset  # noqa: E402
from motion2video.evaluation.forecasting import EvalProtocol, evaluate_bundles  # noqa: E402

BEGIN, END = "<!-- per-action:begin -->", "<!-- per-action:end -->"
OLD_REV = "805c753"  # the last commit whose motion2video/weights held the 72-clip (5-minute) models
OLD = ("mtvae-add", "lcpvae", "behavior")
SHIPPED = ("mtvae-add", "mtvae-add-dlow", "lcpvae", "behavior", "mixer-cvae-dlow", "mixture-dlow", "mixture-periodic")
BASELINE = "zero-velocity"


FIVE_MINUTE = ROOT / "out" / "five_minute"  # scripts/retrain_five_minute.py writes the retrained models here


def default_models(rev: str = OLD_REV, retrained: Path = FIVE_MINUTE) -> list[tuple[str, str]]:
    """(label, spec): the 5-minute models, then the shipped models. The 5-minute checkpoints of git ``rev`` follow
    canonical skeleton version 1, which this motion2video refuses; their recipe retrained on today's joints
    (``scripts/retrain_five_minute.py``) stands in for each one found in ``retrained``."""
    old = []
    for n in OLD:
        mine = retrained / f"{n}.safetensors"
        old.append((f"{n} (5 min)", str(mine) if mine.is_file() else f"git:{rev}:motion2video/weights/{n}.safetensors"))
    return old + [(n, n) for n in SHIPPED]


def parse_model(value: str) -> tuple[str, str]:
    """``LABEL=SPEC`` -> (label, spec)."""
    label, sep, spec = value.partition("=")
    if not sep or not label or not spec:
        raise SystemExit(f"--model wants LABEL=PATH (or LABEL=git:REV:PATH, or LABEL=shipped-name), got {value!r}")
    return label, spec


def resolve(spec: str, cache: Path) -> str:
    """A checkpoint path or shipped name for ``spec``; ``git:REV:PATH`` is written from git into ``cache``."""
    if not spec.startswith("git:"):
        return spec
    _, rev, path = spec.split(":", 2)
    out = cache / rev / path
    if not out.is_file():
        blob = subprocess.run(["git", "show", f"{rev}:{path}"], cwd=ROOT, capture_output=True)
        if blob.returncode != 0:
            raise SystemExit(f"{spec}: git show failed: {blob.stderr.decode().strip()}")
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_bytes(blob.stdout)
    return str(out)


def subset(windows: WindowSet, idx: np.ndarray) -> WindowSet:
    """The windows at indices ``idx``."""
    frames = windows.frames
    if frames is not None:
        frames = dataclasses.replace(frames, origin=frames.origin[idx], angle=frames.angle[idx])
    return dataclasses.replace(windows, features=windows.features[idx], raw=windows.raw[idx], frames=frames,
                               clip_names=tuple(windows.clip_names[i] for i in idx), starts=windows.starts[idx],
                               labels=tuple(windows.labels[i] for i in idx))


def ratios(result: dict, label: str) -> dict:
    """ADE / FDE ratios to zero-velocity of ``label``, per action, macro and pooled, from evaluate's JSON."""
    zv_pa, pa = result["per_action"][BASELINE], result["per_action"][label]
    out = {a: {"ade": pa[a]["ade"] / zv_pa[a]["ade"], "fde": pa[a]["fde"] / zv_pa[a]["fde"]} for a in pa}
    out["macro"] = {k: float(np.mean([out[a][k] for a in pa])) for k in ("ade", "fde")}
    out["pooled"] = {k: result["results"][label][k] / result["results"][BASELINE][k] for k in ("ade", "fde")}
    return out


def render(result: dict, labels: list[str], *, command: str, seconds: float, seen: dict, samples: int,
           stride: int, dropped: int, kept: bool, validated: list[str]) -> str:
    table = {label: ratios(result, label) for label in labels}
    counts = result["protocol"]["actions"]
    zv = result["per_action"][BASELINE]
    n = result["protocol"]["windows"]
    head = "| action | windows | zero-velocity ADE / FDE (m) | " + " | ".join(labels) + " |"
    lines = [head, "| --- | ---: | ---: | " + " | ".join("---:" for _ in labels) + " |"]

    def cells(key: str) -> str:
        return " | ".join(f"{table[m][key]['ade']:.2f} / {table[m][key]['fde']:.2f}" for m in labels)

    for action, count in counts.items():
        lines.append(f"| {action} | {count} | {zv[action]['ade']:.3f} / {zv[action]['fde']:.3f} | {cells(action)} |")
    zvm = result["macro"][BASELINE]
    zvp = result["results"][BASELINE]
    lines.append(f"| **macro** (each action once) | {len(counts)} actions | {zvm['ade']:.3f} / {zvm['fde']:.3f} | "
                 f"{cells('macro')} |")
    lines.append(f"| pooled (each window once) | {n} | {zvp['ade']:.3f} / {zvp['fde']:.3f} | {cells('pooled')} |")
    best = {a: min(labels, key=lambda m: table[m][a]["ade"]) for a in list(counts) + ["macro"]}
    flagged = sorted({c for clips in seen.values() for c in clips})
    who = [m for m, clips in seen.items() if clips]
    if not flagged:
        check = "No model's recorded training split holds a clip of the test split."
    elif kept:
        check = (f"**Not all held out**: {', '.join(f'`{m}`' for m in who)} trained on {len(flagged)} of these "
                 f"clips ({', '.join(flagged)}); their windows are included (`--keep-trained`).")
    else:
        check = (f"{', '.join(f'`{m}`' for m in who)} trained on {len(flagged)} clips of the corpus's test split "
                 f"({', '.join(flagged)}: CMU subjects the corpus split holds out, but the 72-clip split trained "
                 f"on); their {dropped} windows are left out, so every window here is held out for every model.")
    text = [
        "### Per action and macro over actions, the 5-minute models against the corpus models",
        "",
        f"Generated by `{command}` ({seconds / 60:.1f} min, 1 thread). {n} held-out test windows (16 observed + 48 "
        f"future frames at 25 fps, {stride} frames apart) from {len(result['protocol']['clips'])} clips of the "
        "corpus's pinned test subjects (CMU 2, 131, 140, 94 Indian dance and the clips linked to them), the same "
        "windows for every model; each cell is best-of-"
        f"{samples} ADE / FDE as a ratio to zero-velocity on the same windows (lower is better, 1.00 = standing "
        "still). `macro` is the unweighted mean of the per-action ratios, `pooled` the ratio of the means over all "
        "windows (what one pooled average reports). '5 min' = the 72-clip models of git "
        f"{OLD_REV}, retrained on canonical skeleton version 2 with their recorded split, configs and steps "
        "(`python scripts/retrain_five_minute.py`; the original checkpoints follow version 1 and are refused), the "
        "others the checkpoints shipped now. Futures continue the observed motion for every learned model "
        "(`stages.sampling.continue_observed`). Actions are the coarse classes "
        "of the manifest's action column (`motion2video.data.corpus.action_class`).",
        "",
        *lines,
        "",
        "Lowest ADE ratio per action: " + "; ".join(f"{a}: `{m}`" for a, m in best.items()) + ".",
        "",
        "Held-out check: " + check + (
            f" Kept: {len(validated)} clips some model's recorded split used for validation ({', '.join(validated)}; "
            "model selection, not training)." if validated else ""),
        "",
        "Per action in the JSON of `motion2video evaluate --model NAME --data ../shared/data/mocap --json out.json` "
        "(`per_action`, `macro`).",
    ]
    return "\n".join(text)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", action="append", default=[], help="LABEL=SPEC (repeatable; module docstring)")
    p.add_argument("--no-defaults", action="store_true", help="only the --model models")
    p.add_argument("--old-rev", default=OLD_REV, help="git revision of the 5-minute models")
    p.add_argument("--windows-from", default="mtvae-add", help="checkpoint whose recorded test split gives the windows")
    p.add_argument("--data", default=str(DEFAULT_MOCAP))
    p.add_argument("--samples", type=int, default=50)
    p.add_argument("--stride", type=int, default=16)
    p.add_argument("--every", type=int, default=1, help="keep every n-th window (timing runs)")
    p.add_argument("--keep-trained", action="store_true",
                   help="also score the test windows of clips some model's recorded split trained on (flagged)")
    p.add_argument("--cache", default="/tmp/motion2video-git-weights", help="where git:REV:PATH files are written")
    p.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    p.add_argument("--json", default=str(ROOT / "out" / "results_per_action.json"))
    p.add_argument("--dry-run", action="store_true", help="print the section instead of writing the doc")
    args = p.parse_args(argv)
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    models = ([] if args.no_defaults else default_models(args.old_rev)) + [parse_model(v) for v in args.model]
    if not models:
        raise SystemExit("no models: give --model LABEL=PATH")
    bundles, kept = [], []
    for label, spec in models:
        try:
            bundles.append(load_model(resolve(spec, Path(args.cache))))
            kept.append((label, spec))
        except InputError as err:  # e.g. the 5-minute models: trained on canonical skeleton version 1
            print(f"note: {label} left out: {err}", file=sys.stderr)
    models = kept
    ref = load_model(args.windows_from)
    for (label, _), b in zip(models, bundles):
        if (b.data_config.observed, b.data_config.future, b.data_config.fps, b.layout.kind) != \
                (ref.data_config.observed, ref.data_config.future, ref.data_config.fps, ref.layout.kind):
            raise SystemExit(f"{label}: other windows ({b.data_config}) than {args.windows_from} ({ref.data_config})")
    dataset = build_dataset(args.data, ref.data_config, split=ref.meta.split, stats=ref.stats)
    windows = dataset.windows("test", stride=args.stride)
    clips = set(windows.clip_names)
    seen = {label: sorted(clips & set(b.meta.split.train)) if b.meta.split else []
            for (label, _), b in zip(models, bundles)}
    trained = sorted(set().union(*seen.values()))
    validated = sorted(set().union(*[clips & set(b.meta.split.val) for b in bundles if b.meta.split]))
    dropped = 0
    if trained and not args.keep_trained:  # only windows that no model trained on
        keep = np.flatnonzero(~np.isin(np.asarray(windows.clip_names), trained))
        dropped = len(windows) - len(keep)
        windows = subset(windows, keep)
    if args.every > 1:
        windows = subset(windows, np.arange(0, len(windows), args.every))
    clips = set(windows.clip_names)
    protocol = EvalProtocol(samples=args.samples, stride=args.stride, split="test", seed=0)
    print(f"{len(windows)} windows from {len(clips)} clips; {len(bundles)} models, best of {args.samples}", flush=True)
    merged: dict = {}
    for (label, _), b in zip(models, bundles):
        t = time.perf_counter()
        r = evaluate_bundles([b], windows, protocol=protocol).to_json()
        for key in ("results", "per_action", "macro", "ade_per_frame"):
            merged.setdefault(key, {})[label] = r[key][b.label]
        merged["protocol"] = r["protocol"]
        print(f"{label}: ADE {r['results'][b.label]['ade']:.3f} m in {time.perf_counter() - t:.0f} s", flush=True)
    r = evaluate_bundles([baseline_bundle(BASELINE, ref.data_config, stats=ref.stats)], windows,
                         protocol=protocol).to_json()
    for key in ("results", "per_action", "macro", "ade_per_frame"):
        merged[key][BASELINE] = r[key][BASELINE]
    seconds = time.perf_counter() - t0
    labels = [label for label, _ in models]
    command = "python scripts/make_results_per_action.py" + "".join(
        f" --{k.replace('_', '-')} {v}" for k, v in (("samples", args.samples), ("stride", args.stride),
                                                       ("every", args.every)) if v != p.get_default(k))
    command += "".join(f" --model '{v}'" for v in args.model) + (" --no-defaults" if args.no_defaults else "")
    section = render(merged, labels, command=command, seconds=seconds, seen=seen, samples=args.samples,
                     stride=args.stride, dropped=dropped, kept=args.keep_trained, validated=validated)
    merged["ratios"] = {label: ratios(merged, label) for label in labels}
    merged["trained_on_test_clips"] = seen
    merged["windows_left_out"] = dropped
    merged["validation_clips_kept"] = validated
    merged["seconds"] = seconds
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    write_json(args.json, merged)
    if args.dry_run:
        print(section)
    else:
        write_section(args.doc, BEGIN, END, section)
        print(f"wrote {args.doc}")
    print(f"wrote {args.json} ({seconds / 60:.1f} min)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
