"""Why mixture-dlow: how far the samplers' futures walk, and every equal-share mixture on validation.

    python scripts/measure_mixtures.py --json out/mixtures.json

Prints and writes (about 30 s on one thread):

- walking: on the held-out walking windows of the shipped split (stride 16, 50 futures each, seed 0), the mean
  distance the true future's pelvis travels, the median over futures of the distance each sampler's pelvis
  travels, and the share of futures travelling at least half the truth's distance; then the pelvis speed of 10
  futures of the demo's walk (``demo_inputs/cmu_walk.npz`` from frame 24) against the observed speed;
- mixtures: for every equal-share mixture of one to three of ``--models`` (future k from member k mod C, the
  rule of :mod:`motion2video.models.mixture`, each member's first futures of one 50-future draw), the macro
  best-of-50 ADE / FDE ratio to zero-velocity over the actions of ``--split`` (default val), lowest first.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2video.core.atomic import write_json  # noqa: E402
from motion2video.data.corpus import action_class  # noqa: E402
from motion2video.data.dataset import DEFAULT_MOCAP, build_dataset  # noqa: E402
from motion2video.data.windows import metric_vectors  # noqa: E402
from motion2video.models.checkpoint import load_model  # noqa: E402
from motion2video.stages.sampling import forecast, sample_futures  # noqa: E402

SAMPLERS = ("mtvae-add-dlow", "mixer-cvae-dlow", "mixture-dlow")
MEMBERS = ("mtvae-add-dlow", "mixer-cvae-dlow", "mtvae-add", "lcpvae", "behavior", "mixer-cvae")
SAMPLES = 50


def travel(features: np.ndarray) -> np.ndarray:
    """Distance (m) the pelvis travels over un-normalised body3d features (..., T, 51) -> (...)."""
    return np.linalg.norm(np.diff(features[..., 48:50], axis=-2), axis=-1).sum(-1)


def walking(models: tuple[str, ...], data: str) -> dict:
    first = load_model(models[0])
    dataset = build_dataset(data, first.data_config, split=first.meta.split, stats=first.stats)
    windows = dataset.windows("test", stride=16)
    idx = np.array([i for i, label in enumerate(windows.labels) if action_class(label) == "walk"])
    truth = travel(windows.raw[idx, windows.observed:])
    out = {"windows": int(len(idx)), "truth_travel_m": float(truth.mean()), "samplers": {}}
    joints = np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"]
    for name in models:
        bundle = load_model(name)
        futures = bundle.stats.denormalize(sample_futures(bundle.model, windows.obs[idx], num_samples=SAMPLES,
                                                          horizon=windows.features.shape[1] - windows.observed, seed=0))
        paths = travel(futures)  # (N, K)
        demo = forecast(bundle, joints, num_samples=10, start=24, seed=0)
        speed = np.linalg.norm(np.diff(demo.futures[:, :, 0, :2], axis=1), axis=-1).mean(axis=1) * demo.fps
        observed = np.linalg.norm(np.diff(demo.observed[:, 0, :2], axis=0), axis=-1).mean() * demo.fps
        out["samplers"][name] = {"median_travel_m": float(np.median(paths)),
                                 "share_half_the_truth": float((paths >= 0.5 * truth[:, None]).mean()),
                                 "demo_speed_mps": [float(v) for v in speed], "demo_observed_mps": float(observed)}
    return out


def mixtures(members: tuple[str, ...], data: str, split: str) -> list[dict]:
    first = load_model(members[0])
    dataset = build_dataset(data, first.data_config, split=first.meta.split, stats=first.stats)
    windows = dataset.windows(split, stride=16)
    to, horizon = windows.observed, windows.features.shape[1] - windows.observed
    truth = metric_vectors(windows.raw[:, to:], first.layout)
    last = metric_vectors(windows.raw[:, to - 1], first.layout)
    actions = np.array([action_class(label) for label in windows.labels])
    zero_ade = np.linalg.norm(last[:, None] - truth, axis=-1).mean(-1)
    zero_fde = np.linalg.norm(last - truth[:, -1], axis=-1)
    errors = {}
    for name in members:
        bundle = load_model(name)
        obs = bundle.stats.normalize(first.stats.denormalize(windows.obs))
        pred = metric_vectors(bundle.stats.denormalize(
            sample_futures(bundle.model, obs, num_samples=SAMPLES, horizon=horizon, seed=0)), first.layout)
        e = np.linalg.norm(pred - truth[:, None], axis=-1)  # (N, K, T)
        errors[name] = (e.mean(-1), e[..., -1])
    rows = []
    for size in (1, 2, 3):
        for parts in itertools.combinations(members, size):
            counts = [len(range(c, SAMPLES, size)) for c in range(size)]
            ade = np.concatenate([errors[p][0][:, :n] for p, n in zip(parts, counts)], axis=1).min(1)
            fde = np.concatenate([errors[p][1][:, :n] for p, n in zip(parts, counts)], axis=1).min(1)
            ratios = [(ade[actions == a].mean() / zero_ade[actions == a].mean(),
                       fde[actions == a].mean() / zero_fde[actions == a].mean()) for a in sorted(set(actions))]
            rows.append({"members": list(parts), "macro_ade": float(np.mean([r[0] for r in ratios])),
                         "macro_fde": float(np.mean([r[1] for r in ratios]))})
    return sorted(rows, key=lambda r: r["macro_ade"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(DEFAULT_MOCAP))
    parser.add_argument("--split", default="val", choices=("val", "test"), help="windows of the mixture search")
    parser.add_argument("--json", default=str(ROOT / "out" / "mixtures.json"))
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    start = time.time()
    walk = walking(SAMPLERS, args.data)
    print(f"{walk['windows']} held-out walking windows: the true pelvis travels {walk['truth_travel_m']:.2f} m")
    for name, r in walk["samplers"].items():
        print(f"  {name}: median {r['median_travel_m']:.2f} m, {r['share_half_the_truth']:.0%} of futures travel at "
              f"least half the truth's; demo walk ({r['demo_observed_mps']:.2f} m/s observed): "
              f"{min(r['demo_speed_mps']):.2f}-{max(r['demo_speed_mps']):.2f} m/s")
    rows = mixtures(MEMBERS, args.data, args.split)
    print(f"{len(rows)} equal-share mixtures on {args.split}, macro ADE / FDE ratio to zero-velocity, lowest first:")
    for r in rows[:8]:
        print(f"  {r['macro_ade']:.3f} / {r['macro_fde']:.3f}  {' + '.join(r['members'])}")
    out = write_json(args.json, {"walking": walk, "mixtures": rows, "split": args.split})
    print(f"wrote {out} in {time.time() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
