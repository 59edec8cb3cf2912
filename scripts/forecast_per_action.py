"""Per-action best-of-K scores of forecasting checkpoints on their held-out windows.

For each checkpoint and the zero-velocity / last-step baselines, on the same windows (``evaluate``'s protocol:
the checkpoint's split and statistics, 16-frame stride, K samples, seed 0, root-relative joints in metres):
best-of-K ADE / FDE per action and their ratios to zero-velocity, the macro average of the ratios over actions,
the pooled numbers, the first future frame's best-of-K error, APD and the velocity / acceleration ratios.

    python scripts/forecast_per_action.py --model mixer-cvae-dlow --data ../shared/data/mocap \
        --json out/mixer-cvae-dlow.per_action.json

(``motion2video evaluate --json`` gets ``per_action`` / ``macro`` of its own now; this script
is what the card of mixer-dct, shipped until 2026-11-27, computed its per-action table with.)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def per_action_scores(bundles, windows, *, samples: int, seed: int) -> dict:
    """{label: {"pooled": {...}, "per_action": {action: {...}}, "macro": {...}}} for bundles on windows."""
    from motion2video.evaluation import metrics as M
    from motion2video.data.windows import metric_vectors
    from motion2video.stages.sampling import sample_futures

    to = windows.observed
    layout = bundles[0].layout
    gt = metric_vectors(windows.raw[:, to:], layout)  # (N, Tf, 48)
    labels = np.array([lab or "unlabelled" for lab in windows.labels])
    actions = sorted(set(labels))
    scores, errors = {}, {}
    for b in bundles:
        s = sample_futures(b.model, windows.obs, num_samples=samples, horizon=gt.shape[1], seed=seed)
        raw = b.stats.denormalize(s)  # (N, K, Tf, F)
        pred = metric_vectors(raw, layout)
        err = np.linalg.norm(pred - gt[:, None], axis=-1)  # (N, K, Tf)
        errors[b.label] = {"ade": err.mean(-1).min(1), "fde": err[..., -1].min(1), "first": err[..., 0].min(1)}
        (v, a), (v_true, a_true) = M.liveliness(raw), M.liveliness(windows.raw[:, to:])
        scores[b.label] = {"apd": float(M.apd(pred)), "velocity_ratio": float(v / v_true),
                           "acceleration_ratio": float(a / a_true)}
    zv = errors["zero-velocity"]
    for label, e in errors.items():
        row = scores[label]
        row["pooled"] = {k: float(e[k].mean()) for k in ("ade", "fde", "first")}
        row["pooled"].update(ade_ratio=row["pooled"]["ade"] / float(zv["ade"].mean()),
                             fde_ratio=row["pooled"]["fde"] / float(zv["fde"].mean()))
        row["per_action"] = {}
        for act in actions:
            i = labels == act
            row["per_action"][act] = {"windows": int(i.sum()), "ade": float(e["ade"][i].mean()),
                                      "fde": float(e["fde"][i].mean()),
                                      "ade_ratio": float(e["ade"][i].mean() / zv["ade"][i].mean()),
                                      "fde_ratio": float(e["fde"][i].mean() / zv["fde"][i].mean())}
        row["macro"] = {k: float(np.mean([r[k] for r in row["per_action"].values()]))
                        for k in ("ade", "fde", "ade_ratio", "fde_ratio")}
    return scores


def markdown(scores: dict) -> str:
    """One table: rows = actions + macro + pooled, columns = ADE/FDE ratio per method."""
    names = list(scores)
    actions = list(next(iter(scores.values()))["per_action"])
    head = "| action | windows | " + " | ".join(f"{n} ADE / FDE (x zero-velocity)" for n in names) + " |"
    lines = [head, "|" + "---|" * (2 + len(names))]
    first = scores[names[0]]
    for act in actions:
        cells = [f"{scores[n]['per_action'][act]['ade']:.3f} / {scores[n]['per_action'][act]['fde']:.3f} m "
                 f"({scores[n]['per_action'][act]['ade_ratio']:.2f}x / {scores[n]['per_action'][act]['fde_ratio']:.2f}x)"
                 for n in names]
        lines.append(f"| {act} | {first['per_action'][act]['windows']} | " + " | ".join(cells) + " |")
    lines.append("| **macro over actions** | | " + " | ".join(
        f"{scores[n]['macro']['ade_ratio']:.2f}x / {scores[n]['macro']['fde_ratio']:.2f}x" for n in names) + " |")
    lines.append("| pooled | | " + " | ".join(
        f"{scores[n]['pooled']['ade']:.3f} / {scores[n]['pooled']['fde']:.3f} m "
        f"({scores[n]['pooled']['ade_ratio']:.2f}x / {scores[n]['pooled']['fde_ratio']:.2f}x)" for n in names) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--model", action="append", required=True, help="checkpoint path or shipped name (repeatable)")
    p.add_argument("--data", default=None, help="mocap folder (default: ../shared/data/mocap)")
    p.add_argument("--split", default="test", choices=("test", "val"))
    p.add_argument("--samples", type=int, default=50)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None, help="write the scores here")
    args = p.parse_args(argv)

    import torch

    from motion2video.models.checkpoint import baseline_bundle, load_model
    from motion2video.core.atomic import write_json
    from motion2video.data.dataset import DEFAULT_MOCAP, build_dataset

    torch.set_num_threads(1)
    bundles = [load_model(m) for m in args.model]
    ref = bundles[0]
    dataset = build_dataset(args.data or DEFAULT_MOCAP, ref.data_config, split=ref.meta.split, stats=ref.stats,
                            recorded_only=True)
    windows = dataset.windows(args.split, stride=16)
    bundles += [baseline_bundle(n, ref.data_config, stats=ref.stats) for n in ("zero-velocity", "last-step")]
    scores = per_action_scores(bundles, windows, samples=args.samples, seed=args.seed)
    print(f"{len(windows)} {args.split} windows, best of {args.samples}")
    print(markdown(scores))
    for name, row in scores.items():
        print(f"{name}: APD {row['apd']:.2f} m, first future frame {row['pooled']['first']:.4f} m, velocity "
              f"{row['velocity_ratio']:.2f}x, acceleration {row['acceleration_ratio']:.2f}x of the truth")
    if args.json:
        write_json(Path(args.json), {"split": args.split, "windows": len(windows), "samples": args.samples,
                                     "scores": scores})
    return 0


if __name__ == "__main__":
    sys.exit(main())
