"""Sampling speed: 50 futures of 48 frames from mtvae-add, batched (one call) versus one sample at a time.

    python scripts/bench_sampling.py --json out/bench_sampling.json

Uses the shipped ``mtvae-add`` checkpoint when it exists, else an untrained ``mtvae-add`` with its default
config (the speed does not depend on the weights; the JSON says which). The observation is a real 16-frame
window from the mocap folder. Warm-up runs first; the reported times are medians over repeats; one torch
thread unless --threads says otherwise.

JSON keys: ``batched_ms`` (milliseconds for the 50 futures in one call), ``loop_ms`` (50 calls of one
sample), ``batched_vs_loop`` (loop_ms / batched_ms), plus the settings and library versions.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import torch


def run_benchmark(*, samples: int = 50, horizon: int = 48, repeats: int = 7, threads: int = 1,
                  data: str | None = None, seed: int = 0) -> dict:
    """Time batched and one-at-a-time sampling; returns the JSON record."""
    from motion2video.evaluation.benchtools import median_ms
    from motion2video.models.checkpoint import WEIGHTS_DIR, load_model
    from motion2video.data.dataset import DEFAULT_MOCAP, DatasetConfig, build_dataset
    from motion2video.models.base import build_model

    torch.set_num_threads(threads)
    shipped = WEIGHTS_DIR / "mtvae-add.safetensors"
    if shipped.is_file():
        bundle = load_model(shipped)
        model, stats, cfg, source = bundle.model, bundle.stats, bundle.data_config, str(shipped)
    else:
        cfg = DatasetConfig()
        torch.manual_seed(seed)
        model, stats, source = build_model("mtvae-add", {"feature_dim": 51}).eval(), None, "untrained default config"
    dataset = build_dataset(data or DEFAULT_MOCAP, cfg, stats=stats)
    window = dataset.windows("test", stride=cfg.length)
    obs = torch.from_numpy(window.obs[:1])  # (1, 16, F)
    gen = torch.Generator().manual_seed(seed)

    def batched():
        with torch.no_grad():
            out = model.sample(obs, num_samples=samples, horizon=horizon, generator=gen)
        assert out.shape == (1, samples, horizon, obs.shape[-1])

    def loop():
        with torch.no_grad():
            for _ in range(samples):
                model.sample(obs, num_samples=1, horizon=horizon, generator=gen)

    batched(), loop()  # warm-up
    batched_ms = median_ms(batched, repeats=repeats)
    loop_ms = median_ms(loop, repeats=max(3, repeats // 2))
    return {
        "batched_ms": round(batched_ms, 3),
        "loop_ms": round(loop_ms, 3),
        "batched_vs_loop": round(loop_ms / batched_ms, 2),
        "samples": samples,
        "horizon": horizon,
        "model": "mtvae-add",
        "weights": source,
        "parameters": int(sum(p.numel() for p in model.parameters())),
        "repeats": repeats,
        "threads": threads,
        "versions": {"python": sys.version.split()[0], "torch": torch.__version__, "numpy": np.__version__},
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", required=True, help="write the record here")
    p.add_argument("--samples", type=int, default=50)
    p.add_argument("--horizon", type=int, default=48)
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--data", default=None, help="mocap folder for the observation (default ../shared/data/mocap)")
    args = p.parse_args(argv)
    record = run_benchmark(samples=args.samples, horizon=args.horizon, repeats=args.repeats, threads=args.threads,
                           data=args.data)
    out = Path(args.json)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(record, indent=2) + "\n")
    print(json.dumps({k: record[k] for k in ("batched_ms", "loop_ms", "batched_vs_loop", "weights")}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
