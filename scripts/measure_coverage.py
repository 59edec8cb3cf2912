"""How far more futures of the same sampler go: best of 50, 100 and 200, and the frame-wise bound.

    python scripts/measure_coverage.py --model mixture-periodic --split test --json out/coverage_test.json

For the windows of ``--split`` (the checkpoint's recorded split, stride 16, as ``motion2video evaluate``), draws
``--draws`` independent sets of 50 futures (seeds 0, 1, ...) and scores, per action and as the macro average over
actions, ratio to zero-velocity on the same windows:

- best of 50 (seed 0 alone: what ``evaluate`` reports), of 100 (seeds 0-1) and of 200 (seeds 0-3);
- the frame-wise bound of the first 50 and of all of them (:func:`motion2video.evaluation.metrics.
  framewise_oracle_ade_per_window`: each frame from whichever future is closest there). No way of re-ordering,
  re-selecting or stitching those futures has a lower ADE.

A rule without noise (``mirror-periodic`` inside ``mixture-periodic``) draws the same futures in every set, so the
extra sets add only the learned samplers' futures. About 25 s per draw on one thread for the test split.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2video.core.atomic import write_json  # noqa: E402
from motion2video.data.dataset import DEFAULT_MOCAP, build_dataset  # noqa: E402
from motion2video.data.windows import metric_vectors  # noqa: E402
from motion2video.evaluation import metrics as M  # noqa: E402
from motion2video.evaluation.per_action import group_by_action, macro_average, per_action_means  # noqa: E402
from motion2video.models.checkpoint import load_model  # noqa: E402
from motion2video.stages.sampling import sample_futures  # noqa: E402

PER_DRAW = 50


def ratio_rows(per_window: dict[str, np.ndarray], zero: dict[str, np.ndarray], labels) -> dict:
    """Per action and macro: each metric's mean over an action's windows divided by zero-velocity's.

    per_window / zero: metric name -> (N,) values ("ade", "fde"); the ratio of "oracle_ade" is to zero's "ade".
    """
    groups = group_by_action(labels)
    model, base = per_action_means(per_window, groups), per_action_means(zero, groups)
    ratios = {}
    for a in groups:
        ratios[a] = {k: model[a][k] / base[a]["fde" if k == "fde" else "ade"] for k in per_window}
        ratios[a]["windows"] = model[a]["windows"]
    return {"per_action": ratios, "macro": macro_average(ratios)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--model", default="mixture-periodic", help="checkpoint path or shipped name")
    p.add_argument("--data", default=None, help="mocap folder (default: ../shared/data/mocap)")
    p.add_argument("--split", default="test", choices=("test", "val"))
    p.add_argument("--draws", type=int, default=4, help="independent sets of 50 futures (default 4: best of 200)")
    p.add_argument("--json", default=None)
    args = p.parse_args(argv)
    torch.set_num_threads(1)
    t0 = time.time()

    bundle = load_model(args.model)
    dataset = build_dataset(args.data or DEFAULT_MOCAP, bundle.data_config, split=bundle.meta.split,
                            stats=bundle.stats, recorded_only=True)
    windows = dataset.windows(args.split, stride=16)
    to = windows.observed
    truth = metric_vectors(windows.raw[:, to:], bundle.layout)  # (N, T, 48)
    last = metric_vectors(windows.raw[:, to - 1], bundle.layout)  # (N, 48)
    zero_err = np.linalg.norm(last[:, None] - truth, axis=-1)  # (N, T)
    zero = {"ade": zero_err.mean(1), "fde": zero_err[:, -1]}
    draws = []
    for seed in range(args.draws):
        s = sample_futures(bundle.model, windows.obs, num_samples=PER_DRAW, horizon=truth.shape[1], seed=seed)
        draws.append(metric_vectors(bundle.stats.denormalize(s), bundle.layout).astype(np.float32))

    rows = {}
    for n in sorted({1, min(2, args.draws), args.draws}):
        pred = np.concatenate(draws[:n], axis=1)  # (N, 50 n, T, 48)
        per_window = {"ade": M.ade_per_window(pred, truth), "fde": M.fde_per_window(pred, truth),
                      "oracle_ade": M.framewise_oracle_ade_per_window(pred, truth)}
        rows[f"best of {PER_DRAW * n}"] = ratio_rows(per_window, zero, windows.labels)

    actions = list(next(iter(rows.values()))["per_action"])
    print(f"{args.model}, {len(windows)} {args.split} windows; ratio to zero-velocity, ADE / FDE "
          f"(frame-wise bound of the ADE); {time.time() - t0:.0f} s")
    print("| futures | " + " | ".join(f"{a} ({rows[next(iter(rows))]['per_action'][a]['windows']})" for a in actions)
          + " | macro |")
    print("|---|" + "---:|" * (len(actions) + 1))
    for name, r in rows.items():
        cells = [r["per_action"][a] for a in actions] + [r["macro"]]
        print(f"| {name} | " + " | ".join(f"{c['ade']:.3f} / {c['fde']:.3f} ({c['oracle_ade']:.3f})" for c in cells)
              + " |")
    if args.json:
        write_json(Path(args.json), {"model": args.model, "split": args.split, "windows": len(windows), "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
