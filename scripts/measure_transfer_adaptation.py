"""How many decoder-adaptation steps behaviour transfer takes: the known-answer transfer
benchmark (:mod:`motion2video.evaluation.transfer_benchmark`) of one behaviour checkpoint, its decoder adapted to
each source for each step count (:func:`motion2video.stages.latents.adapt_to_source`; 0 = the decoder as trained).

    python scripts/measure_transfer_adaptation.py --json out/transfer_adaptation.json

The step count is chosen on the TRAINING cases only: the score is the mean |log ratio| over their behaviour
signatures and root-relative signatures (0 = every signature carried in full); the held-out cases are reported,
not used. Prints a Markdown table per split (median ratios; ``kept`` = the median :func:`posture_kept`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def split_score(rows: list[dict], split: str) -> float:
    """Mean |log ratio| over the behaviour and root-relative signature medians of ``split``'s transfer rows."""
    values = []
    for r in rows:
        if r["split"] != split or r["method"] != "transfer":
            continue
        values.append(r["median_ratio"])
        values += [v for v in r["relative"].values() if v == v]
    return sum(abs(math.log(v)) for v in values) / len(values)


def table(results: dict[int, list[dict]], split: str) -> list[str]:
    from motion2video.evaluation import transfer_benchmark as B

    names = list(B.RELATIVE)
    lines = ["| steps | behaviour | signature | " + " | ".join(n.replace("_", " ") for n in names)
             + " | start error (m) | kept |",
             "| ---: | --- | ---: | " + " | ".join("---:" for _ in names) + " | ---: | ---: |"]
    for steps, rows in results.items():
        for r in rows:
            if r["split"] != split or r["method"] != "transfer":
                continue
            rel = " | ".join("-" if r["relative"][n] != r["relative"][n] else f"{r['relative'][n]:.2f}"
                             for n in names)
            lines.append(f"| {steps} | {r['behaviour']} | {r['median_ratio']:.2f} | {rel} | "
                         f"{r['start_error']:.3f} | {r['posture_kept']:.2f} |")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--model", default="behavior", help="behaviour checkpoint or shipped name")
    parser.add_argument("--steps", default="0,25,50,100,200,300", help="comma-separated step counts")
    parser.add_argument("--json", default=None, help="also write the summaries here")
    args = parser.parse_args(argv)

    import torch

    from motion2video.evaluation import transfer_benchmark as B
    from motion2video.models.checkpoint import load_model

    torch.set_num_threads(1)
    bundle = load_model(args.model)
    results, seconds = {}, {}
    for steps in (int(s) for s in args.steps.split(",")):
        t0 = time.time()
        rows = B.summarise(B.run_benchmark(args.data, transfer=bundle, adapt_steps=steps))
        seconds[steps] = time.time() - t0
        results[steps] = rows
        print(f"{steps} steps: training-case score {split_score(rows, 'train'):.3f}, held-out "
              f"{split_score(rows, 'held-out'):.3f} ({seconds[steps]:.0f} s for {len(B.CASES)} sources)", flush=True)
    for split in ("train", "held-out"):
        print(f"\n{split} cases (median ratio re-enactment / source):\n")
        print("\n".join(table(results, split)))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"model": args.model, "seconds": seconds, "rows": results,
                                               "score": {s: {sp: split_score(r, sp) for sp in ("train", "held-out")}
                                                         for s, r in results.items()}}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
