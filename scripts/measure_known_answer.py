"""The known-answer multimodal benchmark for any shipped latent model and DLow on it (issue 24, item 6: "known-answer
benchmark, the new model: coverage and precision >= 0.9 at K = 10").

    python scripts/measure_known_answer.py [--model mixer-cvae] [--steps 4000] [--dlow-steps 600]
        [--runs out/known_answer] [--json out/known_answer.json]

The model is retrained from scratch on ``procedural:multimodal`` (sequences whose future is one of the observed
mode's known next modes) with the shipped checkpoint's config and ``--steps`` steps (seed 0, batch 64), then DLow
with the shipped ``mtvae-add-dlow`` config and K = 10 maps (``--dlow-steps``, batch 16); both are scored with K = 10
samples per test sequence: coverage (share of valid modes hit by a sample), precision (share of samples in a valid
mode) and TV (total variation between sampled and true mode frequencies). The same protocol as
``scripts/make_results_corpus.py``'s table for mtvae-add and lcpvae. A model whose loss is in metres
(``feature_scale``, mixer-cvae) gets this dataset's scales, as ``motion2video train`` gives them.
About 12 minutes on one thread for mixer-cvae (2026-11-27).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2video.core.atomic import write_json  # noqa: E402
from motion2video.data.dataset import MULTIMODAL_SOURCE, DatasetConfig, build_dataset, decode_samples  # noqa: E402
from motion2video.data.multimodal import MultimodalBenchmark, score_futures  # noqa: E402
from motion2video.models.checkpoint import WEIGHTS_DIR, load_model  # noqa: E402
from motion2video.models.training import TrainConfig, train_model  # noqa: E402
from motion2video.stages.sampling import sample_futures  # noqa: E402

MM_CONFIG = DatasetConfig(speed=0.0)  # benchmark clips are exactly one window long (as make_results_corpus.py)
SAMPLES = 10


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="mixer-cvae", help="a shipped latent model (its config is retrained)")
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--dlow-steps", type=int, default=600)
    parser.add_argument("--runs", default=str(ROOT / "out" / "known_answer"))
    parser.add_argument("--json", default=str(ROOT / "out" / "known_answer.json"))
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    start = time.time()

    ds = build_dataset(MULTIMODAL_SOURCE, MM_CONFIG)
    test = ds.windows("test")
    runs = Path(args.runs)
    runs.mkdir(parents=True, exist_ok=True)
    shipped = load_model(WEIGHTS_DIR / f"{args.model}.safetensors")
    drop = {"feature_dim", "feature_scale"}  # set from this dataset by train_model
    base_out = runs / f"mm-{args.model}-{args.steps}.safetensors"
    if not base_out.is_file():
        cfg = {k: v for k, v in shipped.meta.config.items() if k not in drop}
        train_model(model_name=shipped.name, model_config=cfg, dataset=ds, out=base_out, progress=False,
                    config=TrainConfig(steps=args.steps, batch_size=64, checkpoint_every=args.steps, val_every=0,
                                       seed=0))
    base = load_model(base_out)
    dlow_out = runs / f"mm-{args.model}-{args.steps}-dlow{SAMPLES}-{args.dlow_steps}.safetensors"
    if not dlow_out.is_file():
        dlow_cfg = {k: v for k, v in load_model(WEIGHTS_DIR / "mtvae-add-dlow.safetensors").meta.config.items()
                    if k != "feature_dim"}
        cfg = {**dlow_cfg, "base_model": base.name, "num_samples": SAMPLES,
               "base_config": {k: v for k, v in base.meta.config.items() if k != "feature_dim"}}
        state = {"base." + k: v for k, v in base.model.state_dict().items()}
        ds_b = build_dataset(MULTIMODAL_SOURCE, MM_CONFIG, split=base.meta.split, stats=base.stats)
        train_model(model_name="dlow", model_config=cfg, dataset=ds_b, out=dlow_out, progress=False,
                    init_state=state, config=TrainConfig(steps=args.dlow_steps, batch_size=16, lr=5e-4,
                                                         checkpoint_every=args.dlow_steps, val_every=0, seed=0))
    bench = MultimodalBenchmark(observed_frames=MM_CONFIG.observed, future_frames=MM_CONFIG.future, fps=MM_CONFIG.fps)
    report = {}
    print(f"| model | coverage | precision | TV |\n|---|---|---|---|")
    for label, path in ((args.model, base_out), (f"{args.model} + dlow", dlow_out)):
        b = load_model(path)
        s = sample_futures(b.model, test.obs, num_samples=SAMPLES, horizon=MM_CONFIG.future, seed=0)
        world = decode_samples(s, config=MM_CONFIG, stats=b.stats, frame=test.frames)
        sc = score_futures(world, list(test.labels), benchmark=bench)
        report[label] = {"coverage": sc.coverage, "precision": sc.precision, "distribution_tv": sc.distribution_tv}
        print(f"| {label} | {sc.coverage:.3f} | {sc.precision:.3f} | {sc.distribution_tv:.3f} |")
    write_json(args.json, {"samples": SAMPLES, "steps": args.steps, "dlow_steps": args.dlow_steps,
                           "test_sequences": len(test), "models": report})
    print(f"wrote {args.json} in {time.time() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
