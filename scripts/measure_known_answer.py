"""The known-answer multimodal benchmark for any shipped latent model and DLow on it (its target:
coverage and precision >= 0.9 at K = 10).

    python scripts/measure_known_answer.py [--model mixer-cvae] [--steps 4000] [--dlow-steps 600]
        [--runs out/known_answer] [--json out/known_answer.json]

The model is retrained from scratch on ``procedural:multimodal`` (sequences whose future is one of the observed
mode's known next modes) with the shipped checkpoint's config and ``--steps`` steps (seed 0, batch 64), then DLow
with the shipped ``mtvae-add-dlow`` config and K = 10 maps (``--dlow-steps``, batch 16); both are scored with K = 10
samples per test sequence: coverage (share of valid modes hit by a sample), precision (share of samples in a valid
mode) and TV (total variation between sampled and true mode frequencies). ``scripts/make_results_corpus.py``'s
table for mtvae-add and lcpvae is made with the same two functions (:func:`train_with_dlow`, :func:`score`). A
model whose loss is in metres (``feature_scale``, mixer-cvae) gets this dataset's scales, as ``motion2video train``
gives them.
About 14 minutes on one thread for mixer-cvae (2026-11-27).
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
from motion2video.data.dataset import (  # noqa: E402
    MULTIMODAL_SOURCE, DatasetConfig, WindowSet, build_dataset, decode_samples,
)
from motion2video.data.multimodal import MultimodalBenchmark, score_futures  # noqa: E402
from motion2video.models.checkpoint import WEIGHTS_DIR, load_model  # noqa: E402
from motion2video.models.training import TrainConfig, train_model  # noqa: E402
from motion2video.stages.sampling import sample_futures  # noqa: E402

MM_CONFIG = DatasetConfig(speed=0.0)  # benchmark clips are exactly one window long
SAMPLES = 10


def train_with_dlow(name: str, config: dict, runs: Path, *, steps: int, dlow_steps: int,
                    samples: int = SAMPLES) -> tuple[Path, Path]:
    """Train model ``name`` with ``config`` (``feature_dim`` / ``feature_scale`` are set from the data) on
    ``procedural:multimodal`` for ``steps`` steps, then DLow with the shipped ``mtvae-add-dlow`` config and
    ``samples`` maps on it; a checkpoint already in ``runs`` is reused. Returns (base, dlow) checkpoint paths."""
    ds = build_dataset(MULTIMODAL_SOURCE, MM_CONFIG)
    runs.mkdir(parents=True, exist_ok=True)
    base_out = runs / f"mm-{name}-{steps}.safetensors"
    if not base_out.is_file():
        cfg = {k: v for k, v in config.items() if k not in ("feature_dim", "feature_scale")}
        train_model(model_name=name, model_config=cfg, dataset=ds, out=base_out, progress=False,
                    config=TrainConfig(steps=steps, batch_size=64, checkpoint_every=steps, val_every=0, seed=0))
    dlow_out = runs / f"mm-{name}-{steps}-dlow{samples}-{dlow_steps}.safetensors"
    if not dlow_out.is_file():
        base = load_model(base_out)
        dlow_cfg = {k: v for k, v in load_model(WEIGHTS_DIR / "mtvae-add-dlow.safetensors").meta.config.items()
                    if k != "feature_dim"}
        cfg = {**dlow_cfg, "base_model": name, "num_samples": samples,  # K maps for the K it is scored with
               "base_config": {k: v for k, v in base.meta.config.items() if k != "feature_dim"}}
        state = {"base." + k: v for k, v in base.model.state_dict().items()}
        ds_b = build_dataset(MULTIMODAL_SOURCE, MM_CONFIG, split=base.meta.split, stats=base.stats)
        train_model(model_name="dlow", model_config=cfg, dataset=ds_b, out=dlow_out, progress=False,
                    init_state=state, config=TrainConfig(steps=dlow_steps, batch_size=16, lr=5e-4,
                                                         checkpoint_every=dlow_steps, val_every=0, seed=0))
    return base_out, dlow_out


def score(path: Path, test: WindowSet, samples: int = SAMPLES) -> dict[str, float]:
    """Coverage, precision and distribution TV of ``samples`` futures (seed 0) per window of the benchmark's
    ``test`` windows, drawn by the checkpoint at ``path``."""
    bench = MultimodalBenchmark(observed_frames=MM_CONFIG.observed, future_frames=MM_CONFIG.future, fps=MM_CONFIG.fps)
    b = load_model(path)
    s = sample_futures(b.model, test.obs, num_samples=samples, horizon=MM_CONFIG.future, seed=0)
    world = decode_samples(s, config=MM_CONFIG, stats=b.stats, frame=test.frames)
    sc = score_futures(world, list(test.labels), benchmark=bench)
    return {"coverage": sc.coverage, "precision": sc.precision, "distribution_tv": sc.distribution_tv}


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

    shipped = load_model(WEIGHTS_DIR / f"{args.model}.safetensors")
    base_out, dlow_out = train_with_dlow(shipped.name, shipped.meta.config, Path(args.runs), steps=args.steps,
                                         dlow_steps=args.dlow_steps)
    test = build_dataset(MULTIMODAL_SOURCE, MM_CONFIG).windows("test")
    report = {}
    print("| model | coverage | precision | TV |\n|---|---|---|---|")
    for label, path in ((args.model, base_out), (f"{args.model} + dlow", dlow_out)):
        report[label] = r = score(path, test)
        print(f"| {label} | {r['coverage']:.3f} | {r['precision']:.3f} | {r['distribution_tv']:.3f} |")
    write_json(args.json, {"samples": SAMPLES, "steps": args.steps, "dlow_steps": args.dlow_steps,
                           "test_sequences": len(test),
                           "models": report})
    print(f"wrote {args.json} in {time.time() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
