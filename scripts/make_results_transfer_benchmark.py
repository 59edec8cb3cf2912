"""Write the known-answer transfer benchmark and the liveliness / realism numbers into
docs/results_transfer.md, between the markers of its "Known-answer transfer on real motion" section (the
rest of the page is scripts/make_results_transfer.py's).

    python scripts/make_results_transfer_benchmark.py \
        --behavior before=out/behavior_before.safetensors --behavior after=behavior --analogy mtvae-add

Each ``--behavior LABEL=CHECKPOINT`` is a behaviour model to compare (a shipped name or a path); the
benchmark itself is :mod:`motion2video.evaluation.transfer_benchmark`, the liveliness and realism numbers
:func:`motion2video.evaluation.transfer.evaluate_transfer` on the held-out windows of the corpus's pinned
subject-disjoint split (the checkpoints' own split).
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import shlex
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

BEGIN = "<!-- transfer-benchmark:begin (scripts/make_results_transfer_benchmark.py) -->"
END = "<!-- transfer-benchmark:end -->"


def _pairs(values: list[str]) -> list[tuple[str, str]]:
    out = []
    for v in values:
        label, _, path = v.partition("=")
        if not path:
            raise SystemExit(f"--behavior wants LABEL=CHECKPOINT, got {v!r}")
        out.append((label, path))
    return out


def benchmark_rows(mocap: str, behaviors: list[tuple[str, str]], analogy: str | None, *, adapt_steps: int) -> dict:
    from motion2video.models.checkpoint import load_model
    from motion2video.evaluation import transfer_benchmark as B

    rows: dict[str, list[dict]] = {}
    for label, path in behaviors:
        res = B.run_benchmark(mocap, transfer=load_model(path), adapt_steps=adapt_steps)
        rows[f"transfer ({label})"] = [r for r in B.summarise(res) if r["method"] == "transfer"]
        rows["copy the source"] = [r for r in B.summarise(res) if r["method"] == "copy"]
    if analogy:
        res = B.run_benchmark(mocap, analogy=load_model(analogy))
        rows[f"analogy ({analogy})"] = [r for r in B.summarise(res) if r["method"] == "analogy"]
    return rows


_CLIPS: dict = {}  # data config -> the clips of the mocap folder, read once per config for every function below


def checkpoint_dataset(mocap: str, bundle):
    """The mocap folder as ``bundle`` sees it (its data config, split and normalisation), the files read once."""
    from motion2video.data.dataset import build_dataset, load_clips

    cfg = bundle.data_config
    if cfg not in _CLIPS:
        _CLIPS[cfg] = load_clips(mocap, config=cfg)
    return build_dataset(mocap, cfg, split=bundle.meta.split, stats=bundle.stats, clips=_CLIPS[cfg])


def liveliness(mocap: str, checkpoints: list[tuple[str, str]], *, stride: int, seed: int) -> dict:
    from motion2video.models.checkpoint import load_model
    from motion2video.evaluation.transfer import evaluate_transfer, transfer_pairs

    out = {}
    dataset = stats = None
    for label, path in checkpoints:
        bundle = load_model(path)
        if stats is None or not stats.same_as(bundle.stats):  # windows normalised with this checkpoint's statistics
            stats = bundle.stats
            dataset = checkpoint_dataset(mocap, bundle)
            test = dataset.windows("test", stride=stride)
            train = dataset.windows("train", stride=32)
            pairs = transfer_pairs(test.clip_names, seed=seed)
        s = evaluate_transfer(bundle, test, train, pairs=pairs, seed=seed)
        out[label] = {"motion": s.motion, "realism": s.realism, "realism_control": s.realism_control,
                      "realism_poses": s.realism_poses, "windows": s.windows}
    return out


def sampler_rows(mocap: str, checkpoints: list[tuple[str, str]], *, stride: int, samples: int, seed: int) -> dict:
    """Liveliness and realism of each model's sampled futures (what `sample` and `synthesize` draw) on the
    held-out windows: :func:`motion2video.evaluation.transfer.sample_realism`."""
    import dataclasses

    from motion2video.models.checkpoint import load_model
    from motion2video.evaluation.transfer import sample_realism

    out = {}
    for label, path in checkpoints:
        bundle = load_model(path)
        dataset = checkpoint_dataset(mocap, bundle)
        out[label] = dataclasses.asdict(sample_realism(bundle, dataset.windows("test", stride=stride),
                                                       samples=samples, seed=seed))
    return out


def classifier_controls(mocap: str, checkpoint: str, *, stride: int, seed: int = 0) -> dict:
    """The realism test's classifier (:mod:`motion2video.evaluation.realism`: logistic regression on per-window
    motion features, 5-fold cross-validated) with REAL motion on both sides: the held-out futures against
    (a) a random half of themselves (the test's own control), (b) the validation subjects' real futures (other
    people: what the retired full-descriptor classifier told apart with 0.99)."""
    import numpy as np

    from motion2video.models.checkpoint import load_model
    from motion2video.evaluation import realism as R

    bundle = load_model(checkpoint)
    dataset = checkpoint_dataset(mocap, bundle)
    to = bundle.data_config.observed
    dim = R.point_dim(bundle.layout.kind)
    real = R.motion_features(dataset.windows("test", stride=stride).raw[:, to:], dim=dim)
    other = R.motion_features(dataset.windows("val", stride=stride).raw[:, to:], dim=dim)
    x = np.concatenate([real, other])
    y = np.concatenate([np.ones(len(real), np.int64), np.zeros(len(other), np.int64)])
    return {"two random halves of the held-out futures (the control)":
            {"accuracy": R.real_vs_real_control(real, seed=seed), "items": [len(real) // 2, len(real) - len(real) // 2]},
            "the held-out futures against the validation subjects' real futures (other people)":
            {"accuracy": R.cross_validated_accuracy(x, y, np.arange(len(x)), seed=seed),
             "items": [len(real), len(other)]}}


def _table(rows: dict, split: str, key: str, fmt: str) -> list[str]:
    methods = list(rows)
    behaviours = [r["behaviour"] for r in next(iter(rows.values())) if r["split"] == split]
    lines = ["| behaviour (signature) | pairs | " + " | ".join(methods) + " |",
             "| --- | ---: | " + " | ".join("---:" for _ in methods) + " |"]
    for b in behaviours:
        cells = []
        n = sig = None
        for m in methods:
            r = next(r for r in rows[m] if r["split"] == split and r["behaviour"] == b)
            n, sig = r["pairs"], r["signature"]
            cells.append(fmt.format(**r))
        lines.append(f"| {b} ({sig}) | {n} | " + " | ".join(cells) + " |")
    return lines


def _relative_table(rows: dict, split: str) -> list[str]:
    """Per behaviour and method: the root-path signature's median ratio, then each root-relative one's."""
    from motion2video.evaluation import transfer_benchmark as B

    def cell(v: float) -> str:
        return "-" if v != v else f"{v:.2f}"

    names = list(B.RELATIVE)
    lines = ["| behaviour | method | root path (its signature) | " + " | ".join(n.replace("_", " ") for n in names)
             + " |", "| --- | --- | ---: | " + " | ".join("---:" for _ in names) + " |"]
    behaviours = [r["behaviour"] for r in next(iter(rows.values())) if r["split"] == split]
    for b in behaviours:
        for m, rs in rows.items():
            r = next(r for r in rs if r["split"] == split and r["behaviour"] == b)
            lines.append(f"| {b} | {m} | {r['median_ratio']:.2f} ({r['signature']}) | "
                         + " | ".join(cell(r["relative"][n]) for n in names) + " |")
    return lines


def render(bench: dict, live: dict, samplers: dict, controls: dict, *, command: str, seconds: float,
           adapt_steps: int) -> str:
    from motion2video.evaluation import transfer_benchmark as B

    import torch

    L = ["", "## Known-answer transfer on real motion", "",
         f"Generated by `{command}` on {datetime.date.today()} ({platform.machine()}, torch {torch.__version__}, "
         f"{seconds / 60:.1f} min).", "",
         "Behaviour windows with a measurable signature, cut from real clips "
         "(`motion2video/evaluation/transfer_benchmark.py`, `CASES`: the clip, start frame at 25 fps and why), "
         "each re-enacted from the start postures of clips of OTHER subjects (`TARGETS`). The number is the "
         "median over the pairs of signature(re-enactment) / signature(source), with the inter-quartile range: "
         "1.0 = the behaviour came across in full. Held-out = the pinned split's test subjects (CMU 2, 5, 7, "
         "131, 94), re-enacted from postures of other test subjects; training = training clips and postures. "
         "Signatures (`motion2video/evaluation/signatures.py`): jump = pelvis vertical range; kick = ankle "
         "height above the knee, from the hanging-shin position; walk/run = mean horizontal root speed; turn = "
         "net heading change; dance/martial arts = mean wrist/ankle speed relative to the pelvis.",
         "- transfer: the behaviour model, z = E(source window), decoded from the target posture "
         f"(as `motion2video transfer --adapt-steps {adapt_steps}`: "
         + ("the decoder as trained);" if adapt_steps == 0 else
            f"the decoder first fitted to each source for {adapt_steps} steps);"),
         "- analogy: MT-VAE A : B :: C : D, A = 16 frames before the source start (the first frame repeated "
         "where the clip starts there), C = 16 frames up to the target posture;",
         "- copy the source: the source moved rigidly onto the target's position and heading (ratio 1 by "
         "construction; it does not start from the target's posture).", "",
         "Root-relative signatures (`signatures.ROOT_RELATIVE_SIGNATURES`), each the range over the "
         "window of a distance measured on the body, so a re-enactment carried along the source's root path "
         "gets no credit for the path itself: leg extension = pelvis height above the ankles' mean height; arm "
         "swing = wrist height relative to the thorax (the larger of the two wrists); knee bend = hip-to-ankle "
         "distance (the larger of the two legs); ankle lift = ankle height relative to the pelvis (the kick "
         "measured from the body). Ratios as above; '-' where no source of the row moves that way by "
         f"{B.MIN_RELATIVE_AMPLITUDE:.2f} m or more. Target for held-out jumps and kicks: every median between 0.6 "
         "and 1.4.", ""]
    for split in ("held-out", "train"):
        L += [f"### Signature ratio, {split} clips (median [IQR])", ""]
        L += _table(bench, split, "ratio", "{median_ratio:.2f} [{q25:.2f}, {q75:.2f}]")
        L.append("")
    for split in ("held-out", "train"):
        L += [f"### Root-relative signatures beside the root-path one, {split} clips (median ratio)", ""]
        L += _relative_table(bench, split)
        L.append("")
    L += ["### Start posture and rigid bones, held-out clips", "",
          "Start error: mean per-joint distance (m) between the first generated frame and the target posture "
          "(root-relative, heading-aligned; real motion moves about 0.01-0.03 m per frame). Bone spread: the "
          "largest per-bone s.d. / mean length over the generated frames (real mocap < 0.01). Medians over "
          "the pairs. Every behaviour-model row goes through what `motion2video transfer` does to its output: "
          "bones rescaled to the start posture's lengths and ankles kept above the start's lower ankle by leg IK "
          "(`motion2video.stages.latents.rigid_bones`); the analogy rows are the raw decoder output.", ""]
    L += _table(bench, "held-out", "start", "{start_error:.3f} m / {bone_spread:.3f}")
    L.append("")
    if live:
        first = next(iter(live.values()))
        real_v, real_a = first["motion"]["real"]
        L += ["### Liveliness and realism", "",
              f"Held-out windows of the corpus's pinned split ({first['windows']} windows, 16 observed + 48 "
              "future frames); `motion2video.evaluation.transfer.evaluate_transfer`: self = reconstruction, "
              "transfer = re-enacted from another held-out clip's window, prior = z ~ N(0, I), flow = z = "
              "T^-1(u). Mean absolute velocity / acceleration of the features per frame (m/frame, m/frame^2; "
              f"held-out ground truth **{real_v:.4f} / {real_a:.4f}**), and their ratio to the ground truth "
              "(target: within 0.8-1.2). Realism: the two-sample test "
              "(`motion2video.evaluation.realism`): a logistic regression on per-window motion features (per "
              "joint: mean speed, mean acceleration, positional spread), 5-fold cross-validated over the windows, "
              "tells the real futures from the generated futures of the same windows; its held-out accuracy "
              "(0.5 = indistinguishable; target <= 0.75) and its control, real against real of the same windows "
              f"split in two halves (**{first['realism_control']:.2f}**, about 0.5 as it must be). Last column: "
              "a ridge classifier on poses alone (even windows train, odd test).",
              "", "| model | origin | velocity / acceleration | vs real | two-sample test | classifier (poses) |",
              "| --- | --- | ---: | ---: | ---: | ---: |"]
        for label, d in live.items():
            for origin, (v, a) in d["motion"].items():
                if origin == "real":
                    continue
                L.append(f"| {label} | {origin} | {v:.4f} / {a:.4f} | {v / real_v:.2f} / {a / real_a:.2f} | "
                         f"{d['realism'][origin]:.2f} | {d['realism_poses'][origin]:.2f} |")
        L.append("")
    if samplers:
        first = next(iter(samplers.values()))
        real_v, real_a = first["real"]
        L += ["### Sampled futures of the shipped body models: liveliness and realism", "",
              f"What `sample` and `synthesize` draw: {first['samples_per_window']} futures per held-out window "
              f"({first['windows']} windows; behavior: flow samples). Mean absolute velocity / acceleration of "
              f"the features per frame over all samples (held-out ground truth **{real_v:.4f} / {real_a:.4f}**) "
              "and their ratio to it (target 0.8-1.2; the 2D model's in virtual-camera image heights, against its "
              "own ground truth); the two-sample realism test (above) and the pose classifier on one sample per window, "
              "with the test's real-vs-real control. "
              "'before' = the checkpoints shipped before the liveliness term (git 96e5d78), 'after' = shipped now.",
              "Beside it, the test on one family of features alone (speeds / accelerations / positional spreads of "
              "the 17 points), which says what kind of difference gives the generated futures away.",
              "", "| model | velocity / acceleration | vs real | two-sample test | control | speed / accel. / spread alone "
              "| classifier (poses) |",
              "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
        for label, d in samplers.items():
            v, a = d["samples"]
            rv, ra = d["real"]  # each model's own ground truth (a 2D model's is in image units)
            L.append(f"| {label} | {v:.4f} / {a:.4f} | {v / rv:.2f} / {a / ra:.2f} | "
                     f"{d['realism']:.2f} | {d['realism_control']:.2f} | "
                     + " / ".join(f"{v:.2f}" for v in d["realism_by_family"].values())
                     + f" | {d['realism_poses']:.2f} |")
        L.append("")
    if controls:
        L += ["### What the realism test's classifier says about real motion", "",
              "The two-sample test's classifier and folds with real motion capture on both sides:", "",
              "| the two classes (all real motion) | items | held-out accuracy |", "| --- | ---: | ---: |"]
        for what, d in controls.items():
            L.append(f"| {what} | {d['items'][0]} / {d['items'][1]} | {d['accuracy']:.2f} |")
        L += ["", "The retired realism classifier (a ridge classifier on the full sequence descriptor: poses every "
              "4th frame, mean absolute velocity and acceleration, standard deviations) told the held-out subjects' "
              "real futures from the validation subjects' with accuracy 0.99: it measured who moves and what they "
              "do, not whether the motion is real. The two-sample test compares the real and the generated futures "
              "of the same observed windows, so who moves and what they do are the same in both classes; the "
              "second row shows how much other people's real motion differs in the same features.", ""]
    L += ["Cases:", ""]
    L += [f"- {c.split}, {c.behaviour}: `{c.clip}` from frame {c.start} (25 fps), {c.horizon} frames: {c.why}"
          for c in B.CASES]
    return "\n".join(L) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--behavior", action="append", default=[], help="LABEL=CHECKPOINT (repeatable)")
    parser.add_argument("--analogy", default="mtvae-add", help="MT-VAE checkpoint for the analogy ('' = none)")
    parser.add_argument("--no-liveliness", action="store_true", help="skip the held-out liveliness numbers")
    parser.add_argument("--stride", type=int, default=8, help="frames between held-out windows (liveliness)")
    parser.add_argument("--sampler", action="append", default=[],
                        help="LABEL=CHECKPOINT whose sampled futures are measured (repeatable)")
    parser.add_argument("--samples", type=int, default=10, help="futures per window for --sampler")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--adapt-steps", type=int, default=None,
                        help="decoder adaptation steps of the transfer rows (default: motion2video transfer's)")
    parser.add_argument("--out", default=str(ROOT / "docs" / "results_transfer.md"))
    parser.add_argument("--json", default=None, help="also write the raw numbers here")
    args = parser.parse_args(argv)
    behaviors = _pairs(args.behavior) or [("shipped", "behavior")]
    t0 = time.time()
    from motion2video.stages.latents import ADAPT_STEPS

    adapt_steps = ADAPT_STEPS if args.adapt_steps is None else args.adapt_steps
    bench = benchmark_rows(args.data, behaviors, args.analogy or None, adapt_steps=adapt_steps)
    live = {}
    if not args.no_liveliness:
        models = [(f"behavior ({label})", path) for label, path in behaviors]
        if args.analogy:
            models.append((args.analogy, args.analogy))
        live = liveliness(args.data, models, stride=args.stride, seed=args.seed)
    samplers = sampler_rows(args.data, _pairs(args.sampler), stride=args.stride, samples=args.samples,
                            seed=args.seed)
    controls = classifier_controls(args.data, behaviors[-1][1], stride=args.stride) if samplers else {}
    command = "python scripts/make_results_transfer_benchmark.py " + " ".join(
        [f"--behavior {label}={path}" for label, path in behaviors]
        + ([f"--analogy {args.analogy}"] if args.analogy != "mtvae-add" else [])
        + [f"--sampler {shlex.quote(v)}" for v in args.sampler]
        + ([f"--adapt-steps {args.adapt_steps}"] if args.adapt_steps is not None else []))
    from motion2video.core.atomic import write_section

    section = render(bench, live, samplers, controls, command=command, seconds=time.time() - t0,
                     adapt_steps=adapt_steps)
    write_section(Path(args.out), BEGIN, END, section)
    if args.json:
        Path(args.json).write_text(json.dumps({"benchmark": bench, "liveliness": live, "samplers": samplers,
                                               "controls": controls}, indent=1))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
