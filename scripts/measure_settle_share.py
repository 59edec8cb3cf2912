"""How many of mixture-periodic's 50 futures the ``settle`` rule should draw, chosen on windows no test row uses.

    python scripts/measure_settle_share.py --json out/settle_share.json

Two tuning sets, neither of them a test split:
- Bandai-Namco clips of the subject split's *training* groups (1A, 2A, 2B, ...; the held-out groups 1B and 2C are
  its test rows), 900 windows drawn at random (seed 0) from those at stride 128. The shipped samplers never
  trained on any Bandai-Namco clip, so for them these are unseen performers;
- the motion corpus's validation split (stride 16), which model selection has used before.

Each candidate is a real mixture (``compose_mixture``) of the shipped parts with the shares given, scored best of
50 by the project's metric; macro = the mean over actions of the best-of-50 ADE / FDE over the mean of
zero-velocity's (as ``evaluate`` prints it). About 10 minutes on the shared 2-core machine.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from motion2video.data.dataset import build_dataset
from motion2video.data.windows import metric_vectors
from motion2video.evaluation.forecasting import subject_windows
from motion2video.evaluation.metrics import best_of_k_displacements, displacement
from motion2video.evaluation.per_action import family_key
from motion2video.models.checkpoint import baseline_bundle, compose_mixture, load_model
from motion2video.stages.sampling import sample_futures

REPO = Path(__file__).resolve().parents[1]
DATA = [REPO.parent / "shared" / "data" / "mocap", REPO.parent / "shared" / "data" / "bandai"]
# (label, shares of mtvae-add-dlow, mixer-cvae-dlow, mirror-periodic, settle, settle's decay range in frames)
CANDIDATES = (("shipped before settle", (19, 19, 12, 0), None),
              ("settle 2", (18, 18, 12, 2), (1.0, 16.0)),
              ("settle 3", (18, 17, 12, 3), (1.0, 16.0)),
              ("settle 4", (17, 17, 12, 4), (1.0, 16.0)),
              ("settle 6", (16, 16, 12, 6), (1.0, 16.0)),
              ("settle 4, decay 0.5-8", (17, 17, 12, 4), (0.5, 8.0)),
              ("settle 4, decay 2-32", (17, 17, 12, 4), (2.0, 32.0)),
              ("settle 4, mirror 10", (18, 18, 10, 4), (1.0, 16.0)))


def tuning_windows(first):
    """{set name: (obs (N, To, F) normalised, raw (N, L, F) metres, action per window)} of the two tuning sets."""
    dataset, _, _ = subject_windows([str(d) for d in DATA], first.data_config, [first], stride=128, character=None)
    train = dataset.windows("train", stride=128)
    bandai = np.flatnonzero([name.startswith("bandai") for name in train.clip_names])
    pick = np.sort(np.random.default_rng(0).choice(bandai, size=min(900, len(bandai)), replace=False))
    actions = [family_key(train.labels[i], "bandai").rpartition(" @ ")[0] for i in pick]
    corpus = build_dataset(str(DATA[0]), first.data_config, split=first.meta.split, stats=first.stats)
    val = corpus.windows("val", stride=16)
    return {"bandai training groups": (train.obs[pick], train.raw[pick], actions),
            "corpus validation": (val.obs, val.raw, list(val.labels))}


def macro_ratio(pred: np.ndarray, gt: np.ndarray, still: np.ndarray, actions: list[str]) -> tuple[float, float]:
    """Best-of-K macro ADE / FDE over zero-velocity's: pred (N, K, T, D), gt (N, T, D), still (N, T, D)."""
    best = best_of_k_displacements(displacement(pred, gt))
    zero = best_of_k_displacements(displacement(still[:, None], gt))
    acts = np.array(actions)
    out = []
    for key in ("ade", "fde"):
        ours = np.mean([best[key][acts == a].mean() for a in sorted(set(actions))])
        ref = np.mean([zero[key][acts == a].mean() for a in sorted(set(actions))])
        out.append(float(ours / ref))
    return out[0], out[1]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", default=None, help="write the table as JSON here")
    args = parser.parse_args(argv)
    first = load_model("mtvae-add-dlow")
    parts = [first, load_model("mixer-cvae-dlow"), baseline_bundle("mirror-periodic", first.data_config,
                                                                    stats=first.stats)]
    sets = tuning_windows(first)
    rows: dict[str, dict] = {}
    for label, shares, decay in CANDIDATES:
        bundles, used = list(parts), list(shares[:3])
        if shares[3]:
            config = {"min_decay": decay[0], "max_decay": decay[1]}
            bundles.append(baseline_bundle("settle", first.data_config, stats=first.stats, config=config))
            used.append(shares[3])
        mixture = compose_mixture(bundles, used)
        rows[label] = {}
        for name, (obs, raw, actions) in sets.items():
            gt = metric_vectors(raw[:, obs.shape[1]:], first.layout)
            still = np.repeat(metric_vectors(raw[:, obs.shape[1] - 1:obs.shape[1]], first.layout), gt.shape[1], 1)
            futures = sample_futures(mixture.model, obs, num_samples=50, horizon=gt.shape[1], seed=0)
            pred = metric_vectors(first.stats.denormalize(futures), first.layout)
            rows[label][name] = macro_ratio(pred, gt, still, actions)
        print(f"{label:26s} " + "   ".join(f"{name}: {a:.3f} / {f:.3f}" for name, (a, f) in rows[label].items()),
              flush=True)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
