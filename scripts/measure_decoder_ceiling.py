"""How close can any sampler of a latent model's decoder get to the held-out futures? Its posterior ceiling.

    python scripts/measure_decoder_ceiling.py [--model mtvae-add-dlow] [--model PATH ...] [--split test]
        [--json out/decoder_ceiling.json]

A latent-variable forecaster (MT-VAE, LCP-VAE, the behaviour model, and DLow on top of one of them) draws a future
by decoding a latent z. Its recognition model q(z | observed, future) sees the TRUE future; decoding its latents is
the best that decoder does for that window with latents it was trained on. Whatever a sampler learns (the prior,
LCP-VAE's conditional prior, DLow's maps) only picks latents, so a sampler's best-of-50 cannot be expected to beat
the decoder fed from the recognition model. For each ``--model`` (a DLow checkpoint is measured through its frozen
base), on the windows ``motion2video evaluate`` scores (its recorded split, stride 16), per action and the macro
average over actions, ADE / FDE as a ratio to zero-velocity:

- ``posterior mean``: the future decoded from the recognition model's mean latent (one future per window);
- ``posterior, best of 50``: 50 latents drawn from the recognition model, the best future of each window;
- ``nearest training latents, best of 50``: the recognition model's mean latents of the 50 training windows whose
  last observed frames are nearest (:func:`motion2video.evaluation.retrieval.retrieved_latent_futures`; training
  windows at stride ``--db-stride``): real latents picked for the context, as a sampler could draw them;
- ``sampled, best of 50``: the model's own samples, as ``motion2video evaluate`` scores them.

Every future continues the observed motion (:func:`motion2video.stages.sampling.continue_observed`), as sampled.
About 1.5 minutes (mixer-cvae) to 3 minutes (mtvae-add) per model on one thread.
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
from motion2video.evaluation.forecasting import (EvalProtocol, dlow_metrics_per_window,  # noqa: E402
                                                 evaluate_bundles, posterior_futures)
from motion2video.evaluation.retrieval import (posterior_means, retrieved_latent_futures,  # noqa: E402
                                               training_database)
from motion2video.evaluation.per_action import group_by_action, per_action_means, ratios_to  # noqa: E402
from motion2video.models.checkpoint import baseline_bundle, load_model  # noqa: E402
from motion2video.stages.sampling import continue_observed  # noqa: E402

SAMPLES = 50


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", action="append", help="shipped name or checkpoint (repeat; default mtvae-add-dlow)")
    parser.add_argument("--data", default=str(DEFAULT_MOCAP))
    parser.add_argument("--split", default="test", choices=("test", "val"))
    parser.add_argument("--db-stride", type=int, default=2, help="stride of the training windows whose latents "
                        "are retrieved (default 2)")
    parser.add_argument("--json", default=str(ROOT / "out" / "decoder_ceiling.json"))
    args = parser.parse_args(argv)
    torch.set_num_threads(1)

    start = time.time()
    report: dict[str, dict] = {}
    for name in args.model or ["mtvae-add-dlow"]:
        bundle = load_model(name)
        decoder = getattr(bundle.model, "base", bundle.model)  # DLow samples the latents of its frozen base
        if not (hasattr(decoder, "encode") and hasattr(decoder, "decode")):
            raise SystemExit(f"{name}: not a latent model with a recognition model and a decoder")
        dataset = build_dataset(args.data, bundle.data_config, split=bundle.meta.split, stats=bundle.stats)
        windows = dataset.windows(args.split, stride=16)
        layout = bundle.layout
        gt = metric_vectors(windows.raw[:, windows.observed:], layout)
        last = metric_vectors(windows.raw[:, windows.observed - 1], layout)
        threshold = EvalProtocol().threshold(layout)
        actions = group_by_action(windows.labels)
        scored = evaluate_bundles([bundle, baseline_bundle("zero-velocity", bundle.data_config, stats=bundle.stats)],
                                  windows, protocol=EvalProtocol(samples=SAMPLES, stride=16))
        zero = scored.per_action["zero-velocity"]

        def score(normalised: np.ndarray) -> dict[str, list[float]]:
            pred = metric_vectors(bundle.stats.denormalize(continue_observed(normalised, windows.obs)), layout)
            return ratios_to(per_action_means(dlow_metrics_per_window(pred, gt, last, threshold=threshold), actions), zero)

        train = dataset.windows("train", stride=args.db_stride)
        database = training_database(train, bundle.stats)
        latents = posterior_means(decoder, train.features, observed=train.observed)
        rows = {
            "posterior mean": score(posterior_futures(decoder, windows.obs, windows.future, num_samples=1, seed=0,
                                                      from_mean=True)),
            f"posterior, best of {SAMPLES}": score(posterior_futures(decoder, windows.obs, windows.future,
                                                                      num_samples=SAMPLES, seed=0)),
            f"nearest training latents, best of {SAMPLES}": score(retrieved_latent_futures(
                decoder, database, latents, windows.obs, num_samples=SAMPLES, horizon=windows.future.shape[1])),
            f"sampled, best of {SAMPLES}": ratios_to(scored.per_action[bundle.label], zero),
        }
        counts = {a: int(len(idx)) for a, idx in actions.items()}
        report[bundle.label] = {"rows": rows, "windows": counts, "apd": scored.results[bundle.label]["apd"]}

        print(f"\n{bundle.label} ({len(windows)} {args.split} windows), ADE / FDE ratio to zero-velocity")
        print("| | " + " | ".join(f"{a} ({counts[a]})" for a in counts) + " | macro |")
        print("| --- |" + " ---: |" * (len(counts) + 1))
        for label, row in rows.items():
            print(f"| {label} | " + " | ".join(f"{row[a][0]:.2f} / {row[a][1]:.2f}" for a in [*counts, "macro"]) + " |")
    out = write_json(args.json, {"split": args.split, "samples": SAMPLES, "models": report})
    print(f"\nwrote {out} in {time.time() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
