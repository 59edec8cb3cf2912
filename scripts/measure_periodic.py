"""Why mixture-periodic: the mirror-periodic rule alone, its share of a mixture, and its smoothing.

    python scripts/measure_periodic.py --json out/periodic.json

Prints markdown tables and writes --json (6 minutes alone on the 2 cores, 14 beside another job). Every row is scored as ``motion2video
evaluate`` scores (the shipped split's windows at stride 16, best of 50, seed 0, ratio to zero-velocity per action,
macro = the unweighted mean over actions), on validation (where the choices were made) and test:

1. ``mirror-periodic`` alone, 9 half-periods over 8-16 frames, raw (no smoothing) and as shipped;
2. mixtures of ``mtvae-add-dlow``, ``mixer-cvae-dlow`` (equal shares of what is left) and ``kp`` futures of the
   rule over a half-period range, kp in 0 (that is mixture-dlow), 5, 9, 12, 15 and three ranges;
3. the smoothing of the rule's seams at the chosen share, with the futures' velocity and acceleration against the
   truth's (all features, as ``evaluate`` reports them);
4. one future of the rule (best of 1): the half-period fitted to the observed frames (what K = 1 draws) against a
   fixed one of 12 or 16 frames.
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
from motion2video.models.checkpoint import ModelBundle, baseline_bundle, compose_mixture, load_model  # noqa: E402

PARTS = ("mtvae-add-dlow", "mixer-cvae-dlow")
SAMPLES = 50
SHARE_SCAN = [(0, 8.0, 16.0)] + [(kp, lo, 16.0) for kp in (5, 9, 12, 15) for lo in (6.0, 8.0, 10.0)]
SMOOTHING = (0.0, 1.0, 1.5, 2.0)
CHOSEN = (12, 8.0, 16.0)


def rule(first: ModelBundle, label: str, **config) -> ModelBundle:
    """``mirror-periodic`` with ``config`` in ``first``'s windows and statistics, labelled ``label``."""
    bundle = baseline_bundle("mirror-periodic", first.data_config, stats=first.stats, config=config)
    return replace(bundle, meta=replace(bundle.meta, model=label))


def mixture(parts: list[ModelBundle], label: str, kp: int, lo: float, hi: float, smooth: float = 1.5) -> ModelBundle:
    """The two samplers sharing 50 - kp futures equally (the first one more when odd) and kp of the rule."""
    if kp == 0:
        mix = compose_mixture(parts)
    else:
        first_share = (SAMPLES - kp + 1) // 2
        periodic = rule(parts[0], "mirror-periodic", min_half_period=lo, max_half_period=hi, smooth_frames=smooth)
        mix = compose_mixture(parts + [periodic], [first_share, SAMPLES - kp - first_share, kp])
    return replace(mix, meta=replace(mix.meta, model=label))


def score(bundles: list[ModelBundle], windows, samples: int = SAMPLES) -> dict[str, dict]:
    zero = baseline_bundle("zero-velocity", bundles[0].data_config, stats=bundles[0].stats)
    result = evaluate_bundles(bundles + [zero], windows, protocol=EvalProtocol(samples=samples, stride=16))
    zero_rows = result.per_action["zero-velocity"]
    return {b.label: {"ratios": ratios_to(result.per_action[b.label], zero_rows),
                      "velocity_ratio": result.results[b.label]["velocity_ratio"],
                      "acceleration_ratio": result.results[b.label]["acceleration_ratio"]} for b in bundles}


def table(title: str, rows: dict[str, dict], *, lively: bool = False) -> None:
    actions = list(next(iter(rows.values()))["ratios"])
    extra = " velocity / acceleration |" if lively else ""
    print(f"\n{title}\n\n| row | " + " | ".join(actions) + f" |{extra}")
    print("| --- |" + " ---: |" * (len(actions) + lively))
    for label, r in rows.items():
        cells = " | ".join(f"{r['ratios'][a][0]:.2f} / {r['ratios'][a][1]:.2f}" if a != "macro"
                           else f"{r['ratios'][a][0]:.3f} / {r['ratios'][a][1]:.3f}" for a in actions)
        tail = f" {r['velocity_ratio']:.2f} / {r['acceleration_ratio']:.2f} |" if lively else ""
        print(f"| {label} | {cells} |{tail}", flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(DEFAULT_MOCAP))
    parser.add_argument("--json", default=str(ROOT / "out" / "periodic.json"))
    args = parser.parse_args(argv)
    start = time.time()
    parts = [load_model(name) for name in PARTS]
    first = parts[0]
    dataset = build_dataset(args.data, first.data_config, split=first.meta.split, stats=first.stats)
    out: dict = {}
    for split in ("val", "test"):
        windows = dataset.windows(split, stride=16)
        alone = [rule(first, "mirror-periodic, raw", smooth_frames=0.0), rule(first, "mirror-periodic")]
        out[f"{split}/alone"] = score(alone, windows)
        table(f"{split} ({len(windows)} windows): the rule alone, 50 futures (half-periods spread over 8-16 frames)",
              out[f"{split}/alone"], lively=True)
        scan = [mixture(parts, f"{kp} of the rule, half-periods {lo:g}-{hi:g}" if kp else "no rule (mixture-dlow)",
                        kp, lo, hi) for kp, lo, hi in SHARE_SCAN]
        out[f"{split}/shares"] = score(scan, windows)
        table(f"{split}: shares of the rule in 50 futures", out[f"{split}/shares"])
        kp, lo, hi = CHOSEN
        smooth = [mixture(parts, f"smoothing {s:g} frames", kp, lo, hi, smooth=s) for s in SMOOTHING]
        out[f"{split}/smoothing"] = score(smooth, windows)
        table(f"{split}: the rule's seams smoothed ({kp} of 50 futures, half-periods {lo:g}-{hi:g})",
              out[f"{split}/smoothing"], lively=True)
        one = [rule(first, "fitted half-period (K = 1)")] + [
            rule(first, f"half-period {t:g} frames", min_half_period=t, max_half_period=t) for t in (12.0, 16.0)]
        out[f"{split}/one"] = score(one, windows, samples=1)
        table(f"{split}: one future of the rule", out[f"{split}/one"])
    path = write_json(args.json, out)
    print(f"\nwrote {path} in {time.time() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
