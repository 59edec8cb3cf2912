"""Frame-generator speed: inference frames/s (batch 1 and larger batches, torch.inference_mode +
channels_last) and training steps/s, on random inputs of the default architecture. Writes JSON.

    python scripts/bench_frames.py --json out/bench_frames.json [--size 128] [--threads 2]
"""

from __future__ import annotations

import argparse
import platform
import sys

import numpy as np
import torch

from motion2video import __version__
from motion2video.evaluation.benchtools import median_seconds as _median_time
from motion2video.core.atomic import write_json
from motion2video.frames.data import structure_channels
from motion2video.frames.model import (FrameGenerator, FrameGeneratorConfig, count_parameters, generate,
                                       reconstruction_loss)


def bench(*, size: int, domain: str, batches: tuple[int, ...], train_batch: int, repeats: int) -> dict:
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    s = structure_channels(domain)
    model = FrameGenerator(FrameGeneratorConfig(domain=domain, image_size=size, structure_channels=s))
    infer = {}
    for b in batches:
        imgs = rng.integers(0, 256, (b, size, size, 3), dtype=np.uint8)
        ps = rng.random((b, s, size, size), dtype=np.float32)
        pt = rng.random((b, s, size, size), dtype=np.float32)
        sec = _median_time(lambda: generate(model, imgs, ps, pt, batch_size=b), repeats=repeats)
        infer[str(b)] = round(b / sec, 2)
    model = FrameGenerator(model.config).train()
    opt = torch.optim.Adam(model.parameters(), lr=1e-4)
    x = torch.rand(train_batch, 3, size, size)
    p = torch.rand(train_batch, s, size, size)
    q = torch.rand(train_batch, s, size, size)

    def step():
        loss = reconstruction_loss(model(x, p, q), x, ssim_weight=1.0).total
        opt.zero_grad()
        loss.backward()
        opt.step()

    sec = _median_time(step, repeats=repeats)
    best = max(infer, key=infer.get)
    return {
        "domain": domain,
        "image_size": size,
        "parameters": count_parameters(model),
        "inference_fps_by_batch": infer,
        "inference_fps_batch1": infer.get("1"),
        "best_batch": int(best),
        "inference_fps_best": infer[best],
        "train_batch": train_batch,
        "train_steps_per_second": round(1.0 / sec, 3),
        "train_samples_per_second": round(train_batch / sec, 2),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", required=True, help="output JSON")
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--threads", type=int, default=None, help="torch threads (default: torch's)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    if args.threads:
        torch.set_num_threads(args.threads)
    results = [bench(size=args.size, domain=d, batches=(1, 4, 8, 16), train_batch=8, repeats=args.repeats)
               for d in ("body", "face")]
    payload = {
        "results": results,
        "torch_threads": torch.get_num_threads(),
        "versions": {"motion2video": __version__, "torch": torch.__version__, "numpy": np.__version__,
                     "python": sys.version.split()[0]},
        "machine": platform.platform(),
    }
    print(write_json(args.json, payload).read_text(), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
