"""Retrain the 5-minute models on today's joints: the per-action comparison needs them.

    python scripts/retrain_five_minute.py [--out out/five_minute] [--models mtvae-add,lcpvae,behavior]
        [--mocap ../shared/data/mocap] [--rev 805c753]

The 72-clip models of git ``--rev`` (4.7 minutes of motion, the "5-minute models") were trained on canonical
skeleton version 1; this motion2video refuses them (every source now follows Human3.6M's body points).
Each is retrained here with what its checkpoint records: the model name and config, the data config, the exact
72-clip split (train / val / test clip names; only those clips are loaded) and the training config (2000 steps,
batch 64, seed 0). The joints are version 2 and the code is today's: config fields added since take their defaults
(each is off unless a card says otherwise), and the normalisation statistics are computed on the training windows.
Writes ``OUT/NAME.safetensors`` (with a ``.json`` of the run), for ``scripts/make_results_per_action.py --model``.
About 3-5 minutes per model on one thread (2026-11-26).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from make_results_per_action import OLD, OLD_REV, resolve  # noqa: E402  (scripts/ is on sys.path when run)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(REPO / "out" / "five_minute"))
    parser.add_argument("--models", default=",".join(OLD))
    parser.add_argument("--mocap", default=str(REPO.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--rev", default=OLD_REV)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--cache", default="/tmp/motion2video-git-weights",
                        help="where the old checkpoints are written (as make_results_per_action.py --cache)")
    args = parser.parse_args(argv)

    import torch

    import motion2video.models.checkpoint as checkpoint
    from motion2video.data.dataset import build_dataset
    from motion2video.models.training import TrainConfig, train_model

    torch.set_num_threads(args.threads)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in args.models.split(","):
        old = resolve(f"git:{args.rev}:motion2video/weights/{name}.safetensors", Path(args.cache))
        meta = checkpoint.read_meta(old)
        dataset = build_dataset(args.mocap, meta.data_config, split=meta.split, recorded_only=True)
        known = {f.name for f in dataclasses.fields(TrainConfig)}
        train = TrainConfig(**{k: v for k, v in meta.training["config"].items() if k in known})
        model_config = {k: v for k, v in meta.config.items() if k != "feature_dim"}
        t0 = time.perf_counter()
        result = train_model(model_name=meta.model, model_config=model_config, dataset=dataset, config=train,
                             out=out / f"{name}.safetensors", progress=False)
        record = {"rev": args.rev, "model": meta.model, "config": model_config, "train": dataclasses.asdict(train),
                  "clips": dataset.summary["per_split"], "wall_time_s": round(time.perf_counter() - t0, 1),
                  "val_loss": result.val_loss, "train_loss": result.train_loss}
        (out / f"{name}.json").write_text(json.dumps(record, indent=1))
        print(f"{name}: {result.steps} steps in {record['wall_time_s']:.0f} s, clips {record['clips']}, "
              f"wrote {result.path}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
