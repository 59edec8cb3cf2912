"""Real motion retrieved for each window, scored like a model: the forecasting protocol and the realism test.

    python scripts/measure_retrieved_futures.py [--model mtvae-add-dlow] [--json out/retrieved_futures.json]

The windows and split are those of ``--model``'s recorded split (the corpus's pinned test subjects), as
``motion2video evaluate --model mtvae-add-dlow --data ../shared/data/mocap`` scores them. The database is every
window of that split's training clips (stride ``--db-stride``); each held-out window gets the K nearest
(:class:`motion2video.evaluation.retrieval.RetrievedFutures`). Printed and written to --json:

- best-of-50 ADE / FDE per action and macro, ratio to zero-velocity, for the retrieved futures and ``--model``;
- the two-sample realism test (:func:`motion2video.evaluation.transfer.sample_realism`, 10 futures per window, one
  per window tested) on the held-out windows at stride 8, as docs/results_transfer.md measures the samplers.

About a minute on one thread.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2video.core.atomic import write_json  # noqa: E402
from motion2video.data.dataset import DEFAULT_MOCAP, build_dataset  # noqa: E402
from motion2video.evaluation.forecasting import EvalProtocol, evaluate_bundles  # noqa: E402
from motion2video.evaluation.per_action import ratios_to  # noqa: E402
from motion2video.evaluation.retrieval import RetrievalConfig, training_database  # noqa: E402
from motion2video.evaluation.transfer import sample_realism  # noqa: E402
from motion2video.models.checkpoint import ModelBundle, baseline_bundle, load_model  # noqa: E402

LABEL = "retrieved futures"


def retrieval_bundle(model: ModelBundle, dataset, *, db_stride: int) -> ModelBundle:
    """The retrieval sampler over the training windows of ``dataset``, in ``model``'s normalisation."""
    net = training_database(dataset.windows("train", stride=db_stride), model.stats)
    return ModelBundle(model=net, stats=model.stats, meta=replace(model.meta, model=LABEL), path=None)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="mtvae-add-dlow", help="the model compared, and whose split is used")
    parser.add_argument("--data", default=str(DEFAULT_MOCAP))
    parser.add_argument("--db-stride", type=int, default=2)
    parser.add_argument("--json", default=str(ROOT / "out" / "retrieved_futures.json"))
    args = parser.parse_args(argv)

    start = time.time()
    model = load_model(args.model)
    cfg = model.data_config
    dataset = build_dataset(args.data, cfg, split=model.meta.split, stats=model.stats)
    retrieved = retrieval_bundle(model, dataset, db_stride=args.db_stride)
    print(f"database: {len(retrieved.model.windows)} training windows (stride {args.db_stride})")

    windows = dataset.windows("test", stride=16)
    bundles = [retrieved, model, baseline_bundle("zero-velocity", cfg, stats=model.stats)]
    result = evaluate_bundles(bundles, windows, protocol=EvalProtocol(samples=50, stride=16))
    zero = result.per_action["zero-velocity"]
    ratios = {label: ratios_to(result.per_action[label], zero) for label in (LABEL, model.label)}
    actions = list(result.per_action[LABEL])
    print(f"\n{len(windows)} held-out windows, best of 50, ADE / FDE ratio to zero-velocity")
    print("| action (windows) | " + " | ".join(ratios) + " |")
    for a in actions + ["macro"]:
        count = f" ({result.per_action[LABEL][a]['windows']})" if a != "macro" else ""
        print(f"| {a}{count} | " + " | ".join(f"{r[a][0]:.2f} / {r[a][1]:.2f}" for r in ratios.values()) + " |")
    apd = {label: result.results[label]["apd"] for label in ratios}
    print("APD (m):", ", ".join(f"{k} {v:.2f}" for k, v in apd.items()))

    dense = dataset.windows("test", stride=8)
    realism = {}
    for bundle in (retrieved, model):
        r = sample_realism(bundle, dense, samples=10, seed=0)
        realism[bundle.label] = {"accuracy": r.realism, "control": r.realism_control, "by_family": r.realism_by_family,
                                 "velocity_ratio": r.samples[0] / r.real[0],
                                 "acceleration_ratio": r.samples[1] / r.real[1], "windows": r.windows}
    print(f"\ntwo-sample realism test, {len(dense)} held-out windows (stride 8), one of 10 futures per window")
    for label, r in realism.items():
        fam = ", ".join(f"{k} {v:.2f}" for k, v in r["by_family"].items())
        print(f"{label}: {r['accuracy']:.3f} (control {r['control']:.3f}; {fam}; velocity {r['velocity_ratio']:.2f}, "
              f"acceleration {r['acceleration_ratio']:.2f} of the truth's)")
    out = write_json(args.json, {"ratios": ratios, "apd": apd, "realism": realism, "config": vars(RetrievalConfig()),
                                 "database_windows": len(retrieved.model.windows), "model": model.label,
                                 "evaluate": result.to_json()})
    print(f"wrote {out} in {time.time() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
