"""Regenerate the results tables of docs/ from real runs, one sub-command per table (each writes its section of
the page between its markers and keeps the rest, and the raw numbers as JSON under out/).

    python scripts/make_results.py forecasting        # the three papers' models on the 5-minute set
    python scripts/make_results.py card --checkpoint motion2video/weights/mtvae-add.safetensors \\
        --eval out/mtvae-add.eval.json --command "..."    # one model card (scripts/train_shipped.sh calls this)
    python scripts/make_results.py corpus             # LCP-VAE's learned prior: the 5-minute model against the shipped one
    python scripts/make_results.py known-answer       # the known-answer multimodal benchmark of the latent models
    python scripts/make_results.py per-action         # every body model per action (ADE / FDE to zero-velocity)
    python scripts/make_results.py five-minute-models # retrain the 5-minute models (per-action, corpus, forecasting)
    python scripts/make_results.py skeleton-figure    # docs/images/skeletons.png
    python scripts/make_results.py frames             # the keypoint warp body generator, with baselines
    python scripts/make_results.py frames-analysis    # where a warp body generator's error comes from
    python scripts/make_results.py frames-real        # the frame generator driven by held-out real mocap
    python scripts/make_results.py transfer           # behaviour transfer and analogy (docs/results_transfer.md)
    python scripts/make_results.py transfer-benchmark # liveliness of the sampled futures and of transfers
    python scripts/make_results.py face-sheet CLIP PHOTO... -o SHEET.png  # the photo's face over the generated heads
    python scripts/make_results.py transfer-unseen    # behaviour transfer on clips the behaviour model never saw
    python scripts/make_results.py bandai             # the samplers retrained with Bandai-Namco beside the shipped

``python scripts/make_results.py SUB-COMMAND --help`` gives each one's options, cost and outputs.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import json
import platform
import shlex
import subprocess
import sys
import tempfile
import textwrap
import time
from collections import Counter
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from motion2video.core.atomic import check_section, write_json, write_section, write_text
from motion2video.core.errors import InputError
from motion2video.core.skeletons import (H36M_17, H36M_BONES_MM, H36M_LEG_MM, L_ANKLE, L_HIP, PELVIS, R_ANKLE, R_HIP,
                                         leg_length, proportion_ratios)
from motion2video.data.dataset import (DEFAULT_MOCAP, MULTIMODAL_SOURCE, DatasetConfig, WindowSet,
                                       build_dataset, decode_samples)
from motion2video.data.multimodal import MultimodalBenchmark, score_futures
from motion2video.evaluation.forecasting import EvalProtocol, evaluate_bundles
from motion2video.evaluation.per_action import COUNT_KEY
from motion2video.formats.io import load_motion
from motion2video.generator.image_baselines import run_baseline
from motion2video.generator.checkpoint import load_frame_model
from motion2video.generator.data import default_cache_dir, evaluation_pair_index, load_or_generate, make_pairs
from motion2video.generator.scores import frame_metrics, region_psnr, sharpness_ratio
from motion2video.generator.model import images_to_tensor, tensor_to_images
from motion2video.generator.specs import default_spec
from motion2video.generator.warp import WarpGenerator, warp_image
from motion2video.models.base import MODEL_REGISTRY
from motion2video.models.baselines import BASELINES
from motion2video.models.checkpoint import WEIGHTS_DIR, baseline_bundle, load_model
from motion2video.models.training import TrainConfig, train_model
from motion2video.stages.sampling import sample_futures
from motion2video.apps.transfer import TransferResult, render_transfer
from motion2video.evaluation import signatures as S
from motion2video.evaluation.transfer_benchmark import MIN_RELATIVE_AMPLITUDE
from motion2video.formats.video import write_image
from motion2video.stages.clips import load_clip
from motion2video.stages.latents import (ADAPT_STEPS, adapt_to_source, behavior_latents, behavior_model,
                                         behavior_root, decode_sequences, encode_sequences, reenact, reenact_source,
                                         rigid_bones)

ROOT = Path(__file__).resolve().parents[1]


def _wrap(paragraph: str) -> list[str]:
    """The lines of a generated paragraph, broken as the hand-written text of docs/ is (at most 115 characters)."""
    return textwrap.wrap(paragraph, width=115, break_long_words=False, break_on_hyphens=False)



# ----------------------------------------------------------------------------------------------------------------
# forecasting: The three papers' models compared on the 5-minute set: held-out and known-answer numbers.
# ----------------------------------------------------------------------------------------------------------------


FORECASTING_DOC = """The three papers' models on the 5-minute set: held-out forecasting and the known-answer benchmark.

    python scripts/make_results.py forecasting --mm-steps 2000 --mm-steps-for cvae=4000 --mm-steps-for behavior=4000
    python scripts/make_results.py card --checkpoint motion2video/weights/mtvae-add.safetensors \\
        --eval out/mtvae-add.eval.json --command "..."    # one model card (train_shipped.sh calls this)

The reference models are mtvae-add, lcpvae and behavior of --weights (default out/five_minute: the 72-clip,
4.7-minute recipe retrained on today's joints by ``scripts/make_results.py five-minute-models``); only the
clips their recorded split names are used. ``forecasting`` does, in order (checkpoints it trains go to --runs,
default runs/results, and are reused):

1. trains the comparison models of MT-VAE's Table 1 that are not among them (pred-lstm, cvae, mtvae-concat)
   with mtvae-add's sizes, data, split, steps and seed;
2. evaluates the six models and zero-velocity on the held-out test windows of that split (best of 50, stride
   16): ADE, FDE, APD, and MT-VAE's R-MSE / S-MSE;
3. trains every stochastic model on the known-answer multimodal benchmark (``--mm-steps``, seed 0) and scores
   coverage and precision at K = 10.

It writes the table between ``<!-- motion-models:begin -->`` and ``<!-- motion-models:end -->`` of
docs/results.md ("The three papers' models on the first 4.7 minutes") and the raw numbers to
out/results_forecasting.json.

Cost: about 25 minutes on 2 cores with the page's options, two processes at a time. Checkpoints already in
--runs are reused, so an interrupted run continues where it stopped.
"""


FORECASTING_BEGIN, FORECASTING_END = "<!-- motion-models:begin -->", "<!-- motion-models:end -->"


TABLE1 = ("pred-lstm", "cvae", "mtvae-concat", "mtvae-add")


STOCHASTIC = ("cvae", "mtvae-concat", "mtvae-add", "lcpvae", "behavior")


BODY_MODELS = ("pred-lstm", *STOCHASTIC)  # the table's rows, then zero-velocity


MM_CONFIG = DatasetConfig(speed=0.0)  # benchmark clips are exactly one window long


NUMBER_WORDS = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine")


def _forecasting_fmt(v, digits: int = 3) -> str:
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    return f"{v:.{digits}f}"


def _forecasting_md_table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(_forecasting_fmt(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


SHIPPED_DIR = [ROOT / "out" / "five_minute"]  # --weights replaces it



def _card_metrics(ev: dict, res: dict) -> list[str]:
    """A model card's "Metrics" lines from an ``evaluate --json`` payload ``ev`` and its ``results`` ``res``."""
    return [
        "## Metrics",
        "",
        f"Held-out test windows: {ev['protocol']['windows']} from {', '.join(ev['protocol']['clips'])}; best of "
        f"{ev['protocol']['samples']}; units: {ev['protocol']['units']}.",
        "",
        _forecasting_md_table(["method", "ADE", "FDE", "MMADE", "MMFDE", "APD"],
                              [[n, r["ade"], r["fde"], r["mmade"], r["mmfde"], r["apd"]] for n, r in res.items()]),
        "",
    ]

def shipped_path(name: str) -> Path:
    path = SHIPPED_DIR[0] / f"{name}.safetensors"
    if not path.is_file():
        raise InputError("missing reference checkpoint: run `python scripts/make_results.py five-minute-models` "
                         "(or give --weights)", path)
    return path


def comparison_config(reference, model_name: str) -> dict:
    """The reference model's sizes, restricted to the fields ``model_name``'s config has."""
    fields = {f.name for f in dataclasses.fields(MODEL_REGISTRY[model_name].config_cls)}
    return {k: v for k, v in reference.meta.config.items()
            if k in fields and k in ("hidden_dim", "latent_dim", "mlp_dim", "layer_norm")}


@dataclasses.dataclass(frozen=True)
class TrainTask:
    """One model to train for the results (rebuilt from its data source in a worker process); with a ``split``,
    only the clips it names are loaded."""

    model: str
    out: Path
    data: str
    data_config: DatasetConfig
    model_config: dict
    train_config: TrainConfig
    split: dict | None = None


def _run_task(task: TrainTask) -> str:
    from motion2video.data.dataset import Split

    torch.set_num_threads(1)
    split = None if task.split is None else Split.from_dict(task.split)
    dataset = build_dataset(task.data, task.data_config, split=split, recorded_only=split is not None)
    t0 = time.perf_counter()
    train_model(model_name=task.model, model_config=task.model_config, dataset=dataset, config=task.train_config,
                out=task.out, progress=False)
    return f"trained {task.out} in {time.perf_counter() - t0:.0f} s"


def run_tasks(tasks: list[TrainTask], *, jobs: int) -> None:
    """Train every task whose checkpoint does not exist yet, ``jobs`` processes at a time."""
    import multiprocessing

    pending = [t for t in tasks if not t.out.is_file()]
    for t in tasks:
        if t.out.is_file():
            print(f"reusing {t.out}")
    if not pending:
        return
    print(f"training {len(pending)} models, {jobs} at a time: {', '.join(t.out.name for t in pending)}", flush=True)
    if jobs <= 1:
        for t in pending:
            print(_run_task(t), flush=True)
        return
    with multiprocessing.get_context("spawn").Pool(jobs) as pool:
        for message in pool.imap_unordered(_run_task, pending):
            print(message, flush=True)


def body_tasks(runs: Path, *, steps: int | None = None) -> list[TrainTask]:
    """pred-lstm, cvae and mtvae-concat with the reference mtvae-add's sizes, data, split, steps and seed
    (``steps`` overrides the step count, for smoke runs)."""
    ref = load_model(shipped_path("mtvae-add"))
    train_cfg = TrainConfig(**ref.meta.training["config"])
    if steps is not None:
        train_cfg = dataclasses.replace(train_cfg, steps=steps)
    return [TrainTask(model=name, out=runs / f"{name}.safetensors", data=str(DEFAULT_MOCAP),
                      data_config=ref.data_config, model_config=comparison_config(ref, name),
                      train_config=train_cfg, split=ref.meta.split.to_dict())
            for name in ("pred-lstm", "cvae", "mtvae-concat")]


def multimodal_tasks(runs: Path, *, steps: int, steps_for: dict[str, int] | None = None) -> list[TrainTask]:
    """Every stochastic model on the known-answer benchmark, reference sizes, ``steps`` steps (``steps_for``
    overrides it per model; such a checkpoint is named ``mm-NAME-STEPSsteps``), seed 0."""
    ref = load_model(shipped_path("mtvae-add"))
    tasks = []
    for name in STOCHASTIC:
        n = (steps_for or {}).get(name, steps)
        suffix = "" if n == steps else f"-{n}steps"
        model_cfg = comparison_config(ref, name) if name in TABLE1 else {
            k: v for k, v in load_model(shipped_path(name)).meta.config.items() if k != "feature_dim"}
        tasks.append(TrainTask(model=name, out=runs / f"mm-{name}{suffix}.safetensors", data=MULTIMODAL_SOURCE,
                               data_config=MM_CONFIG, model_config=model_cfg,
                               train_config=TrainConfig(steps=n, batch_size=64, checkpoint_every=max(n // 2, 1),
                                                        val_every=0, flow_steps=500, seed=0)))
    return tasks


def evaluate_body(runs: Path, record: dict, *, samples: int) -> tuple[dict, dict, dict]:
    """The six models and zero-velocity on the held-out test windows of the reference split (recorded clips
    only). Returns (results: name -> metrics, evaluate's protocol, the dataset summary)."""
    ref = load_model(shipped_path("mtvae-add"))
    cfg = ref.data_config
    dataset = build_dataset(DEFAULT_MOCAP, cfg, split=ref.meta.split, stats=ref.stats, recorded_only=True)
    paths = {name: shipped_path(name) for name in ("mtvae-add", "lcpvae", "behavior")}
    paths.update({t.model: t.out for t in body_tasks(runs)})
    bundles = []
    for name in BODY_MODELS:
        b = load_model(paths[name])
        if b.data_config != cfg or not np.allclose(b.stats.mean, ref.stats.mean):
            raise InputError("trained on other data settings than the reference mtvae-add", paths[name])
        bundles.append(b)
    bundles.append(baseline_bundle("zero-velocity", cfg, stats=ref.stats))
    test = dataset.windows("test", stride=16)
    protocol = EvalProtocol(samples=samples, stride=16, split="test", seed=0)
    t0 = time.perf_counter()
    result = evaluate_bundles(bundles, test, protocol=protocol, extended=True)
    record["body3d"] = {**result.to_json(), "eval_seconds": time.perf_counter() - t0, "data": dataset.summary}
    return result.results, result.protocol, dataset.summary


def score_multimodal(runs: Path, record: dict, *, steps: int, steps_for: dict[str, int] | None = None
                     ) -> dict[str, tuple[dict, int]]:
    """Known-answer coverage / precision / TV at K = 10 of every stochastic model: name -> (scores, steps)."""
    test = build_dataset(MULTIMODAL_SOURCE, MM_CONFIG).windows("test")
    out = {}
    for task in multimodal_tasks(runs, steps=steps, steps_for=steps_for):
        sc = score(task.out, test)
        record.setdefault("multimodal", {})[task.model] = {**sc, "steps": task.train_config.steps}
        out[task.model] = (sc, task.train_config.steps)
    return out


def _held_out_clips(clips: list[str]) -> str:
    """"CMU subjects 131 and 16 and two single clips" for the test clips ``clips`` (``source/NAME.bvh``)."""
    subjects = list(dict.fromkeys(c.split("/")[1].split("_")[0] for c in clips if c.startswith("cmu/")))
    others = sum(not c.startswith("cmu/") for c in clips)
    parts = []
    if subjects:
        named = subjects[0] if len(subjects) == 1 else ", ".join(subjects[:-1]) + f" and {subjects[-1]}"
        parts.append(f"CMU subject{'s' if len(subjects) > 1 else ''} {named}")
    if others:
        word = NUMBER_WORDS[others] if others < len(NUMBER_WORDS) else str(others)
        parts.append(f"{word} single clip{'s' if others > 1 else ''}")
    return " and ".join(parts)


def forecasting_section(results: dict, protocol: dict, summary: dict, multimodal: dict[str, tuple[dict, int]], *,
                        command: str, samples: int, split_seed: int, mm_steps: int) -> str:
    """The block between the motion-models markers of docs/results.md (no heading: the page's stands above it)."""
    rows = []
    for name in (*BODY_MODELS, "zero-velocity"):
        r = results[name]
        known = "-"
        if name in multimodal:
            sc, n = multimodal[name]
            known = f"{sc['coverage']:.3f} / {sc['precision']:.3f}" + (f" ({n} steps)" if n != mm_steps else "")
        rows.append(f"| {name} | {r['ade']:.3f} | {r['fde']:.3f} | {r['apd']:.3f} | {_forecasting_fmt(r.get('r_mse'))} "
                    f"| {_forecasting_fmt(r.get('s_mse'))} | {known} |")
    minutes = summary["frames"] / summary["fps"] / 60
    text = (f"The paper reproductions (pred-lstm, cVAE, MT-VAE concat / add, LCP-VAE, the behaviour model) compared "
            f"on the first {summary['clips']} clips ({minutes:.1f} minutes, `split_seed` {split_seed}: "
            f"{protocol['windows']} windows of {_held_out_clips(protocol['clips'])}; best of {samples}, metres). "
            f"`{command}` trains them all (about 25 minutes on 2 cores):")
    return "\n".join([*_wrap(text), "",
                      "| method | ADE | FDE | APD | R-MSE | S-MSE | known-answer coverage / precision |",
                      "|---|---:|---:|---:|---:|---:|---|", *rows])


def cmd_results(args: argparse.Namespace) -> int:
    check_section(args.doc, FORECASTING_BEGIN, FORECASTING_END)
    torch.set_num_threads(1)
    SHIPPED_DIR[0] = Path(args.weights)
    runs = Path(args.runs)
    runs.mkdir(parents=True, exist_ok=True)
    record: dict = {"started": time.strftime("%Y-%m-%d %H:%M:%S")}
    t0 = time.perf_counter()
    steps_for = dict((name, int(n)) for name, n in (item.split("=") for item in args.mm_steps_for))
    run_tasks(body_tasks(runs, steps=args.body_steps)
              + multimodal_tasks(runs, steps=args.mm_steps, steps_for=steps_for), jobs=args.jobs)
    record["training_seconds"] = time.perf_counter() - t0
    results, protocol, summary = evaluate_body(runs, record, samples=args.samples)
    multimodal = score_multimodal(runs, record, steps=args.mm_steps, steps_for=steps_for)
    command = "python scripts/make_results.py forecasting" + "".join(
        f" --{k.replace('_', '-')} {getattr(args, k)}" for k in ("weights", "samples", "mm_steps", "body_steps")
        if getattr(args, k) != args.default_of(k)) + "".join(f" --mm-steps-for {v}" for v in args.mm_steps_for)
    split_seed = load_model(shipped_path("mtvae-add")).data_config.split_seed
    write_section(args.doc, FORECASTING_BEGIN, FORECASTING_END, forecasting_section(
        results, protocol, summary, multimodal, command=command, samples=args.samples, split_seed=split_seed,
        mm_steps=args.mm_steps))
    record["wall_time_s"] = time.perf_counter() - t0
    write_json(args.json, json.loads(json.dumps(record, default=str)))
    print(f"wrote {args.doc} and {args.json}")
    return 0


def _sources(source) -> str:
    """A checkpoint's recorded data source: one folder, or the folders of a joined corpus as ``A + B``."""
    if isinstance(source, str) and source.startswith("["):  # a joined corpus recorded as the list's text
        source = ast.literal_eval(source)
    return " + ".join(map(str, source)) if isinstance(source, (list, tuple)) else str(source)


def cmd_card(args: argparse.Namespace) -> int:
    """Write ``weights/<name>.md`` for a trained checkpoint from its metadata and an evaluate JSON."""
    path = Path(args.checkpoint)
    bundle = load_model(path)
    meta = bundle.meta
    ev = json.loads(Path(args.eval).read_text())
    res = ev["results"]
    tr = meta.training
    summary = meta.data_summary
    size_mb = path.stat().st_size / 2 ** 20
    lines = [
        f"# {path.stem}",
        "",
        f"Model `{meta.model}` ({meta.kind}), layout `{meta.data_config.layout}` "
        f"({meta.data_config.feature_layout.num_features} features per frame), {size_mb:.1f} MB, "
        f"{sum(p.numel() for p in bundle.model.parameters()):,} parameters, motion2video {meta.version}.",
        "",
        "## Command",
        "",
        f"```\n{args.command}\n```",
        "",
        "## Data",
        "",
        f"{_sources(summary.get('source'))}: {summary.get('clips')} clips, {summary.get('frames')} frames at "
        f"{summary.get('fps')} fps; split train/val/test clips "
        + "/".join(str(summary['per_split'][s]['clips']) for s in ('train', 'val', 'test'))
        + f" (held-out test groups: {', '.join(summary.get('test_groups', []))}). Windows of "
        f"{meta.data_config.observed} observed + {meta.data_config.future} future frames; augmentation: "
        f"mirror={meta.data_config.mirror}, speed +-{meta.data_config.speed:.0%}"
        + (f", canonical heading={meta.data_config.canonical_heading}." if meta.layout.is_body
           else f"; head pose: {meta.data_config.face_head_pose}."),
        "",
        "## Training",
        "",
        f"{tr.get('steps')} steps, batch {tr['config']['batch_size']}, AdamW lr {tr['config']['lr']}, seed "
        f"{tr.get('seed')}, wall time {tr.get('wall_time_s', 0) / 60:.1f} min on CPU (torch {tr.get('torch')}); "
        f"final train loss {_forecasting_fmt(tr.get('train_loss'))}, validation loss {_forecasting_fmt(tr.get('val_loss'))}.",
        "",
        "Model config:",
        "",
        "```json\n" + json.dumps(meta.config, indent=1) + "\n```",
        "",
        *_card_metrics(ev, res),
    ]
    out = WEIGHTS_DIR / f"{path.stem}.md" if args.out is None else Path(args.out)
    # The data licence block is scripts/shipped_licences.py's (write_section needs its markers): an existing
    # card's is kept, a new card gets the empty marker pair for it to fill.
    from motion2video.data.licences import CARD_BEGIN, CARD_END

    licence = f"{CARD_BEGIN}\n{CARD_END}"
    if out.is_file() and CARD_BEGIN in (old := out.read_text()) and CARD_END in old.split(CARD_BEGIN, 1)[1]:
        licence = CARD_BEGIN + old.split(CARD_BEGIN, 1)[1].split(CARD_END, 1)[0] + CARD_END
    write_text(out, "\n".join(lines) + "\n" + licence + "\n")
    print(f"wrote {out}")
    return 0


def forecasting_main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=FORECASTING_DOC.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    r = sub.add_parser("forecasting", help="regenerate the three papers' models table of docs/results.md")
    r.add_argument("--runs", default="runs/results", help="where comparison models are trained / reused")
    r.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    r.add_argument("--json", default=str(ROOT / "out" / "results_forecasting.json"))
    r.add_argument("--samples", type=int, default=50, help="K for the held-out evaluation (default 50)")
    r.add_argument("--mm-steps", type=int, default=4000,
                   help="training steps per model on the benchmark (default 4000; cvae reached coverage 0.90 / "
                   "precision 0.99 at 3000 in development)")
    r.add_argument("--mm-steps-for", action="append", default=[], metavar="MODEL=STEPS",
                   help="train one model longer (or shorter) on the benchmark, e.g. cvae=4000 (repeatable)")
    r.add_argument("--body-steps", type=int, default=None,
                   help="steps of the comparison models (default: the reference mtvae-add's; lower only for smoke runs)")
    r.add_argument("--jobs", type=int, default=2, help="models trained in parallel (one torch thread each)")
    r.add_argument("--weights", default=str(SHIPPED_DIR[0]),
                   help="folder of the reference mtvae-add, lcpvae and behavior (default: the 5-minute models that "
                   "`make_results.py five-minute-models` writes)")
    r.set_defaults(run=cmd_results, default_of=r.get_default)
    c = sub.add_parser("card", help="write a model card for a trained checkpoint")
    c.add_argument("--checkpoint", required=True)
    c.add_argument("--eval", required=True, help="the JSON of `motion2video evaluate --json`")
    c.add_argument("--command", required=True, help="the command that trained it")
    c.add_argument("--out", default=None, help="default: motion2video/weights/<name>.md")
    c.set_defaults(run=cmd_card)
    args = p.parse_args(argv)
    return args.run(args)


# ----------------------------------------------------------------------------------------------------------------
# corpus: The body models trained on the whole corpus, against the 5-minute models they replace.
# ----------------------------------------------------------------------------------------------------------------


CORPUS_DOC = """LCP-VAE's learned prior: the 5-minute model against the corpus model that ships.

    python scripts/make_results.py corpus     # after scripts/train_shipped.sh and make_results.py five-minute-models

For the 5-minute lcpvae (the 72-clip recipe of git 805c753 with the paper's weights, retrained on today's joints
by ``scripts/make_results.py five-minute-models``; --five-minute) and the shipped corpus lcpvae (--weights), each
on its held-out test windows of the corpus's pinned test subjects (the 5-minute model's test split keeps out
CMU subjects 5, 6 and 7, which it trained on): the mean width sigma_c of q(z_c | obs), its KL to N(0, I), and
APD of 50 futures with z from the learned prior and from N(0, I). Writes the table between
``<!-- corpus-models:begin -->`` and ``<!-- corpus-models:end -->`` of docs/results.md ("LCP-VAE's learned
prior") and the raw numbers to out/results_corpus.json. A few minutes on one thread.
"""

CORPUS_BEGIN, CORPUS_END = "<!-- corpus-models:begin -->", "<!-- corpus-models:end -->"


OLD = ("mtvae-add", "lcpvae", "behavior")


OLD_REV = "805c753"  # the last commit whose motion2video/weights held the 72-clip (5-minute) models


def _corpus_fmt(v, digits: int = 3) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def _corpus_md_table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        lines.append("| " + " | ".join(_corpus_fmt(c) if isinstance(c, float) else str(c) for c in row) + " |")
    return "\n".join(lines)


def _corpus_subset(windows: WindowSet, keep: np.ndarray) -> WindowSet:
    """The windows where ``keep`` (N,) is true."""
    frames = windows.frames
    if frames is not None:
        frames = dataclasses.replace(frames, origin=frames.origin[keep], angle=frames.angle[keep])
    idx = np.flatnonzero(keep)
    return dataclasses.replace(windows, features=windows.features[keep], raw=windows.raw[keep], frames=frames,
                               clip_names=tuple(windows.clip_names[i] for i in idx), starts=windows.starts[keep],
                               labels=tuple(windows.labels[i] for i in idx))


def lcp_diagnosis(old: Path, new: Path, clips: set[str], record: dict, *, samples: int = 50) -> str:
    """The width of the learned prior q(z_c | obs) of the 5-minute LCP-VAE (``old``) and the shipped one
    (``new``), its KL to N(0, I), and APD when the same decoder samples z from the learned prior or from
    N(0, I); each model on its own held-out test windows (stride 16) of ``clips``. Returns the page's block."""
    from motion2video.evaluation import metrics as M
    from motion2video.data.windows import metric_vectors
    from motion2video.models.blocks import repeat_batch

    defaults = {f.name: f.default for f in dataclasses.fields(MODEL_REGISTRY["lcpvae"].config_cls)}
    rows = []
    for path, shipped in ((old, False), (new, True)):
        b = load_model(path)
        config = {**defaults, **b.meta.config}
        label = (f"`cs_kl_weight` {config['cs_kl_weight']:g}, teacher forcing {config['teacher_forcing_steps']} steps"
                 + (" (shipped)" if shipped else ""))
        ds = build_dataset(DEFAULT_MOCAP, b.data_config, split=b.meta.split, stats=b.stats)
        ws = ds.windows("test", stride=16)
        ws = _corpus_subset(ws, np.isin(ws.clip_names, sorted(clips)))
        obs = torch.from_numpy(ws.obs.astype(np.float32))
        gen = torch.Generator().manual_seed(0)
        with torch.no_grad():
            cond, _ = b.model.condition_posterior(obs)
            sigma = torch.exp(0.5 * cond.logvar)
            kl = float((0.5 * (cond.mu ** 2 + sigma ** 2 - 1 - cond.logvar)).sum(-1).mean())
            n, k = obs.shape[0], samples
            z = torch.randn(n * k, cond.mu.shape[1], generator=gen)
            out = b.model.future_decoder(torch.tanh(b.model.lcp_decoder(z)), repeat_batch(obs[:, -1], k),
                                         horizon=b.data_config.future).view(n, k, b.data_config.future, -1)
        prior = sample_futures(b.model, ws.obs, num_samples=k, horizon=b.data_config.future, seed=0)

        def apd(x):
            return M.apd(metric_vectors(b.stats.denormalize(np.asarray(x, dtype=np.float64)), b.layout))

        row = {"sigma_c_mean": float(sigma.mean()), "kl_cs_nats": kl, "apd_learned_prior": apd(prior),
               "apd_standard_normal": apd(out.numpy())}
        record.setdefault("lcp_diagnosis", {})[label] = row
        rows.append([label, row["sigma_c_mean"], row["kl_cs_nats"], row["apd_learned_prior"], row["apd_standard_normal"]])
    return "\n".join([
        "On the held-out test windows each model did not train on (`python scripts/make_results.py corpus`; APD of",
        f"{samples} futures):",
        "",
        _corpus_md_table(["prior", "mean sigma_c", "KL of q(z_c given obs) to N(0, I), nats", "APD, learned prior (m)",
                          "APD, z ~ N(0, I) (m)"], rows),
    ])


def corpus_main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=CORPUS_DOC.splitlines()[0])
    p.add_argument("--weights", default=str(WEIGHTS_DIR), help="folder of the shipped lcpvae")
    p.add_argument("--five-minute", default=str(ROOT / "out" / "five_minute"),
                   help="folder of the retrained 5-minute lcpvae (scripts/make_results.py five-minute-models --out)")
    p.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    p.add_argument("--json", default=str(ROOT / "out" / "results_corpus.json"))
    p.add_argument("--samples", type=int, default=50)
    args = p.parse_args(argv)
    check_section(args.doc, CORPUS_BEGIN, CORPUS_END)
    old = Path(args.five_minute) / "lcpvae.safetensors"
    if not old.is_file():
        raise InputError("no 5-minute lcpvae here: run `python scripts/make_results.py five-minute-models` first", old)
    torch.set_num_threads(1)
    new = Path(args.weights) / "lcpvae.safetensors"
    ref = load_model(new)
    test = build_dataset(DEFAULT_MOCAP, ref.data_config, split=ref.meta.split, stats=ref.stats).windows("test", stride=16)
    record: dict = {"started": time.strftime("%Y-%m-%d %H:%M:%S")}
    section = lcp_diagnosis(old, new, set(test.clip_names), record, samples=args.samples)
    write_section(args.doc, CORPUS_BEGIN, CORPUS_END, section)
    write_json(args.json, record)
    print(f"wrote {args.doc} and {args.json}")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# known_answer: The known-answer multimodal benchmark for any shipped latent model and DLow on it
# ----------------------------------------------------------------------------------------------------------------


KNOWN_ANSWER_DOC = """The known-answer multimodal benchmark for the shipped latent models and DLow on each (target: coverage
and precision >= 0.9 at K = 10).

    python scripts/make_results.py known-answer [--model mtvae-add --model lcpvae --model mixer-cvae]
        [--steps 4000] [--dlow-steps 600] [--runs out/known_answer] [--json out/known_answer.json]

Each model is retrained from scratch on ``procedural:multimodal`` (sequences whose future is one of the observed
mode's known next modes) with its shipped checkpoint's config and ``--steps`` steps (seed 0, batch 64), then DLow
with the shipped ``mtvae-add-dlow`` config and K = 10 maps (``--dlow-steps``, batch 16); both are scored with K = 10
samples per test sequence: coverage (share of valid modes hit by a sample), precision (share of samples in a valid
mode) and TV (total variation between sampled and true mode frequencies). A model whose loss is in metres
(``feature_scale``, mixer-cvae) gets this dataset's scales, as ``motion2video train`` gives them. Checkpoints
already in --runs are reused. Writes the table between ``<!-- known-answer:begin -->`` and
``<!-- known-answer:end -->`` of docs/results.md ("Known-answer multimodal benchmark") and the raw numbers to --json.
About 14 minutes on one thread per model (2026-11-27).
"""

KNOWN_ANSWER_BEGIN, KNOWN_ANSWER_END = "<!-- known-answer:begin -->", "<!-- known-answer:end -->"


KNOWN_ANSWER_MODELS = ("mtvae-add", "lcpvae", "mixer-cvae")

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


def _known_answer_section(report: dict[str, dict], *, command: str, train_sequences: int, test_sequences: int,
                          steps: int, dlow_steps: int) -> str:
    """The block between the known-answer markers of docs/results.md; ``report``: label -> :func:`score`'s dict.
    Coverage and precision are bold where both reach the 0.9 target."""
    rows = []
    for label, r in report.items():
        met = r["coverage"] >= 0.9 and r["precision"] >= 0.9
        cov, prec = (f"**{r[k]:.3f}**" if met else f"{r[k]:.3f}" for k in ("coverage", "precision"))
        rows.append(f"| {label} | {cov} | {prec} | {r['distribution_tv']:.3f} |")
    return f"""Procedural clips (`motion2video/data/multimodal.py`, `--data {MULTIMODAL_SOURCE}`): the {MM_CONFIG.observed} observed frames show
one mode (walk, stand, run), the {MM_CONFIG.future} future frames one of its possible next modes with known probabilities; {train_sequences}
training / {test_sequences} test sequences; the shipped configs trained {steps} steps, DLow {dlow_steps} steps with K = {SAMPLES} maps; K = {SAMPLES}
samples per test sequence. Coverage: share of the valid modes hit by a sample; precision: share of samples in a
valid mode; TV: total variation between sampled and true mode frequencies. Target: >= 0.9 on coverage and
precision. `{command}` (about 14 min on one thread per model):

| model | coverage | precision | TV |
|---|---|---|---|
""" + "\n".join(rows)


def known_answer_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=KNOWN_ANSWER_DOC.splitlines()[0])
    parser.add_argument("--model", action="append", default=None,
                        help="a shipped latent model whose config is retrained (repeatable; default: "
                        + ", ".join(KNOWN_ANSWER_MODELS) + ")")
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--dlow-steps", type=int, default=600)
    parser.add_argument("--runs", default=str(ROOT / "out" / "known_answer"))
    parser.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    parser.add_argument("--json", default=str(ROOT / "out" / "known_answer.json"))
    args = parser.parse_args(argv)
    check_section(args.doc, KNOWN_ANSWER_BEGIN, KNOWN_ANSWER_END)
    models = args.model or list(KNOWN_ANSWER_MODELS)
    torch.set_num_threads(1)
    start = time.time()
    dataset = build_dataset(MULTIMODAL_SOURCE, MM_CONFIG)
    test = dataset.windows("test")
    report = {}
    for name in models:
        shipped = load_model(WEIGHTS_DIR / f"{name}.safetensors")
        base_out, dlow_out = train_with_dlow(shipped.name, shipped.meta.config, Path(args.runs), steps=args.steps,
                                             dlow_steps=args.dlow_steps)
        for label, path in ((name, base_out), (f"{name} + dlow", dlow_out)):
            report[label] = r = score(path, test)
            print(f"{label}: coverage {r['coverage']:.3f}, precision {r['precision']:.3f}, "
                  f"TV {r['distribution_tv']:.3f}", flush=True)
    command = "python scripts/make_results.py known-answer" + "".join(
        f" --{k.replace('_', '-')} {v}" for k, v in (("steps", args.steps), ("dlow_steps", args.dlow_steps))
        if v != parser.get_default(k)) + ("".join(f" --model {m}" for m in models) if args.model else "")
    write_section(args.doc, KNOWN_ANSWER_BEGIN, KNOWN_ANSWER_END, _known_answer_section(
        report, command=command, train_sequences=len(dataset.split.train), test_sequences=len(test),
        steps=args.steps, dlow_steps=args.dlow_steps))
    write_json(args.json, {"samples": SAMPLES, "steps": args.steps, "dlow_steps": args.dlow_steps,
                           "test_sequences": len(test), "models": report})
    print(f"wrote {args.doc} and {args.json} in {time.time() - start:.0f} s")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# per_action: Every body model per action and as the macro average over actions, on the same held-out
# ----------------------------------------------------------------------------------------------------------------


PER_ACTION_DOC = """Every body model per action and as the macro average over actions, on the same held-out
test windows, as best-of-K ADE / FDE ratios to zero-velocity.

    python scripts/make_results.py per-action                       # the 5-minute models (git) and the shipped ones
    python scripts/make_results.py per-action --model new=runs/new.safetensors    # add a model
    python scripts/make_results.py per-action --no-defaults --model a=PATH --model b=PATH

Each ``--model LABEL=SPEC`` is a shipped name, a checkpoint path, or ``git:REV:PATH`` (a checkpoint file of a
git revision of this repository, written to --cache first). Without ``--no-defaults`` the 5-minute models
(the 72-clip checkpoints of git :data:`OLD_REV`) and the shipped corpus models come first. The windows are
the held-out test windows of ``--windows-from``'s recorded split (default: the shipped ``mtvae-add``, the
corpus's pinned test subjects), the same for every model; each model reads them with its own normalisation.
A model whose recorded training split holds a clip of those windows is scored anyway and flagged.

Writes the section between ``<!-- per-action:begin -->`` and ``<!-- per-action:end -->`` of
docs/results.md and the raw numbers (``motion2video evaluate``'s JSON: pooled, per_action, macro) to --json.
"""

PER_ACTION_BEGIN, PER_ACTION_END = "<!-- per-action:begin -->", "<!-- per-action:end -->"


_per_action_SHIPPED = ("mtvae-add", "mtvae-add-dlow", "lcpvae", "behavior", "mixer-cvae-dlow", "mixture-dlow", "mixture-periodic")


BASELINE = "zero-velocity"


FIVE_MINUTE = ROOT / "out" / "five_minute"  # scripts/make_results.py five-minute-models writes the retrained models here


def default_models(rev: str = OLD_REV, retrained: Path = FIVE_MINUTE) -> list[tuple[str, str]]:
    """(label, spec): the 5-minute models, then the shipped models. The 5-minute checkpoints of git ``rev`` follow
    canonical skeleton version 1, which this motion2video refuses; their recipe retrained on today's joints
    (``scripts/make_results.py five-minute-models``) stands in for each one found in ``retrained``."""
    old = []
    for n in OLD:
        mine = retrained / f"{n}.safetensors"
        old.append((f"{n} (5 min)", str(mine) if mine.is_file() else f"git:{rev}:motion2video/weights/{n}.safetensors"))
    return old + [(n, n) for n in _per_action_SHIPPED]


def parse_model(value: str) -> tuple[str, str]:
    """``LABEL=SPEC`` -> (label, spec)."""
    label, sep, spec = value.partition("=")
    if not sep or not label or not spec:
        raise SystemExit(f"--model wants LABEL=PATH (or LABEL=git:REV:PATH, or LABEL=shipped-name), got {value!r}")
    return label, spec


def resolve(spec: str, cache: Path) -> str:
    """A checkpoint path or shipped name for ``spec``; ``git:REV:PATH`` is written from git into ``cache``."""
    if not spec.startswith("git:"):
        return spec
    _, rev, path = spec.split(":", 2)
    out = cache / rev / path
    if not out.is_file():
        blob = subprocess.run(["git", "show", f"{rev}:{path}"], cwd=ROOT, capture_output=True)
        if blob.returncode != 0:
            raise SystemExit(f"{spec}: git show failed: {blob.stderr.decode().strip()}")
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_bytes(blob.stdout)
    return str(out)


def _per_action_subset(windows: WindowSet, idx: np.ndarray) -> WindowSet:
    """The windows at indices ``idx``."""
    frames = windows.frames
    if frames is not None:
        frames = dataclasses.replace(frames, origin=frames.origin[idx], angle=frames.angle[idx])
    return dataclasses.replace(windows, features=windows.features[idx], raw=windows.raw[idx], frames=frames,
                               clip_names=tuple(windows.clip_names[i] for i in idx), starts=windows.starts[idx],
                               labels=tuple(windows.labels[i] for i in idx))


def ratios(result: dict, label: str) -> dict:
    """ADE / FDE ratios to zero-velocity of ``label``, per action, macro and pooled, from evaluate's JSON."""
    zv_pa, pa = result["per_action"][BASELINE], result["per_action"][label]
    out = {a: {"ade": pa[a]["ade"] / zv_pa[a]["ade"], "fde": pa[a]["fde"] / zv_pa[a]["fde"]} for a in pa}
    out["macro"] = {k: float(np.mean([out[a][k] for a in pa])) for k in ("ade", "fde")}
    out["pooled"] = {k: result["results"][label][k] / result["results"][BASELINE][k] for k in ("ade", "fde")}
    return out


def _per_action_render(result: dict, labels: list[str], *, command: str, seconds: float, seen: dict, samples: int,
           stride: int, dropped: int, kept: bool, validated: list[str]) -> str:
    table = {label: ratios(result, label) for label in labels}
    counts = result["protocol"]["actions"]
    zv = result["per_action"][BASELINE]
    n = result["protocol"]["windows"]
    head = "| action | windows | zero-velocity ADE / FDE (m) | " + " | ".join(labels) + " |"
    lines = [head, "| --- | ---: | ---: | " + " | ".join("---:" for _ in labels) + " |"]

    def cells(key: str) -> str:
        return " | ".join(f"{table[m][key]['ade']:.2f} / {table[m][key]['fde']:.2f}" for m in labels)

    for action, count in counts.items():
        lines.append(f"| {action} | {count} | {zv[action]['ade']:.3f} / {zv[action]['fde']:.3f} | {cells(action)} |")
    zvm = result["macro"][BASELINE]
    zvp = result["results"][BASELINE]
    lines.append(f"| **macro** (each action once) | {len(counts)} actions | {zvm['ade']:.3f} / {zvm['fde']:.3f} | "
                 f"{cells('macro')} |")
    lines.append(f"| pooled (each window once) | {n} | {zvp['ade']:.3f} / {zvp['fde']:.3f} | {cells('pooled')} |")
    best = {a: min(labels, key=lambda m: table[m][a]["ade"]) for a in list(counts) + ["macro"]}
    flagged = sorted({c for clips in seen.values() for c in clips})
    who = [m for m, clips in seen.items() if clips]
    if not flagged:
        check = "No model's recorded training split holds a clip of the test split."
    elif kept:
        check = (f"**Not all held out**: {', '.join(f'`{m}`' for m in who)} trained on {len(flagged)} of these "
                 f"clips ({', '.join(flagged)}); their windows are included (`--keep-trained`).")
    else:
        check = (f"{', '.join(f'`{m}`' for m in who)} trained on {len(flagged)} clips of the corpus's test split "
                 f"({', '.join(flagged)}: CMU subjects the corpus split holds out, but the 72-clip split trained "
                 f"on); their {dropped} windows are left out, so every window here is held out for every model.")
    text = [
        f"Generated by `{command}` ({seconds / 60:.1f} min, 1 thread). {n} held-out test windows (16 observed + 48 "
        f"future frames at 25 fps, {stride} frames apart) from {len(result['protocol']['clips'])} clips of the "
        "corpus's pinned test subjects (CMU 2, 131, 140, 94 Indian dance and the clips linked to them), the same "
        "windows for every model; each cell is best-of-"
        f"{samples} ADE / FDE as a ratio to zero-velocity on the same windows (lower is better, 1.00 = standing "
        "still). `macro` is the unweighted mean of the per-action ratios, `pooled` the ratio of the means over all "
        "windows (what one pooled average reports). '5 min' = the 72-clip models of git "
        f"{OLD_REV}, retrained on canonical skeleton version 2 with their recorded split, configs and steps "
        "(`python scripts/make_results.py five-minute-models`; the original checkpoints follow version 1 and are refused), the "
        "others the checkpoints shipped now. Futures continue the observed motion for every learned model "
        "(`stages.sampling.continue_observed`). Actions are the coarse classes "
        "of the manifest's action column (`motion2video.data.corpus.action_class`).",
        "",
        *lines,
        "",
        "Lowest ADE ratio per action: " + "; ".join(f"{a}: `{m}`" for a, m in best.items()) + ".",
        "",
        "Held-out check: " + check + (
            f" Kept: {len(validated)} clips some model's recorded split used for validation ({', '.join(validated)}; "
            "model selection, not training)." if validated else ""),
        "",
        "Per action in the JSON of `motion2video evaluate --model NAME --data ../shared/data/mocap --json out.json` "
        "(`per_action`, `macro`).",
    ]
    return "\n".join(text)


def per_action_main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=PER_ACTION_DOC.splitlines()[0])
    p.add_argument("--model", action="append", default=[], help="LABEL=SPEC (repeatable; module docstring)")
    p.add_argument("--no-defaults", action="store_true", help="only the --model models")
    p.add_argument("--old-rev", default=OLD_REV, help="git revision of the 5-minute models")
    p.add_argument("--windows-from", default="mtvae-add", help="checkpoint whose recorded test split gives the windows")
    p.add_argument("--data", default=str(DEFAULT_MOCAP))
    p.add_argument("--samples", type=int, default=50)
    p.add_argument("--stride", type=int, default=16)
    p.add_argument("--every", type=int, default=1, help="keep every n-th window (timing runs)")
    p.add_argument("--keep-trained", action="store_true",
                   help="also score the test windows of clips some model's recorded split trained on (flagged)")
    p.add_argument("--cache", default="/tmp/motion2video-git-weights", help="where git:REV:PATH files are written")
    p.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    p.add_argument("--json", default=str(ROOT / "out" / "results_per_action.json"))
    p.add_argument("--dry-run", action="store_true", help="print the section instead of writing the doc")
    args = p.parse_args(argv)
    if not args.dry_run:
        check_section(args.doc, PER_ACTION_BEGIN, PER_ACTION_END)
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    models = ([] if args.no_defaults else default_models(args.old_rev)) + [parse_model(v) for v in args.model]
    if not models:
        raise SystemExit("no models: give --model LABEL=PATH")
    bundles, kept = [], []
    for label, spec in models:
        try:
            bundles.append(load_model(resolve(spec, Path(args.cache))))
            kept.append((label, spec))
        except InputError as err:  # e.g. the 5-minute models: trained on canonical skeleton version 1
            print(f"note: {label} left out: {err}", file=sys.stderr)
    models = kept
    ref = load_model(args.windows_from)
    for (label, _), b in zip(models, bundles):
        if (b.data_config.observed, b.data_config.future, b.data_config.fps, b.layout.kind) !=\
                (ref.data_config.observed, ref.data_config.future, ref.data_config.fps, ref.layout.kind):
            raise SystemExit(f"{label}: other windows ({b.data_config}) than {args.windows_from} ({ref.data_config})")
    dataset = build_dataset(args.data, ref.data_config, split=ref.meta.split, stats=ref.stats)
    windows = dataset.windows("test", stride=args.stride)
    clips = set(windows.clip_names)
    seen = {label: sorted(clips & set(b.meta.split.train)) if b.meta.split else []
            for (label, _), b in zip(models, bundles)}
    trained = sorted(set().union(*seen.values()))
    validated = sorted(set().union(*[clips & set(b.meta.split.val) for b in bundles if b.meta.split]))
    dropped = 0
    if trained and not args.keep_trained:  # only windows that no model trained on
        keep = np.flatnonzero(~np.isin(np.asarray(windows.clip_names), trained))
        dropped = len(windows) - len(keep)
        windows = _per_action_subset(windows, keep)
    if args.every > 1:
        windows = _per_action_subset(windows, np.arange(0, len(windows), args.every))
    clips = set(windows.clip_names)
    protocol = EvalProtocol(samples=args.samples, stride=args.stride, split="test", seed=0)
    print(f"{len(windows)} windows from {len(clips)} clips; {len(bundles)} models, best of {args.samples}", flush=True)
    merged: dict = {}
    for (label, _), b in zip(models, bundles):
        t = time.perf_counter()
        r = evaluate_bundles([b], windows, protocol=protocol).to_json()
        for key in ("results", "per_action", "macro", "ade_per_frame"):
            merged.setdefault(key, {})[label] = r[key][b.label]
        merged["protocol"] = r["protocol"]
        print(f"{label}: ADE {r['results'][b.label]['ade']:.3f} m in {time.perf_counter() - t:.0f} s", flush=True)
    r = evaluate_bundles([baseline_bundle(BASELINE, ref.data_config, stats=ref.stats)], windows,
                         protocol=protocol).to_json()
    for key in ("results", "per_action", "macro", "ade_per_frame"):
        merged[key][BASELINE] = r[key][BASELINE]
    seconds = time.perf_counter() - t0
    labels = [label for label, _ in models]
    command = "python scripts/make_results.py per-action" + "".join(
        f" --{k.replace('_', '-')} {v}" for k, v in (("samples", args.samples), ("stride", args.stride),
                                                       ("every", args.every)) if v != p.get_default(k))
    command += "".join(f" --model '{v}'" for v in args.model) + (" --no-defaults" if args.no_defaults else "")
    section = _per_action_render(merged, labels, command=command, seconds=seconds, seen=seen, samples=args.samples,
                     stride=args.stride, dropped=dropped, kept=args.keep_trained, validated=validated)
    merged["ratios"] = {label: ratios(merged, label) for label in labels}
    merged["trained_on_test_clips"] = seen
    merged["windows_left_out"] = dropped
    merged["validation_clips_kept"] = validated
    merged["seconds"] = seconds
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    write_json(args.json, merged)
    if args.dry_run:
        print(section)
    else:
        write_section(args.doc, PER_ACTION_BEGIN, PER_ACTION_END, section)
        print(f"wrote {args.doc}")
    print(f"wrote {args.json} ({seconds / 60:.1f} min)")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# five_minute: Retrain the 5-minute models on today's joints: per-action, corpus and forecasting compare them.
# ----------------------------------------------------------------------------------------------------------------


FIVE_MINUTE_DOC = """Retrain the 5-minute models on today's joints: per-action, corpus and forecasting compare them.

    python scripts/make_results.py five-minute-models [--out out/five_minute] [--models mtvae-add,lcpvae,behavior]
        [--mocap ../shared/data/mocap] [--rev 805c753]

The 72-clip models of git ``--rev`` (4.7 minutes of motion, the "5-minute models") were trained on canonical
skeleton version 1; this motion2video refuses them (every source follows Human3.6M's body points).
Each is retrained here with what its checkpoint records: the model name and config, the data config, the exact
72-clip split (train / val / test clip names; only those clips are loaded) and the training config (2000 steps,
batch 64, seed 0). The joints are version 2 and the code is today's: config fields added since take their defaults
(each is off unless a card says otherwise), and the normalisation statistics are computed on the training windows.
Writes ``OUT/NAME.safetensors`` (with a ``.json`` of the run), which ``per-action``, ``corpus`` and ``forecasting`` read.
About 3-5 minutes per model on one thread (2026-11-26).
"""


def five_minute_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=FIVE_MINUTE_DOC.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "out" / "five_minute"))
    parser.add_argument("--models", default=",".join(OLD))
    parser.add_argument("--mocap", default=str(ROOT.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--rev", default=OLD_REV)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--cache", default="/tmp/motion2video-git-weights",
                        help="where the old checkpoints are written (as `make_results.py per-action --cache`)")
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


# ----------------------------------------------------------------------------------------------------------------
# skeleton_figure: Draw docs/images/skeletons.png: every source's canonical H36M-17 skeleton beside Human3.6M's.
# ----------------------------------------------------------------------------------------------------------------


SKELETON_FIGURE_DOC = """Draw docs/images/skeletons.png: every source's canonical H36M-17 skeleton beside Human3.6M's.

Each source gives one frame of a walk (mid-stance: the frame whose ankles are closest together), moved so
its pelvis is at the origin, turned to face -y and scaled so its leg (thigh + shin) is Human3.6M's 897 mm.
Front (x-z) and side (y-z) views; Human3.6M's own skeleton (subject S1 bone lengths) is drawn grey behind
every source, and the four proportions of the canonical skeleton are printed under each (1.00 = as in Human3.6M).

    python scripts/make_results.py skeleton-figure [--mocap ../shared/data/mocap] [--out docs/images/skeletons.png]
"""

SOURCES = {
    "CMU Daz BVH": "cmu/08_01.bvh",
    "acrnn (Daz)": "acrnn/salsa_01a.bvh",
    "CMU 3dsMax": "cmu/131_01.bvh",
    "CMU MotionBuilder": "cmu/01_01.bvh",
    "CMU amc2bvh": "cmu/16_01.bvh",
    "DeepMimic BVH": "deepmimic/humanoid3d_walk.bvh",
    "DeepMimic .txt": "deepmimic/txt/humanoid3d_walk.txt",
    "MASS": "mass/mass_walk.bvh",
    "exp-map benchmark": "cmu-bench/test/walking/walking_1.txt",
    "procedural demo": "demo:walk_to_run.npz",
}


def human36m_pose() -> np.ndarray:
    """(17, 3) Human3.6M's skeleton standing straight, arms hanging, mm."""
    b = H36M_BONES_MM
    j = np.zeros((17, 3))
    for side, (hip, knee, ankle, shoulder, elbow, wrist) in ((-1, (1, 2, 3, 14, 15, 16)), (1, (4, 5, 6, 11, 12, 13))):
        j[hip] = (side * b["hip"], 0, 0)
        j[knee] = j[hip] - (0, 0, b["thigh"])
        j[ankle] = j[knee] - (0, 0, b["shin"])
    j[7] = (0, 0, b["pelvis_spine"])
    j[8] = j[7] + (0, 0, b["spine_thorax"])
    j[9] = j[8] + (0, 0, b["thorax_nose"])
    j[10] = j[9] + (0, 0, b["nose_head"])
    for side, (shoulder, elbow, wrist) in ((1, (11, 12, 13)), (-1, (14, 15, 16))):
        j[shoulder] = j[8] + (side * b["thorax_shoulder"], 0, 0)
        j[elbow] = j[shoulder] - (0, 0, b["upper_arm"])
        j[wrist] = j[elbow] - (0, 0, b["forearm"])
    return j


def normalised_frame(joints: np.ndarray) -> np.ndarray:
    """(17, 3) mid-stance frame of (T, 17, 3) joints: pelvis at 0, facing -y, leg = 897 mm."""
    t = int(np.argmin(np.linalg.norm(joints[:, L_ANKLE, :2] - joints[:, R_ANKLE, :2], axis=-1)))
    j = joints[t] - joints[t, PELVIS]
    across = j[L_HIP] - j[R_HIP]
    yaw = np.arctan2(across[1], across[0])  # turn the hip axis onto +x (so the body faces -y)
    c, s = np.cos(-yaw), np.sin(-yaw)
    j = j @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    return j * (H36M_LEG_MM / leg_length(joints))


def draw(out: Path, mocap: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref = human36m_pose()
    panels = [("Human3.6M (S1)", ref[None], ref)]
    for label, name in SOURCES.items():
        path = ROOT / "demo_inputs" / name[5:] if name.startswith("demo:") else mocap / name
        joints = np.asarray(load_motion(path).joints, np.float64)
        panels.append((label, joints, normalised_frame(joints)))
    fig, axes = plt.subplots(2, len(panels), figsize=(1.6 * len(panels), 6.4))
    colour = {"left": "tab:green", "right": "tab:red", "centre": "tab:blue"}
    for col, (label, joints, frame) in enumerate(panels):
        ratios = proportion_ratios(joints)
        for row, (a, b, view) in enumerate(((0, 2, "front"), (1, 2, "side"))):
            ax = axes[row, col]
            for i, p in enumerate(H36M_17.parents):
                if p < 0:
                    continue
                ax.plot(ref[[p, i], a], ref[[p, i], b], color="0.8", lw=3, zorder=1)
                name = H36M_17.joints[i]
                side = "left" if name.startswith("left") else "right" if name.startswith("right") else "centre"
                ax.plot(frame[[p, i], a], frame[[p, i], b], color=colour[side], lw=1.6, zorder=2)
            ax.scatter(frame[[8, 9, 10], a], frame[[8, 9, 10], b], s=8, color="k", zorder=3)
            ax.set_xlim(-650, 650)
            ax.set_ylim(-1000, 800)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            if row == 0:
                ax.set_title(label, fontsize=8)
            else:
                ax.set_xlabel("\n".join(f"{k.replace('_', '-')} {v:.2f}" for k, v in ratios.items()), fontsize=6.5)
            if col == 0:
                ax.set_ylabel(view, fontsize=9)
    fig.suptitle("Canonical H36M-17 of every source (skeleton version 2), leg scaled to 897 mm, grey: Human3.6M;"
                 " numbers: ratio to Human3.6M's proportions", fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def skeleton_figure_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=SKELETON_FIGURE_DOC.split("\n\n")[0])
    parser.add_argument("--mocap", type=Path, default=ROOT.parent / "shared" / "data" / "mocap")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / "skeletons.png")
    args = parser.parse_args(argv)
    print(f"wrote {draw(args.out, args.mocap)}")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# frames: The body frame generator measured on the person, next to its baselines, in one run.
# ----------------------------------------------------------------------------------------------------------------


FRAMES_DOC = """The body frame generator on the held-out pairs, next to the previous generator and the baselines.

    python scripts/make_results.py frames [--model frames-body-128] [--cache DIR]

Runs ``motion2video evaluate-frames --model MODEL`` once on the held-out body pairs (held-out identities and
clips; the previous generator ``frames-body-128-v1``, copy-reference and limb-warp scored on the same pairs) and
writes the table between ``<!-- body-frames:begin -->`` and ``<!-- body-frames:end -->`` of docs/results.md
("Frame generation on renders"): whole-frame PSNR / SSIM, person PSNR / SSIM / sharpness inside the target's
silhouette and PSNR where the person moved; and out/results_frames.json, the evaluation as evaluate-frames
writes it.

About a minute on 2 cores when the held-out shards are cached (``--cache``), plus a few minutes to render
them the first time.
"""

FRAMES_BEGIN, FRAMES_END = "<!-- body-frames:begin -->", "<!-- body-frames:end -->"


ORDER = ("generator", "frames-body-128-v1", "copy-reference", "limb-warp")


NAMES = {"generator": "**`{model}`**", "frames-body-128-v1": "`frames-body-128-v1` (feature analogy)",
         "copy-reference": "copy-reference", "limb-warp": "limb-warp"}


KIND_WORDS = {"warp": "The keypoint warp", "mesh": "The mesh generator"}  # evaluate-frames' model_kind


def _frames_table(results: dict, model: str) -> str:
    head = ("| method | whole PSNR | whole SSIM | person PSNR | person SSIM | person sharpness | moving PSNR |\n"
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows = []
    for key in ORDER:
        r = results.get(key)
        if r is None:
            continue
        rows.append(f"| {NAMES[key].format(model=model)} | {r['psnr']:.2f} | {r['ssim']:.3f} | {r['person_psnr']:.2f} "
                    f"| {r['person_ssim']:.3f} | {r['person_sharpness']:.2f} | {r['moving_psnr']:.2f} |")
    return head + "\n" + "\n".join(rows)


def _frames_section(evaluation: dict, model: str) -> str:
    """The block between the body-frames markers of docs/results.md, from evaluate-frames' JSON ``evaluation``."""
    words = KIND_WORDS.get(evaluation.get("model_kind"), "The generator")
    return (f"{words} `{model}` (`motion2video evaluate-frames --model {model}`, {evaluation['num_pairs']} pairs;\n"
            "`python scripts/make_results.py frames` writes this table):\n\n" + _frames_table(evaluation["results"], model))


def frames_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=FRAMES_DOC, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="frames-body-128", help="the body generator (default frames-body-128)")
    parser.add_argument("--cache", default=None, help="frame-data cache folder (evaluate-frames --cache)")
    parser.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    parser.add_argument("--json", default=str(ROOT / "out" / "results_frames.json"))
    args = parser.parse_args(argv)
    check_section(args.doc, FRAMES_BEGIN, FRAMES_END)

    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    cmd = ["evaluate-frames", "--model", args.model, "--json", args.json, "--no-progress"]
    if args.cache:
        cmd += ["--cache", args.cache]
    subprocess.run([sys.executable, "-m", "motion2video.cli", *cmd], check=True, cwd=ROOT)
    evaluation = json.loads(Path(args.json).read_text())
    write_section(args.doc, FRAMES_BEGIN, FRAMES_END, _frames_section(evaluation, args.model))
    print(f"wrote {args.doc} and {args.json}")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# frames_analysis: Where a warp body generator's error on the person comes from, on the held-out body pairs.
# ----------------------------------------------------------------------------------------------------------------


FRAMES_ANALYSIS_DOC = """Where a warp body generator's error on the person comes from, on the held-out body pairs.

    python scripts/make_results.py frames-analysis --model frames-body-128 --json out/frames_error_analysis.json

Measures, on the same 256 pairs that ``motion2video evaluate-frames`` scores:

1. person PSNR (inside the target's silhouette) by the time between reference and target (frames 1..8 of
   each 1.2 s sequence), for the generator, limb-warp and copy-reference;
2. how much a sub-pixel error of the flow costs: the reference sampled by the generator's own person flow,
   and by that flow shifted by half a pixel;
3. the whole frame's squared error split into the target's silhouette, the background the reference person
   uncovered (reference silhouette minus the target's) and the rest;
4. ceilings: the generator's person flow composited with the true target silhouette over the true
   background (no mask or background error left: what the flow alone allows), and with a per-pair residual
   flow fitted to the truth (an oracle: how far the flow is from one that matches).

The generator runs on the whole 128x128 frames (``forward_parts``), which for these frames is the crop that
``evaluate-frames`` uses; the paste back differs only outside the people.
"""

def mean_person_psnr(pred: np.ndarray, truth: np.ndarray, masks: np.ndarray) -> float:
    return float(np.nanmean([region_psnr(p, t, m) for p, t, m in zip(pred, truth, masks)]))


def fitted_residual_psnr(ref: torch.Tensor, truth: torch.Tensor, flow: torch.Tensor, masks: np.ndarray, *,
                         grid: int, steps: int, mode: str) -> tuple[float, float]:
    """Person PSNR of the reference sampled by ``flow`` (B, H, W, 2) plus a smooth residual (a ``grid`` x
    ``grid`` field, bilinearly upsampled) fitted by Adam to the truth inside the silhouettes; and the fitted
    residual's mean length in pixels."""
    b, _, h, w = ref.shape
    weight = torch.from_numpy(masks)[:, None].float()
    delta = torch.zeros(b, 2, grid, grid, requires_grad=True)
    opt = torch.optim.Adam([delta], lr=0.5)
    for _ in range(steps):
        d = F.interpolate(delta, size=(h, w), mode="bilinear", align_corners=False).permute(0, 2, 3, 1)
        err = ((warp_image(ref, flow + d, mode) - truth).abs() * weight).sum() / weight.sum()
        smooth = (delta[:, :, 1:] - delta[:, :, :-1]).abs().mean() + (delta[..., 1:] - delta[..., :-1]).abs().mean()
        loss = err + 0.01 * smooth
        opt.zero_grad()
        loss.backward()
        opt.step()
    with torch.no_grad():
        d = F.interpolate(delta, size=(h, w), mode="bilinear", align_corners=False).permute(0, 2, 3, 1)
        pred = tensor_to_images(warp_image(ref, flow + d, mode))
        length = float(d.norm(dim=-1)[torch.from_numpy(masks)].mean())
    truth_u8 = tensor_to_images(truth)
    return mean_person_psnr(pred, truth_u8, masks), length


def frames_analysis_main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=FRAMES_ANALYSIS_DOC.split("\n\n")[0])
    p.add_argument("--model", default="frames-body-128", help="a warp body generator (checkpoint or shipped name)")
    p.add_argument("--json", default="out/frames_error_analysis.json")
    p.add_argument("--cache", default=None, help="frame-data cache folder (default ~/.cache/motion2video/frames)")
    p.add_argument("--oracle-every", type=int, default=8, help="fit the oracle residual on every Nth pair")
    p.add_argument("--oracle-steps", type=int, default=300)
    args = p.parse_args(argv)
    torch.manual_seed(0)
    loaded = load_frame_model(args.model)
    model = loaded.model.eval()
    if not isinstance(model, WarpGenerator):
        p.error(f"{args.model}: not a warp generator (kind {loaded.kind})")
    mode = model.config.sample_mode
    seqs = load_or_generate(default_spec("body", "test"), cache_dir=args.cache or default_cache_dir(),
                            progress=False)
    index = evaluation_pair_index(seqs)
    pairs = make_pairs(seqs, index)
    truth, ref_u8, tgt_masks, ref_masks = pairs.tgt_images, pairs.ref_images, pairs.tgt_masks, pairs.ref_masks
    ref = images_to_tensor(ref_u8)
    images, flows, person = [], [], []
    with torch.no_grad():
        for s in range(0, len(pairs), 32):
            out = model.forward_parts(ref[s:s + 32], torch.from_numpy(pairs.ref_points[s:s + 32]),
                                      torch.from_numpy(pairs.tgt_points[s:s + 32]),
                                      torch.from_numpy(pairs.tgt_structures[s:s + 32]))
            images.append(tensor_to_images(out.image))
            flows.append(out.flow)
            person.append(1.0 - out.masks[:, -1])
    gen, flow = np.concatenate(images), torch.cat(flows)
    limb = run_baseline("limb-warp", ref_u8, pairs.ref_points, pairs.tgt_points)
    rows = tgt_masks.any(axis=2)  # (N, H): image rows the target person covers
    height = float(np.mean([np.ptp(np.nonzero(r)[0]) + 1 for r in rows if r.any()]))
    report: dict = {"model": args.model, "sample_mode": mode, "num_pairs": len(pairs),
                    "person_height_px": round(height, 1), "person_pixels": round(float(tgt_masks.sum((1, 2)).mean()))}

    gaps = {}
    for gap in sorted(set(index[:, 2].tolist())):
        sel = index[:, 2] == gap
        moved = np.linalg.norm(pairs.ref_points[sel] - pairs.tgt_points[sel], axis=-1).mean()
        gaps[int(gap)] = {"pairs": int(sel.sum()), "mean_joint_motion_px": round(float(moved), 1),
                          **{name: round(mean_person_psnr(x[sel], truth[sel], tgt_masks[sel]), 2)
                             for name, x in (("generator", gen), ("limb-warp", limb), ("copy-reference", ref_u8))}}
    report["person_psnr_by_gap"] = gaps

    shifts = {}
    with torch.no_grad():
        for name, offset in (("none", (0.0, 0.0)), ("x+0.5", (0.5, 0.0)), ("x-0.5", (-0.5, 0.0)),
                             ("y+0.5", (0.0, 0.5)), ("y-0.5", (0.0, -0.5))):
            sampled = tensor_to_images(warp_image(ref, flow + torch.tensor(offset), mode))
            shifts[name] = round(mean_person_psnr(sampled, truth, tgt_masks), 2)
    report["person_psnr_of_the_flow_shifted"] = shifts

    err = ((gen.astype(np.float64) - truth.astype(np.float64)) ** 2).mean(-1)  # (N, H, W)
    uncovered = ref_masks & ~tgt_masks
    rest = ~ref_masks & ~tgt_masks
    total = err.sum()
    report["whole_frame_error_share"] = {name: round(float(err[m].sum() / total), 3) for name, m in
                                         (("target_person", tgt_masks), ("uncovered_background", uncovered),
                                          ("rest", rest))}
    with torch.no_grad():
        sampled = tensor_to_images(warp_image(ref, flow, mode))
    alpha = tgt_masks[..., None].astype(np.float64)
    ceiling = np.rint(alpha * sampled + (1 - alpha) * truth).astype(np.uint8)
    report["whole_psnr"] = {"generator": round(float(frame_metrics(gen, truth)[0].mean()), 2),
                            "its_flow_true_silhouette_true_background": round(float(frame_metrics(ceiling, truth)[0].mean()), 2)}
    report["person"] = {"generator_psnr": round(mean_person_psnr(gen, truth, tgt_masks), 2),
                        "generator_sharpness": round(float(np.nanmean([sharpness_ratio(a, b, m) for a, b, m in
                                                                       zip(gen, truth, tgt_masks)])), 3),
                        "limb_warp_psnr": round(mean_person_psnr(limb, truth, tgt_masks), 2)}

    pick = np.arange(0, len(pairs), args.oracle_every)
    tgt = images_to_tensor(truth[pick])
    with torch.no_grad():
        base = mean_person_psnr(tensor_to_images(warp_image(ref[pick], flow[pick], mode)), truth[pick], tgt_masks[pick])
    oracle = {"pairs": len(pick), "its_flow": round(base, 2)}
    for grid in (16, 32):
        value, length = fitted_residual_psnr(ref[pick], tgt, flow[pick], tgt_masks[pick], grid=grid,
                                             steps=args.oracle_steps, mode=mode)
        oracle[f"fitted_residual_{grid}x{grid}"] = {"person_psnr": round(value, 2),
                                                    "mean_residual_px": round(length, 2)}
    report["oracle_residual_flow"] = oracle

    print(write_json(args.json, report).read_text(), end="")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# frames_real: The body frame generator driven by real mocap it never trained on, with the head measured.
# ----------------------------------------------------------------------------------------------------------------


FRAMES_REAL_DOC = """The body frame generator driven by real mocap it never trained on, with the head measured.

    python scripts/make_results.py frames-real [--model frames-body-mesh-256] [--mocap ../shared/data/mocap]

For each clip of :data:`CLIPS` (real CMU captures held out of the frame training data:
``motion2video.generator.specs.is_test_clip``), runs what ``motion2video evaluate-frames --model MODEL --poses
CLIP`` runs (the same functions, once per clip: the held-out identities posed by 4 windows of the clip, the truth
the Anny render of each pose) and writes:

- the block between ``<!-- frames-real-motion:begin -->`` and ``<!-- frames-real-motion:end -->`` of
  docs/results.md (under "Body frames driven by real motion"): the commands, person / head PSNR and SSIM, person
  sharpness and whole-frame PSNR per clip and method, and the targets per clip;
- docs/images/frames_real_motion.png: reference | truth | generator | previous generator | limb-warp, two pairs
  per clip, each frame at twice its size with the head region enlarged beside it;
- out/results_frames_real.json: the evaluate-frames JSON of each clip.

About 2 minutes on 2 cores.
"""

FRAMES_REAL_BEGIN, FRAMES_REAL_END = "<!-- frames-real-motion:begin -->", "<!-- frames-real-motion:end -->"


CLIPS = ("cmu/08_01.bvh", "cmu/13_42.bvh", "cmu/05_14.bvh")


WINDOWS = 4


FRAME_BASELINES = ("copy-reference", "limb-warp")


def order(results: dict) -> list[str]:
    """The methods of a payload in table order: the generator, the previous generator(s), the baselines."""
    old = [k for k in results if k != "generator" and k not in FRAME_BASELINES]
    return ["generator", *old, *FRAME_BASELINES]


def method_name(key: str, model: str) -> str:
    if key == "generator":
        return f"**new** (`{model}`)"
    return key if key in FRAME_BASELINES else f"old (`{key}`)"


_frames_real_TARGETS = {"person_psnr_vs_limb_warp_3db": "person PSNR >= limb-warp + 3 dB",
           "head_psnr_vs_limb_warp_3db": "head PSNR >= limb-warp + 3 dB",
           "person_sharpness_0.9": "person sharpness ratio >= 0.9"}


SHEET_ROWS = (7, 23)  # pairs per clip shown: the last target (1.2 s on) of the first and of the third window


SCALE = 2  # sheet cells at twice the frame size


HEAD_BOX = 24  # pixels (frame scale) of the enlarged head crop beside each cell


def evaluate_clip(model_name: str, clip: Path):
    """The evaluation of ``evaluate-frames --model model_name --poses clip --windows WINDOWS``, its JSON payload
    (the same functions the command runs) and (N, 2, H, W) bool head masks of each pair's target and reference."""
    from motion2video.evaluation.frame_generators import evaluate_posed, load_baselines
    from motion2video.generator.poses import load_body_clips
    from motion2video.generator.scores import json_payload

    loaded = load_frame_model(model_name)
    baselines, left_out = load_baselines(None, loaded)
    posed = evaluate_posed(loaded.model, load_body_clips(clip), poses_path=clip, windows=WINDOWS,
                           baselines=baselines, progress=False)
    evaluation, rendered = posed.evaluation, posed.rendered
    index = evaluation_pair_index(rendered.sequences)  # (N, 3) sequence, reference, target: the evaluated pairs
    heads = np.stack([rendered.head_masks[index[:, 0], index[:, 2]], rendered.head_masks[index[:, 0], index[:, 1]]],
                     axis=1)  # (N, 2, H, W)
    extra = {"model": str(loaded.path.relative_to(ROOT)) if loaded.path.is_relative_to(ROOT) else str(loaded.path),
             "model_kind": loaded.kind, "model_step": loaded.step, "poses": posed.poses}
    if left_out:
        extra["baselines_left_out"] = left_out
    return evaluation, json_payload(evaluation, extra=extra), heads


def head_crop(image: np.ndarray, head: np.ndarray, size: int) -> np.ndarray:
    """A ``HEAD_BOX``-pixel square of ``image`` (H, W, 3) centred on the head mask ``head`` (H, W), enlarged to
    ``size`` x ``size`` (nearest neighbour)."""
    import cv2

    h, w = head.shape
    ys, xs = np.nonzero(head)
    cy, cx = (int(round(ys.mean())), int(round(xs.mean()))) if len(ys) else (h // 4, w // 2)
    y0 = int(np.clip(cy - HEAD_BOX // 2, 0, h - HEAD_BOX))
    x0 = int(np.clip(cx - HEAD_BOX // 2, 0, w - HEAD_BOX))
    return cv2.resize(image[y0:y0 + HEAD_BOX, x0:x0 + HEAD_BOX], (size, size), interpolation=cv2.INTER_NEAREST)


def sheet_columns(evaluation, head_masks: np.ndarray, rows: list[int]) -> dict[str, np.ndarray]:
    """Columns of the sheet for pairs ``rows``: each method's frame at SCALE with its head crop beside it."""
    import cv2

    preds = evaluation.predictions
    names = [("reference", "reference"), ("target", "truth"), ("generator", "new")]
    names += [(k, "old") for k in preds if k not in ("generator", "reference", "target", *FRAME_BASELINES)][:1]
    names += [("limb-warp", "limb-warp")]
    out = {}
    for key, title in names:
        cells = []
        for r in rows:
            frame = preds[key][r]
            big = cv2.resize(frame, None, fx=SCALE, fy=SCALE, interpolation=cv2.INTER_NEAREST)
            # The head crop is taken where the target's head is (the reference's own head for the reference).
            mask = head_masks[r, 1] if key == "reference" else head_masks[r, 0]
            side = np.full((big.shape[0], big.shape[1] // 2, 3), 255, np.uint8)  # the head crop, top right
            side[: big.shape[1] // 2] = head_crop(frame, mask, big.shape[1] // 2)
            cells.append(np.concatenate([big, side], axis=1))
        out[title] = np.stack(cells)
    return out


def _frames_real_table(payloads: dict[str, dict], model: str) -> str:
    head = ("| clip | method | person PSNR | person SSIM | person sharpness | head PSNR | head SSIM | whole PSNR |\n"
            "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows = []
    for clip, payload in payloads.items():
        for key in order(payload["results"]):
            r = payload["results"].get(key)
            if r is not None:
                rows.append(f"| `{clip}` | {method_name(key, model)} | {r['person_psnr']:.2f} "
                            f"| {r['person_ssim']:.3f} | {r['person_sharpness']:.2f} | {r['head_psnr']:.2f} "
                            f"| {r['head_ssim']:.3f} | {r['psnr']:.2f} |")
    return head + "\n" + "\n".join(rows)


def targets(payloads: dict[str, dict]) -> str:
    head = "| target | " + " | ".join(f"`{c}`" for c in payloads) + " |\n| --- |" + " --- |" * len(payloads)
    rows = [f"| {text} | " + " | ".join("met" if p["targets_met"].get(key) else "**missed**"
                                         for p in payloads.values()) + " |" for key, text in _frames_real_TARGETS.items()]
    return head + "\n" + "\n".join(rows)


def _frames_real_section(payloads: dict[str, dict], model: str) -> str:
    """The block between the frames-real markers of docs/results.md (no heading: the page's own stands above it)."""
    left_out = {k: v for p in payloads.values() for k, v in p.get("baselines_left_out", {}).items()}
    old = ("" if not left_out else
           f"\nThe previous generator (`{', '.join(left_out)}`) is left out: the loader refuses it ({'; '.join(left_out.values())}).")
    clips = "\n".join(f"motion2video evaluate-frames --model {model} --poses ../shared/data/mocap/{c}" for c in payloads)
    return f"""One run per clip (`python scripts/make_results.py frames-real` runs the same functions and writes this section):

```
{clips}
```

The frame test split's 8 held-out identities, posed by {WINDOWS} windows spread evenly over each real CMU capture (9
frames over 1.2 s each; frame 0 of a window is the reference, the 8 later frames the targets), rendered by the Anny
body renderer exactly as the training data is; the truth is the render of each pose. None of these clips is in the
frame training data (`motion2video.generator.specs.is_test_clip`). The head is the target's visible head: the pixels
where Anny's head vertices are the front surface, by a depth test, so a hand in front of the face is not head.{old}

{_frames_real_table(payloads, model)}

The targets driven by real motion:

{targets(payloads)}

Reference | truth | new | old | limb-warp, two pairs per clip ({', '.join(f'`{c}`' for c in payloads)},
top to bottom), at twice the frame size, each with the head region enlarged beside it (top right):

![real motion sheet](images/frames_real_motion.png)
"""


def frames_real_main(argv: list[str] | None = None) -> int:
    import imageio.v3 as iio

    from motion2video.generator.scores import contact_sheet

    parser = argparse.ArgumentParser(description=FRAMES_REAL_DOC, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="frames-body-mesh-256",
                        help="the body generator (default frames-body-mesh-256, make demo's)")
    parser.add_argument("--mocap", default=str(ROOT.parent / "shared" / "data" / "mocap"),
                        help="the mocap folder holding cmu/ (default ../shared/data/mocap)")
    parser.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    parser.add_argument("--sheet", default=str(ROOT / "docs" / "images" / "frames_real_motion.png"))
    parser.add_argument("--json", default=str(ROOT / "out" / "results_frames_real.json"))
    args = parser.parse_args(argv)
    check_section(args.doc, FRAMES_REAL_BEGIN, FRAMES_REAL_END)

    from motion2video.generator.specs import is_test_clip

    payloads, columns = {}, []
    for clip in CLIPS:
        assert is_test_clip(clip), f"{clip} is a frame training clip"
        evaluation, payload, heads = evaluate_clip(args.model, Path(args.mocap) / clip)
        payloads[clip] = payload
        columns.append(sheet_columns(evaluation, heads, list(SHEET_ROWS)))
        print(f"{clip}: {json.dumps({k: v['person_psnr'] for k, v in payload['results'].items()})}", flush=True)
    merged = {k: np.concatenate([c[k] for c in columns]) for k in columns[0]}
    sheet = Path(args.sheet)
    sheet.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(sheet, contact_sheet(merged, label_height=22))
    write_json(args.json, payloads)
    write_section(args.doc, FRAMES_REAL_BEGIN, FRAMES_REAL_END, _frames_real_section(payloads, args.model))
    print(f"wrote {args.doc}, {sheet} and {args.json}")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# transfer: Behaviour transfer (Blattmann et al. 2021, Tables 1 and 3) and MT-VAE analogy.
# ----------------------------------------------------------------------------------------------------------------


TRANSFER_DOC = """Behaviour transfer (Blattmann et al. 2021, Tables 1 and 3) and MT-VAE analogy.

    python scripts/make_results.py transfer --json out/results_transfer.json        # ~23 min on 2 CPU cores
    python scripts/make_results.py transfer --steps 20 --analogy-steps 20 --out /tmp/r.md  # smoke run

What it does (one torch thread; every number comes from this run):

1. Loads the real mocap (default ``../shared/data/mocap``) at 25 fps, 16 observed + 48 future frames, only the
   clips of the recorded split of ``--split-of`` (default: the 72-clip, 4.7-minute mtvae-add of git 805c753) and
   that split's held-out test clips.
2. Trains five models the same way (same sizes, steps, batches, seed; the behaviour variants also get their
   normalizing flow fitted), differing only in the objective:
   ``behavior`` (gamma_C = 0.1, KL budget with dual ascent), ``behavior, gamma_C = 0`` (no
   disentanglement), a conditional autoencoder (the behaviour architecture with gamma_KL fixed at 0 and
   gamma_C = 0: no KL term; the posterior mean is used everywhere, so the latent is deterministic at
   evaluation), a plain cVAE (the behaviour architecture with the Eq. 1 ELBO: gamma_KL fixed at 1, no budget,
   gamma_C = 0) and MT-VAE (add), whose transfer is the analogy z = E(obs_src, fut_src), x_R = D(obs_tgt, z).
3. On every held-out window (stride 8), transfers the source's behaviour to the start posture of a window
   of another held-out clip and scores TDE, RE and d_beta / d_random at T = 40
   (:func:`motion2video.evaluation.transfer_protocol.evaluate_transfer`), and checks the paper's statements.
4. The known-answer analogy: a small mtvae-add trained on the procedural multimodal benchmark's
   transitions; for several X -> Y and 20 seeds each, the mode classifier's label of D, against a prior
   sample from C (what the model does without the A -> B latent).

Writes two blocks of ``docs/results_transfer.md`` (``--out``), each between its markers: the known-answer
analogy table ("Analogy") and the Table 1 / 3 numbers with the paper's statements checked ("The behaviour
paper's claims, checked"); with ``--json``, the raw numbers.
"""

TRANSFER_ANALOGY_BEGIN, TRANSFER_ANALOGY_END = "<!-- transfer-analogy:begin -->", "<!-- transfer-analogy:end -->"


TRANSFER_CLAIMS_BEGIN, TRANSFER_CLAIMS_END = "<!-- transfer-claims:begin -->", "<!-- transfer-claims:end -->"


ANALOGY_SEQUENCES = 600  # procedural transition sequences the analogy model trains on


VARIANTS = (  # (label, registry name, model config on top of SIZES[name])
    ("behavior (gamma_C = 0.1)", "behavior", {"gamma_c": 0.1}),
    ("behavior, gamma_C = 0", "behavior", {"gamma_c": 0.0}),
    ("cAE (no KL, gamma_C = 0)", "behavior", {"gamma_c": 0.0, "kl_multiplier_init": 0.0, "kl_multiplier_lr": 0.0}),
    ("cVAE (Eq. 1 ELBO)", "behavior", {"gamma_c": 0.0, "kl_multiplier_init": 1.0, "kl_multiplier_lr": 0.0,
                                       "kl_budget": 0.0}),
    ("MT-VAE add (analogy)", "mtvae-add", {}),
)


SIZES = {"behavior": {"hidden_dim": 128, "latent_dim": 32, "regressor_dim": 128},
         "mtvae-add": {"hidden_dim": 128, "latent_dim": 32, "mlp_dim": 128}}


ANALOGY_PAIRS = (("walk", "run"), ("walk", "turn"), ("run", "walk"), ("stand", "jump"), ("stand", "squat"),
                 ("stand", "wave"), ("stand", "punch"))


ANALOGY_MODEL = {"hidden_dim": 64, "latent_dim": 8, "mlp_dim": 64}


def slug(label: str) -> str:
    return "".join(c if c.isalnum() else "-" for c in label.lower()).strip("-").replace("--", "-")


def _reusable(path: Path, *, name: str, config: dict, data, train) -> bool:
    """True when ``path`` is a checkpoint of exactly this model config, data config and training config
    (``--workdir`` reuse)."""
    import dataclasses

    from motion2video.models.checkpoint import read_meta

    if not path.is_file():
        return False
    meta = read_meta(path)
    return (meta.model == name and meta.data_config == data and meta.training.get("config") == dataclasses.asdict(train)
            and all(meta.config.get(k) == v for k, v in config.items()))


def train_variants(dataset, *, steps: int, batch_size: int, workdir: Path, seed: int) -> dict:
    """Train every variant (or reuse an identical checkpoint in ``workdir``); returns label -> (path, training
    wall time in seconds as the checkpoint records it)."""
    from motion2video.models.checkpoint import read_meta
    from motion2video.models.training import TrainConfig, train_model

    out = {}
    for label, name, extra in VARIANTS:
        path = workdir / f"{slug(label)}.safetensors"
        model_config = {**SIZES[name], **extra}
        config = TrainConfig(steps=steps, batch_size=batch_size, checkpoint_every=10 ** 9, val_every=0,
                             val_windows=128, flow_steps=max(steps // 2, 10), flow_windows=2048, seed=seed)
        if not _reusable(path, name=name, config=model_config, data=dataset.config, train=config):
            train_model(model_name=name, model_config=model_config, dataset=dataset, config=config, out=path,
                        progress=False)
        out[label] = (path, float(read_meta(path).training["wall_time_s"]))
        print(f"[{time.strftime('%H:%M:%S')}] {label}: trained in {out[label][1]:.0f} s", flush=True)
    return out


def known_answer(*, steps: int, seeds: int, workdir: Path, seed: int) -> dict:
    """Train the procedural mtvae-add and label D (analogy) and a prior sample from C for each pair."""
    from motion2video.stages.latents import analogy_windows
    from motion2video.evaluation.analogy import procedural_analogy_case, procedural_transition_dataset
    from motion2video.models.checkpoint import load_model
    from motion2video.data.dataset import decode_samples, encode_windows
    from motion2video.data.multimodal import default_classifier
    from motion2video.models.training import TrainConfig, train_model

    dataset = procedural_transition_dataset(ANALOGY_SEQUENCES, seed=1)
    path = workdir / "procedural-mtvae-add.safetensors"
    model_config = {**ANALOGY_MODEL, "kl_anneal_steps": max(steps // 2, 1)}
    config = TrainConfig(steps=steps, batch_size=32, lr=3e-3, warmup_steps=20, checkpoint_every=10 ** 9,
                         val_every=0, val_windows=32, seed=seed)
    if not _reusable(path, name="mtvae-add", config=model_config, data=dataset.config, train=config):
        train_model(model_name="mtvae-add", model_config=model_config, dataset=dataset, config=config, out=path,
                    progress=False)
    bundle = load_model(path)
    train_s = float(bundle.meta.training["wall_time_s"])
    classifier = default_classifier()
    rows = []
    for x, y in ANALOGY_PAIRS:
        cases = [procedural_analogy_case(x, y, seed=s) for s in range(seeds)]
        ab, c = np.stack([a for a, _ in cases]), np.stack([c for _, c in cases])
        _, d, _, _ = analogy_windows(bundle, ab, c, observed=16, horizon=48)
        raw_c, frame_c = encode_windows(c, config=bundle.data_config)
        gen = torch.Generator().manual_seed(seed)
        with torch.no_grad():
            prior = bundle.model.sample(torch.from_numpy(bundle.stats.normalize(raw_c)), num_samples=1, horizon=48,
                                        generator=gen)
        prior_d = decode_samples(prior.numpy(), config=bundle.data_config, stats=bundle.stats, frame=frame_c)[:, 0]
        d_labels, p_labels = classifier.predict(d), classifier.predict(prior_d)
        rows.append({"x": x, "y": y, "analogy": dict(Counter(d_labels.tolist())),
                     "prior": dict(Counter(p_labels.tolist())), "analogy_hits": int((d_labels == y).sum()),
                     "prior_hits": int((p_labels == y).sum())})
        print(f"  {x} -> {y}: D labelled {y} {rows[-1]['analogy_hits']}/{seeds} (prior {rows[-1]['prior_hits']})",
              flush=True)
    return {"rows": rows, "seeds": seeds, "steps": steps, "train_s": train_s, "model": ANALOGY_MODEL,
            "data": dataset.describe()}


def _fmt(v: float) -> str:
    return f"{v:.2f}" if abs(v) < 100 else f"{v:.0f}"


SHORT = {"behavior (gamma_C = 0.1)": "the behaviour model", "behavior, gamma_C = 0": "gamma_C = 0",
         "cAE (no KL, gamma_C = 0)": "the cAE", "cVAE (Eq. 1 ELBO)": "the cVAE", "MT-VAE add (analogy)": "MT-VAE's analogy"}


def claims(scores: dict) -> list[tuple[str, str]]:
    """The paper's Table 1 / 3 statements, checked on these numbers: (statement, found) rows."""
    b, b0 = scores["behavior (gamma_C = 0.1)"], scores["behavior, gamma_C = 0"]
    cvae = scores["cVAE (Eq. 1 ELBO)"]
    rel = {k: s.d_beta.mean / max(s.d_random.mean, 1e-12) for k, s in scores.items()}

    def yes(ok: bool) -> str:
        return "yes" if ok else "no"

    lowest = min(scores, key=lambda k: scores[k].tde[40])
    rows = [("cAE copies the source (lowest TDE at T = 40)",
             "yes" if lowest == "cAE (no KL, gamma_C = 0)" else f"no ({SHORT.get(lowest, lowest)} is lowest)"),
            ("the cVAE's latent collapses", f"{yes(cvae.d_random.mean < 0.1 * b.d_random.mean)} (d_random "
             f"{cvae.d_random.mean:.2f} against {b.d_random.mean:.2f})")]
    raised = {what: getattr(b, key)[40] > getattr(b0, key)[40] for what, key in (("TDE", "tde"), ("RE", "re"))}
    noisy = [what for what, key in (("TDE", "tde"), ("RE", "re"))
             if abs(getattr(b, key)[40] - getattr(b0, key)[40]) < 2.0 * float(np.hypot(getattr(b, f"{key}_se")[40],
                                                                                    getattr(b0, f"{key}_se")[40]))]
    found = ("yes" if all(raised.values()) else "no" if not any(raised.values())
             else f"{next(w for w, up in raised.items() if up)} only")
    if len(noisy) == 2:
        found += ", both within 2 standard errors: not significant"
    elif noisy:
        found += f", {noisy[0]} within 2 standard errors: not significant"
    else:
        found += f" (TDE {_fmt(b.tde[40])} against {_fmt(b0.tde[40])}, RE {_fmt(b.re[40])} against {_fmt(b0.re[40])})"
    rows += [("disentanglement raises TDE(40) and RE(40)", found),
             ("disentanglement keeps the behaviour closer", f"{yes(rel['behavior (gamma_C = 0.1)'] < rel['behavior, gamma_C = 0'])} "
              f"({rel['behavior (gamma_C = 0.1)']:.2f} against {rel['behavior, gamma_C = 0']:.2f})"),
             ("the behaviour model keeps the behaviour closer than MT-VAE's analogy",
              f"{yes(rel['behavior (gamma_C = 0.1)'] < rel['MT-VAE add (analogy)'])} "
              f"({rel['behavior (gamma_C = 0.1)']:.2f} against {rel['MT-VAE add (analogy)']:.2f})")]
    bp = b.realism_poses
    flow = bp.get("flow", float("nan"))
    rows.append(("flow samples are more realistic than prior samples (pose classifier)",
                 f"{yes(flow < bp['prior'])} ({flow:.2f} against {bp['prior']:.2f})"))
    return rows


def _transfer_claims_block(scores: dict, info: dict) -> str:
    """The block between the transfer-claims markers of docs/results_transfer.md (no heading)."""
    text = (f"Blattmann et al. (CVPR 2021), Tables 1 and 3, on the first {info['clips']} clips ({info['minutes']:.1f} "
            f"minutes) with five small models trained the same way ({info['steps']} steps, hidden "
            f"{SIZES['behavior']['hidden_dim']}, latent {SIZES['behavior']['latent_dim']}): `{info['command']}` (about "
            f"{info['total_min']:.0f} minutes on {info['cores']} cores). Held-out transfer pairs ({info['test_windows']} "
            "windows, each behaviour re-enacted from another held-out clip's posture); TDE(40) = error between "
            "re-enactment and source at generated frame 40 (cm^2; large = not copying), RE(40) = error of a ridge "
            "regression from z to the posture (large = little posture in z), d_beta / d_random = distance of the "
            "re-enactment's behaviour code to the source's over a random pair's (lower = behaviour kept):")
    lines = [*_wrap(text), "",
             "| model | TDE(40) | RE(40) | d_beta / d_random |", "| --- | ---: | ---: | ---: |"]
    lines += [f"| {label} | {_fmt(s.tde[40])} | {_fmt(s.re[40])} | {s.d_beta.mean / max(s.d_random.mean, 1e-12):.2f} |"
              for label, s in scores.items()]
    lines += ["", "| the paper's statement | found |", "| --- | --- |"]
    lines += [f"| {statement} | {found} |" for statement, found in claims(scores)]
    return "\n".join(lines)


def _transfer_analogy_block(analogy: dict) -> str:
    """The block between the transfer-analogy markers of docs/results_transfer.md (no heading)."""
    m = analogy["model"]
    text = (f"**Known answer, procedural transitions.** A small `mtvae-add` (hidden {m['hidden_dim']}, latent "
            f"{m['latent_dim']}, {analogy['steps']} steps on {ANALOGY_SEQUENCES} sequences of the multimodal benchmark); "
            f"for each X -> Y and {analogy['seeds']} seeds, A -> B is a clip where X turns into Y, C another instance "
            "of X of another size and speed, D = decode(C, E(A, B)) labelled by the nearest-template classifier; the "
            "prior's samples from C for comparison:")
    lines = [*_wrap(text), "",
             "| X -> Y | D labelled Y | D labels | prior labelled Y |", "| --- | ---: | --- | ---: |"]
    for r in analogy["rows"]:
        labels = ", ".join(f"{k} {v}" for k, v in sorted(r["analogy"].items(), key=lambda kv: -kv[1]))
        lines.append(f"| {r['x']} -> {r['y']} | {r['analogy_hits']}/{analogy['seeds']} | {labels} | "
                     f"{r['prior_hits']}/{analogy['seeds']} |")
    return "\n".join(lines)


def transfer_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=TRANSFER_DOC.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--steps", type=int, default=1200, help="training steps per transfer model")
    parser.add_argument("--batch-size", type=int, default=32)
    parser.add_argument("--analogy-steps", type=int, default=500, help="steps of the procedural analogy model")
    parser.add_argument("--seeds", type=int, default=20, help="known-answer seeds per X -> Y")
    parser.add_argument("--stride", type=int, default=8, help="frames between held-out windows")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workdir", default=None, help="keep / reuse the checkpoints here (default: a temp dir)")
    parser.add_argument("--split-of", default=f"git:{OLD_REV}:motion2video/weights/mtvae-add.safetensors",
                        help="a checkpoint (path or git:REV:PATH) whose recorded split is used, its clips only "
                        "(default: the 72-clip mtvae-add); '' = the whole folder split with split_seed 1")
    parser.add_argument("--cache", default="/tmp/motion2video-git-weights", help="where git:REV:PATH files are written")
    parser.add_argument("--out", default=str(ROOT / "docs" / "results_transfer.md"))
    parser.add_argument("--json", default=None, help="also write the raw numbers here")
    args = parser.parse_args(argv)
    out = Path(args.out)
    for begin, end in ((TRANSFER_ANALOGY_BEGIN, TRANSFER_ANALOGY_END), (TRANSFER_CLAIMS_BEGIN, TRANSFER_CLAIMS_END)):
        check_section(out, begin, end)

    import os

    from motion2video.models import checkpoint
    from motion2video.evaluation.transfer_protocol import evaluate_transfer, transfer_pairs

    torch.set_num_threads(1)
    t_all = time.perf_counter()
    command = "python scripts/make_results.py transfer " + " ".join(shlex.quote(a) for a in (sys.argv[2:] if argv is None else argv))
    with tempfile.TemporaryDirectory(prefix="m2v-results-transfer-") as tmp:
        workdir = Path(args.workdir) if args.workdir else Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        split = checkpoint.read_meta(resolve(args.split_of, Path(args.cache))).split if args.split_of else None
        dataset = build_dataset(args.data, DatasetConfig(split_seed=1), split=split, recorded_only=split is not None)
        trained = train_variants(dataset, steps=args.steps, batch_size=args.batch_size, workdir=workdir,
                                 seed=args.seed)
        test = dataset.windows("test", stride=args.stride)
        train = dataset.windows("train", stride=16)
        pairs = transfer_pairs(test.clip_names, seed=args.seed)
        scores = {}
        for label, (path, _) in trained.items():
            scores[label] = evaluate_transfer(load_model(path), test, train, pairs=pairs, seed=args.seed)
            s = scores[label]
            print(f"{label}: TDE@40 {s.tde[40]:.1f}, RE@40 {s.re[40]:.1f}, d_beta {s.d_beta.mean:.3f} "
                  f"(random {s.d_random.mean:.3f}), realism {s.realism}", flush=True)
        analogy = known_answer(steps=args.analogy_steps, seeds=args.seeds, workdir=workdir, seed=args.seed)
    info = {
        "command": command.strip(), "date": time.strftime("%Y-%m-%d"),
        "machine": f"{platform.machine()}, {platform.system()}, torch {torch.__version__}",
        "total_min": (time.perf_counter() - t_all) / 60.0, "data": args.data, "cores": os.cpu_count(),
        "clips": dataset.summary["clips"], "minutes": dataset.summary["frames"] / dataset.summary["fps"] / 60,
        "test_clips": sorted(set(test.clip_names)), "test_windows": len(test), "train_windows": len(train),
        "stride": args.stride, "steps": args.steps, "batch_size": args.batch_size, "seed": args.seed,
        "train_s": {k: v[1] for k, v in trained.items()},
    }
    if not out.is_file():  # a new page (e.g. a smoke run's --out) starts with both marker pairs
        write_text(out, f"# Results\n\n{TRANSFER_ANALOGY_BEGIN}\n{TRANSFER_ANALOGY_END}\n\n"
                        f"{TRANSFER_CLAIMS_BEGIN}\n{TRANSFER_CLAIMS_END}\n")
    write_section(out, TRANSFER_ANALOGY_BEGIN, TRANSFER_ANALOGY_END, _transfer_analogy_block(analogy))
    write_section(out, TRANSFER_CLAIMS_BEGIN, TRANSFER_CLAIMS_END, _transfer_claims_block(scores, info))
    print(f"wrote {out} in {info['total_min']:.1f} min")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"info": info, "transfer": {k: v.to_json() for k, v in scores.items()},
                                               "analogy": analogy}, indent=1, default=str))
        print(f"wrote {args.json}")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# transfer_benchmark: the liveliness of the shipped body models' futures and of the behaviour model's transfers.
# ----------------------------------------------------------------------------------------------------------------


TRANSFER_BENCHMARK_DOC = """The liveliness of the shipped body models' sampled futures and of the behaviour model's transfers.

    python scripts/make_results.py transfer-benchmark [--sampler LABEL=CHECKPOINT ...] [--behavior CHECKPOINT]

On the held-out windows (stride 8) of the corpus's pinned subject-disjoint split (the checkpoints' own split):
the mean absolute velocity / acceleration of the features per frame of --samples futures per window of each
--sampler (default mtvae-add, lcpvae and behavior, whose futures are flow samples;
:func:`motion2video.evaluation.transfer_protocol.sample_realism`) and of the --behavior model's transfers with
the decoder as trained (:func:`motion2video.evaluation.transfer_protocol.evaluate_transfer`), as ratios to the
held-out ground truth's. Writes the table between the transfer-benchmark markers of docs/results_transfer.md
("Liveliness") and, with --json, the raw numbers (the realism scores the same functions give included).
"""

TRANSFER_BENCHMARK_BEGIN = "<!-- transfer-benchmark:begin (scripts/make_results.py transfer-benchmark) -->"


TRANSFER_BENCHMARK_END = "<!-- transfer-benchmark:end -->"


LIVELINESS_SAMPLERS = ("mtvae-add", "lcpvae", "behavior")  # the default --sampler models (label = shipped name)


def _pairs(values: list[str]) -> list[tuple[str, str]]:
    out = []
    for v in values:
        label, _, path = v.partition("=")
        if not path:
            raise InputError(f"--sampler wants LABEL=CHECKPOINT, got {v!r}")
        out.append((label, path))
    return out


_CLIPS: dict = {}  # data config -> the clips of the mocap folder, read once per config for every function below


def checkpoint_dataset(mocap: str, bundle):
    """The mocap folder as ``bundle`` sees it (its data config, split and normalisation), the files read once."""
    from motion2video.data.dataset import build_dataset, load_clips

    cfg = bundle.data_config
    if cfg not in _CLIPS:
        _CLIPS[cfg] = load_clips(mocap, config=cfg)
    return build_dataset(mocap, cfg, split=bundle.meta.split, stats=bundle.stats, clips=_CLIPS[cfg])


def transfer_liveliness(mocap: str, checkpoint: str, *, stride: int, seed: int) -> dict:
    """:func:`motion2video.evaluation.transfer_protocol.evaluate_transfer` of one behaviour model on the held-out
    windows: liveliness (``motion``: origin -> (velocity, acceleration), ``real`` the ground truth's), realism."""
    from motion2video.evaluation.transfer_protocol import evaluate_transfer, transfer_pairs

    bundle = load_model(checkpoint)
    dataset = checkpoint_dataset(mocap, bundle)
    test = dataset.windows("test", stride=stride)
    s = evaluate_transfer(bundle, test, dataset.windows("train", stride=32), pairs=transfer_pairs(test.clip_names,
                                                                                                  seed=seed), seed=seed)
    return {"model": bundle.name, "motion": s.motion, "realism": s.realism, "realism_control": s.realism_control,
            "realism_poses": s.realism_poses, "windows": s.windows}


def sampler_rows(mocap: str, checkpoints: list[tuple[str, str]], *, stride: int, samples: int, seed: int) -> dict:
    """Liveliness and realism of each model's sampled futures (what `sample` and `synthesize` draw) on the
    held-out windows: :func:`motion2video.evaluation.transfer_protocol.sample_realism`, and the model's name."""
    from motion2video.evaluation.transfer_protocol import sample_realism

    out = {}
    for label, path in checkpoints:
        bundle = load_model(path)
        dataset = checkpoint_dataset(mocap, bundle)
        out[label] = {"model": bundle.name, **dataclasses.asdict(sample_realism(
            bundle, dataset.windows("test", stride=stride), samples=samples, seed=seed))}
    return out


def _transfer_benchmark_render(samplers: dict, transfers: dict, *, label: str, command: str) -> str:
    """The block between the transfer-benchmark markers of docs/results_transfer.md (no heading)."""
    first = next(iter(samplers.values()))
    real_v, real_a = first["real"]
    rows = []
    for name, d in samplers.items():
        (v, a), (rv, ra) = d["samples"], d["real"]  # each model's own ground truth
        rows.append(f"| `{name}`{', flow samples' if d['model'] == 'behavior' else ''} | {v / rv:.2f} / {a / ra:.2f} |")
    (v, a), (rv, ra) = transfers["motion"]["transfer"], transfers["motion"]["real"]
    rows.append(f"| `{label}`, transfers (decoder as trained) | {v / rv:.2f} / {a / ra:.2f} |")
    return f"""Mean absolute velocity / acceleration of the features per frame, as a ratio to the held-out ground truth's
({real_v:.4f} m/frame / {real_a:.4f} m/frame^2), over {first['samples_per_window']} sampled futures per held-out window ({first['windows']} windows; target 0.8-1.2);
`{command}`:

| model | velocity / acceleration (x the truth's) |
| --- | ---: |
""" + "\n".join(rows)


def transfer_benchmark_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=TRANSFER_BENCHMARK_DOC.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--sampler", action="append", default=None,
                        help="LABEL=CHECKPOINT whose sampled futures are measured (repeatable; default: "
                        + ", ".join(LIVELINESS_SAMPLERS) + ")")
    parser.add_argument("--behavior", default="behavior", help="the behaviour model whose transfers are measured")
    parser.add_argument("--stride", type=int, default=8, help="frames between held-out windows")
    parser.add_argument("--samples", type=int, default=10, help="futures per window")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default=str(ROOT / "docs" / "results_transfer.md"))
    parser.add_argument("--json", default=None, help="also write the raw numbers here")
    args = parser.parse_args(argv)
    check_section(args.out, TRANSFER_BENCHMARK_BEGIN, TRANSFER_BENCHMARK_END)
    torch.set_num_threads(1)
    samplers = sampler_rows(args.data, _pairs(args.sampler) if args.sampler else
                            [(n, n) for n in LIVELINESS_SAMPLERS], stride=args.stride, samples=args.samples, seed=args.seed)
    transfers = transfer_liveliness(args.data, args.behavior, stride=args.stride, seed=args.seed)
    command = "python scripts/make_results.py transfer-benchmark" + "".join(
        f" --{k} {getattr(args, k)}" for k in ("behavior", "stride", "samples", "seed")
        if getattr(args, k) != parser.get_default(k)) + "".join(f" --sampler {shlex.quote(v)}" for v in args.sampler or [])
    label = Path(args.behavior).name.removesuffix(".safetensors")
    write_section(args.out, TRANSFER_BENCHMARK_BEGIN, TRANSFER_BENCHMARK_END,
                  _transfer_benchmark_render(samplers, transfers, label=label, command=command))
    if args.json:
        write_json(args.json, json.loads(json.dumps({"samplers": samplers, "transfers": transfers}, default=list)))
    print(f"wrote {args.out}")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# face-sheet: the photo's face over the generated heads (docs/images/face_sheet.png)
# ----------------------------------------------------------------------------------------------------------------

FACE_SHEET_DOC = """The photo's face over the generated heads: photos driven by a motion-capture clip's frames, a sheet.

For each photo (a body reference, its pose estimated), the clip's observed frames drive the mesh frame generator
(``synthesize``'s path: the motion model only supplies the structures of the observed frames, which are the clip's
own; ``--frame-model frames-body-128``: the keypoint warp) and each picked frame is drawn twice: the generator's own
head, and with the photo's face laid over it (:mod:`motion2video.generator.head_paste`). The sheet shows the whole
frame and a close-up of the head (nearest neighbour, so the pixels are the frame's); ``--json`` records, per photo,
how much of the face each frame took and in what share of all the frames a face detector finds a face on the head,
either way.

    python scripts/make_results.py face-sheet ../shared/data/mocap/cmu/08_01.bvh \\
        ../shared/data/photos/woman_blue_tracksuit.jpg ../shared/data/photos/fashion_man_red_jacket.png \\
        ../shared/data/photos/skier.jpg --size 512 --columns 3 -o docs/images/face_sheet.png --json out/face_sheet.json
"""

FACE_CLOSE_UP_PX = 96  # the head close-up's side on the sheet
FACE_LABEL_PX = 14


def head_close_up(frame: np.ndarray, points: np.ndarray, side: int = FACE_CLOSE_UP_PX) -> np.ndarray:
    """(side, side, 3) the square of 1.6 x the thorax-to-head distance around the head of (17, 2) joints, enlarged
    by nearest neighbour."""
    import cv2

    from motion2video.core.skeletons import HEAD, NECK, THORAX

    centre = 0.5 * (points[NECK] + points[HEAD])
    half = max(4.0, 0.8 * float(np.linalg.norm(points[HEAD] - points[THORAX])))
    k = side / (2 * half)
    mat = np.array([[k, 0.0, -(centre[0] - half) * k], [0.0, k, -(centre[1] - half) * k]])
    return cv2.warpAffine(frame, mat, (side, side), flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)


def sheet_label(image: np.ndarray, text: str) -> np.ndarray:
    """The image with ``text`` in white on a black band at its top left."""
    import cv2

    out = image.copy()
    cv2.rectangle(out, (0, 0), (min(out.shape[1], 8 + 7 * len(text)), FACE_LABEL_PX), (0, 0, 0), -1)
    cv2.putText(out, text, (2, FACE_LABEL_PX - 3), cv2.FONT_HERSHEY_SIMPLEX, 0.38, (255, 255, 255), 1, cv2.LINE_AA)
    return out


def detected_share(frames: np.ndarray, points: np.ndarray) -> float:
    """The share of (N, S, S, 3) frames in which BlazeFace finds a face in the square of 3 x the thorax-to-head
    distance around the head of their (N, 17, 2) joints, enlarged to 192 px: a face a detector can read."""
    import cv2

    from motion2video.stages.pictured_face import cut_square, face_mesh, head_square

    found = 0
    for frame, p in zip(frames, points):
        square = cv2.resize(cut_square(frame, head_square(p)), (192, 192), interpolation=cv2.INTER_CUBIC)
        found += bool(face_mesh().detect(np.ascontiguousarray(square)))
    return found / max(1, len(frames))


def photo_rows(net, photo: Path, clip, bundle, *, size: int, frames: int, columns: int, crop_person: bool
               ) -> tuple[list[np.ndarray], dict]:
    """Two rows (the generator's head, the photo's face) for one photo; the paste weights of the picked frames and
    the share of all the frames where a face detector finds the face (:func:`detected_share`), either way. ``net``
    is a mesh generator or the keypoint warp."""
    from dataclasses import replace

    import cv2

    from motion2video.stages.generation import is_warp, mesh_frames, mesh_setup, paste_faces, warp_face
    from motion2video.stages.reference import load_reference
    from motion2video.stages.sampling import sample_forecast
    from motion2video.stages.structure import render_structures

    ref = load_reference(photo, size=size, domain="body", crop_person=crop_person)
    fc = sample_forecast(bundle, clip, samples=1, observed=frames, horizon=1, start=0, seed=0)
    structures = render_structures(fc, domain="body", size=size, reference=ref)
    every = np.arange(frames)
    if is_warp(net):  # the keypoint warp: its own frames, then the face moved as it moves the head
        pasted = warp_face(ref, structures)
        all_before = net.decode(net.encode_reference(ref.image, structures.points[0], path=ref.path),
                                structures.points[1:1 + frames])
        all_after = paste_faces(all_before, every, pasted)
        face, head_weights = (None, None) if pasted is None else (pasted[0], pasted[2].weights)
    else:
        video = mesh_setup(net, ref, structures)
        all_after = mesh_frames(net, ref, structures, video, every)
        all_before = mesh_frames(net, ref, structures, replace(video, face=None), every)
        face, head_weights = video.face, None if video.head is None else video.head.weights
    detected = {"generator's head": detected_share(all_before, structures.points[1:1 + frames]),
                "photo's face": detected_share(all_after, structures.points[1:1 + frames])}
    picked = np.linspace(0, frames - 1, columns).round().astype(int)
    after, before = all_after[picked], all_before[picked]
    points = structures.points[1 + picked]
    rows = []
    for name, frames_ in (("generator's head", before), ("photo's face", after)):
        cells = [np.concatenate([cv2.resize(f, (FACE_CLOSE_UP_PX, FACE_CLOSE_UP_PX), interpolation=cv2.INTER_AREA),
                                 head_close_up(f, p)], axis=1) for f, p in zip(frames_, points)]
        rows.append(sheet_label(np.concatenate(cells, axis=1), f"{photo.name}: {name}"))
    weights = None if head_weights is None else [round(float(w), 2) for w in head_weights[picked]]
    mean = None if head_weights is None else round(float(head_weights[:frames].mean()), 3)
    return rows, {"photo": photo.name, "size": size, "frames": picked.tolist(), "face_found": face is not None,
                  "weights": weights, "mean_weight": mean,
                  "face_detected_share": {k: round(v, 3) for k, v in detected.items()}}


def face_sheet_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=FACE_SHEET_DOC.splitlines()[0])
    parser.add_argument("clip", type=Path, help="motion-capture clip (.bvh) whose observed frames drive")
    parser.add_argument("photos", type=Path, nargs="+", help="reference photos")
    parser.add_argument("-o", "--output", type=Path, required=True, help="the sheet (.png)")
    parser.add_argument("--frame-model", default="frames-body-mesh-256")
    parser.add_argument("--motion-model", default="mixture-periodic")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--frames", type=int, default=32, help="observed frames of the clip")
    parser.add_argument("--columns", type=int, default=6, help="frames picked, spread over them")
    parser.add_argument("--crop-person", action="store_true")
    parser.add_argument("--json", type=Path, default=None, help="write each photo's numbers here")
    args = parser.parse_args(argv)

    import cv2

    from motion2video.models.checkpoint import load_model
    from motion2video.stages.clips import load_clip

    bundle = load_model(args.motion_model)
    net = load_frame_model(args.frame_model).model
    clip = load_clip(bundle, args.clip).data
    rows, infos = [], []
    for photo in args.photos:
        photo_sheet, info = photo_rows(net, photo, clip, bundle, size=args.size, frames=args.frames,
                                       columns=args.columns, crop_person=args.crop_person)
        rows += photo_sheet
        infos.append(info)
        print(info)
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"clip": str(args.clip), "frame_model": args.frame_model, "photos": infos},
                                        indent=2) + "\n")
    sheet = np.concatenate(rows, axis=0)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.output), cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    print(f"wrote {args.output} ({sheet.shape[1]}x{sheet.shape[0]})")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# The samplers retrained on the joined corpus (mocap + Bandai-Namco) beside the shipped ones

BANDAI_DOC = """The samplers retrained on ../shared/data/mocap + ../shared/data/bandai beside the shipped ones, per action
and macro, best of K, on the same windows of two splits.

    python scripts/make_results.py bandai            # both splits, K = 50
    python scripts/make_results.py bandai --samples 5 --subject-stride 512 --json out/quick.json --doc out/quick.md

1. ``evaluate --split subjects`` on the joined corpus (the corpus's test subjects and Bandai-Namco's skeleton
   groups 1B and 2C held out; a model that trained on a held-out clip is refused), stride ``--subject-stride``:
   per action, the macro over the actions training covers, the unseen action and the cross-dataset row.
2. The corpus's held-out test windows of ``../shared/data/mocap`` (whole CMU subjects 2, 131, 140, 94 and the
   clips linked to them: the first model's recorded split), stride ``--stride``.

The retrained models come from scripts/train_shipped.sh --bandai. Writes the section between
``<!-- bandai-retrained:begin -->`` and ``<!-- bandai-retrained:end -->`` of --doc (appended when absent) and both
evaluations' JSON to --json.
"""

BANDAI_BEGIN = "<!-- bandai-retrained:begin -->"
BANDAI_END = "<!-- bandai-retrained:end -->"
BANDAI_PAIRS = (("mixture-periodic", "mixture-periodic-bandai"), ("mtvae-add-dlow", "mtvae-add-dlow-bandai"),
                ("mixer-cvae-dlow", "mixer-cvae-dlow-bandai"), ("mtvae-add", "mtvae-add-bandai"),
                ("mixer-cvae", "mixer-cvae-bandai"))
# The targets (ADE, FDE ratios to zero-velocity): whole held-out CMU subjects, and the subject split's macro.
BANDAI_TARGETS = {"corpus": (0.60, 0.48), "subjects": (0.65, 0.55)}


def _pair_cell(row: dict | None) -> str:
    return "-" if not row else f"{row['ade']:.2f} / {row['fde']:.2f}"


def _ratio(row: dict | None, ref: dict | None) -> dict | None:
    return {"ade": row["ade"] / ref["ade"], "fde": row["fde"] / ref["fde"]} if row and ref else None


def bandai_subject_rows(record: dict, labels: list[str]) -> tuple[list[str], dict[str, dict[str, dict | None]]]:
    """The subject split's rows from the JSON of ``evaluate --split subjects``: row name -> {label: ADE / FDE
    ratios to zero-velocity}; per action, the macro (ratio of the macro means, as evaluate prints it), each unseen
    action and the cross-dataset row (the held-out Bandai groups)."""
    report = record["subjects"]["report"]
    zv = report[BASELINE]
    names: list[str] = []
    rows: dict[str, dict[str, dict | None]] = {}

    def add(name: str, part: str, key: str | None) -> None:
        names.append(name)
        ref = zv[part] if key is None else zv[part][key]
        rows[name] = {m: _ratio(report[m][part] if key is None else report[m][part].get(key), ref) for m in labels}

    for action, ref in zv["per_action"].items():
        add(f"{action} ({ref[COUNT_KEY]})", "per_action", action)
    add(f"**macro, {len(zv['per_action'])} actions**", "macro", None)
    for action, ref in zv["unseen"].items():
        add(f"unseen action: {action} ({ref[COUNT_KEY]})", "unseen", action)
    if zv["cross_dataset"] is not None:
        add(f"Bandai's held-out groups ({zv['cross_dataset'][COUNT_KEY]})", "cross_dataset", None)
    return names, rows


def bandai_corpus_rows(record: dict, labels: list[str]) -> tuple[list[str], dict[str, dict[str, dict]]]:
    """The corpus test split's rows: per action, the macro (mean of the per-action ratios) and the pooled ratio,
    each {label: ADE / FDE ratios to zero-velocity} (:func:`ratios`)."""
    per = {m: ratios(record, m) for m in labels}
    zv = record["per_action"][BASELINE]
    keys = list(zv) + ["macro", "pooled"]
    names = [f"{a} ({zv[a][COUNT_KEY]})" for a in zv] + ["**macro**", "pooled"]
    return names, {n: {m: per[m][k] for m in labels} for n, k in zip(names, keys)}


def _bandai_table(names: list[str], rows: dict, pairs: list[tuple[str, str]]) -> str:
    lines = ["| row (windows) | " + " | ".join(f"`{a}` → `{b}`" for a, b in pairs) + " |",
             "| --- |" + " ---: |" * len(pairs)]
    for n in names:
        lines.append(f"| {n} | " + " | ".join(f"{_pair_cell(rows[n][a])} → {_pair_cell(rows[n][b])}"
                                                for a, b in pairs) + " |")
    return "\n".join(lines)


def bandai_section(subjects: dict, corpus: dict, pairs: list[tuple[str, str]], *, command: str,
                   minutes: float) -> str:
    """The results section: both tables (each cell: the shipped model → its retrained twin) and the targets of the
    first pair."""
    labels = [m for pair in pairs for m in pair]
    s_names, s_rows = bandai_subject_rows(subjects, labels)
    c_names, c_rows = bandai_corpus_rows(corpus, labels)
    zv = subjects["subjects"]["report"][BASELINE]
    s_windows = sum(v[COUNT_KEY] for part in ("per_action", "unseen") for v in zv[part].values())
    c_windows = sum(v[COUNT_KEY] for v in corpus["per_action"][BASELINE].values())
    samples = corpus["protocol"]["samples"]
    first, second = pairs[0]
    s_macro = next(n for n in s_names if n.startswith("**macro"))
    targets = [("whole held-out CMU subjects, macro", BANDAI_TARGETS["corpus"], c_rows["**macro**"]),
               ("the subject split, macro over actions", BANDAI_TARGETS["subjects"], s_rows[s_macro])]
    lines = [
        "### The samplers retrained with Bandai-Namco",
        "",
        "The `*-bandai` models are the recipes of `mixture-periodic` and its parts (same configs and steps) trained on "
        "`../shared/data/mocap` + `../shared/data/bandai`, on the subject split's training part: neither the corpus's "
        "test subjects nor Bandai-Namco's groups 1B and 2C (`scripts/train_shipped.sh --bandai`; their cards give the "
        "wall times). Bandai-Namco's files are CC BY-NC 4.0, so these models are for non-commercial use. Each cell: "
        f"the shipped model → its retrained twin, best-of-{samples} ADE / FDE as a ratio to zero-velocity on the same "
        f"windows (lower is better). Generated by `{command}` ({minutes:.0f} min, one thread, on the shared machine).",
        "",
        f"The subject split (`evaluate --split subjects`, stride {subjects['protocol']['stride']}, {s_windows} "
        "windows; macro = ratio of the macro means, as `evaluate` prints it):",
        "",
        _bandai_table(s_names, s_rows, pairs),
        "",
        f"Whole held-out CMU subjects (the corpus's test split of `../shared/data/mocap`, stride "
        f"{corpus['protocol']['stride']}, {c_windows} windows; macro = mean of the per-action ratios, as in "
        "\"Forecasting body motion\"):",
        "",
        _bandai_table(c_names, c_rows, pairs),
        "",
        f"Targets, `{first}` → `{second}`:",
        "",
        "| target (ADE / FDE ratio) | shipped | retrained | |",
        "| --- | ---: | ---: | --- |",
    ]
    for text, (ta, tf), row in targets:
        got = row[second]
        met = "met" if got["ade"] <= ta and got["fde"] <= tf else "missed"
        lines.append(f"| {text} <= {ta:.2f} / {tf:.2f} | {_pair_cell(row[first])} | {_pair_cell(got)} | {met} |")
    return "\n".join(lines)


BANDAI_MIXTURE_COMMAND = ("python scripts/make_mixture.py motion2video/weights/mtvae-add-dlow-bandai.safetensors "
                          "motion2video/weights/mixer-cvae-dlow-bandai.safetensors mirror-periodic settle "
                          "--shares 17,17,12,4 "
                          "-o motion2video/weights/mixture-periodic-bandai.safetensors")


def _bandai_mixture_card(path: Path, ev: dict, command: str) -> str:
    """The head of a composed mixture's card: what it draws from, the command, its data and held-out metrics."""
    meta = load_model(path).meta
    summary = meta.data_summary
    parts = meta.training["composed_from"]
    shares = meta.config.get("shares")
    res = ev["results"]
    return "\n".join([
        f"# {path.stem}",
        "",
        f"Model `{meta.model}` ({meta.kind}), layout `{meta.data_config.layout}`, {path.stat().st_size / 2 ** 20:.1f} MB, "
        f"motion2video {meta.version}. The composition of `mixture-periodic` (its card says what the parts and the "
        "rule do and why) with learned parts trained on the corpus joined with Bandai-Namco's files.",
        "",
        "## How it was made",
        "",
        "Nothing was trained for it. Composed from "
        + ", ".join(f"`{c['name']}` ({c['steps']} steps)" if c.get("steps") else f"`{c['name']}`" for c in parts)
        + (f" with shares {':'.join(f'{x:g}' for x in shares)}" if shares else "") + ":",
        "",
        f"```\n{command}\n```",
        "",
        "## Data",
        "",
        f"The learned parts' (identical for both): {_sources(summary.get('source'))}: {summary.get('clips')} clips, "
        f"{summary.get('frames')} frames at {summary.get('fps')} fps (held-out test groups: "
        f"{', '.join(summary.get('test_groups', []))}). Windows of {meta.data_config.observed} observed + "
        f"{meta.data_config.future} future frames.",
        "",
        *_card_metrics(ev, res),
    ])


def write_bandai_cards(subjects: dict, corpus: dict, pairs: list[tuple[str, str]], *, logs: Path) -> list[Path]:
    """The model card of every retrained model of ``pairs`` (:func:`cmd_card` on its rows of the corpus test
    evaluation, then both per-action tables against its shipped twin). The training command is the one
    scripts/train_shipped.sh --bandai logged to ``logs/NAME.command``; a mixture's is its make_mixture.py line."""
    from motion2video.data.licences import CARD_BEGIN, CARD_END

    written = []
    for shipped, name in pairs:
        path = WEIGHTS_DIR / f"{name}.safetensors"
        log = logs / f"{name}.command"
        if log.is_file():
            command = log.read_text().strip().split(": ", 1)[1]
        elif load_model(path).meta.model == "mixture":
            command = BANDAI_MIXTURE_COMMAND
        else:
            raise InputError(f"no training command logged for {name} (scripts/train_shipped.sh --bandai writes it)", log)
        keep = [name] + list(BASELINES)
        ev = {"protocol": {**corpus["protocol"], "windows": sum(
                  v[COUNT_KEY] for v in corpus["per_action"][BASELINE].values())},
              "results": {m: corpus["results"][m] for m in keep}}
        card = WEIGHTS_DIR / f"{name}.md"
        old = card.read_text() if card.is_file() else ""
        # an existing card's "Limits" are the author's: kept, before the data licence section, for them to revise
        limits = ""
        if "\n## Limits\n" in old:
            limits = old.split("\n## Limits\n", 1)[1].split(CARD_BEGIN, 1)[0].strip("\n")
        if command == BANDAI_MIXTURE_COMMAND:
            card.write_text(_bandai_mixture_card(path, ev, command))
        else:
            with tempfile.TemporaryDirectory() as tmp:
                ev_path = Path(tmp) / "eval.json"
                ev_path.write_text(json.dumps(ev))
                cmd_card(argparse.Namespace(checkpoint=str(path), eval=str(ev_path), command=command, out=str(card)))
        s_names, s_rows = bandai_subject_rows(subjects, [shipped, name])
        c_names, c_rows = bandai_corpus_rows(corpus, [shipped, name])
        extra = [
            "Those are the corpus's held-out test windows (whole CMU subjects). Per action, best-of-"
            f"{corpus['protocol']['samples']} ADE / FDE as a ratio to zero-velocity, `{shipped}` (trained without "
            f"Bandai-Namco) → `{name}`, on the same windows (`python scripts/make_results.py bandai`, "
            "docs/results.md):",
            "",
            _bandai_table(c_names, c_rows, [(shipped, name)]),
            "",
            f"The subject split (`evaluate --split subjects` on `../shared/data/mocap` + `../shared/data/bandai`, "
            f"stride {subjects['protocol']['stride']}; it trained on neither the corpus's test subjects nor "
            "Bandai-Namco's groups 1B and 2C):",
            "",
            _bandai_table(s_names, s_rows, [(shipped, name)]),
            "",
        ]
        tail = "\n".join(extra) + (f"\n## Limits\n\n{limits}\n\n" if limits else "")
        text = card.read_text()
        if CARD_BEGIN in text:  # the tables and the limits before the data licence (scripts/shipped_licences.py's)
            text = text.replace(CARD_BEGIN, tail + CARD_BEGIN, 1)
        else:
            text = text.rstrip("\n") + "\n\n" + tail + f"{CARD_BEGIN}\n{CARD_END}\n"
        card.write_text(text)
        written.append(card)
    return written


def bandai_evaluate(models: list[str], *, mocap: str, bandai: str, samples: int, stride: int, subject_stride: int,
                    windows_from: str = "mixture-periodic") -> dict:
    """Both evaluations of ``models`` (and the baselines): the subject split of ``mocap`` + ``bandai`` and the
    corpus's test split of ``mocap``, on the windows ``windows_from``'s data settings and recorded split give
    (:func:`motion2video.evaluation.forecasting.subject_windows`), so that models scored in separate runs are scored
    on the same windows. Returns ``{"subjects": evaluate's JSON with its "subjects" record, "corpus": ...}``."""
    from motion2video.evaluation.forecasting import subject_split_tables, subject_windows

    ref = load_model(windows_from)
    cfg = ref.data_config
    bundles = [load_model(m) for m in models]
    protocol = EvalProtocol(samples=samples, stride=subject_stride, split="subjects", seed=0)
    # the first bundle carries the statistics the windows were normalised with
    scored = [baseline_bundle(n, cfg, stats=ref.stats) for n in BASELINES[:1]] + bundles + [
        baseline_bundle(n, cfg, stats=ref.stats) for n in BASELINES[1:]]
    _, windows, train_actions = subject_windows((mocap, bandai), cfg, [ref] + bundles, stride=subject_stride,
                                                character=None)
    result = evaluate_bundles(scored, windows, protocol=protocol)
    subjects = {**result.to_json(), "subjects": subject_split_tables(result, bundles, train_actions).json}
    print(f"subject split: {len(windows)} windows", flush=True)
    dataset = build_dataset(mocap, cfg, split=ref.meta.split, stats=ref.stats)
    protocol = dataclasses.replace(protocol, stride=stride, split="test")
    corpus = evaluate_bundles(scored, dataset.windows("test", stride=stride), protocol=protocol).to_json()
    return {"subjects": subjects, "corpus": corpus}


def merge_bandai(parts: list[dict]) -> dict:
    """One record of several :func:`bandai_evaluate` records of other models on the same windows."""
    out = json.loads(json.dumps(parts[0]))
    for part in parts[1:]:
        for split in ("subjects", "corpus"):
            if out[split]["protocol"]["clips"] != part[split]["protocol"]["clips"]:
                raise InputError(f"the {split} evaluations were run on other windows: evaluate them together")
            for key in ("results", "per_action", "macro", "ade_per_frame"):
                out[split][key].update(part[split][key])
        for key in ("report", "trained_on_bandai"):
            out["subjects"]["subjects"][key].update(part["subjects"]["subjects"][key])
    return out


def bandai_main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="make_results.py bandai", description=BANDAI_DOC,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--pair", action="append", default=[], metavar="SHIPPED=RETRAINED",
                   help="two models side by side (repeatable; default: mixture-periodic and its parts with their "
                        "-bandai twins); the first pair's are checked against the targets")
    p.add_argument("--mocap", default=str(DEFAULT_MOCAP))
    p.add_argument("--bandai", default=str(Path(DEFAULT_MOCAP).parent / "bandai"))
    p.add_argument("--samples", type=int, default=50)
    p.add_argument("--stride", type=int, default=16, help="frames between the corpus's test windows (default 16)")
    p.add_argument("--subject-stride", type=int, default=128,
                   help="frames between the subject split's windows (default 128, as in its section above)")
    p.add_argument("--doc", default=str(ROOT / "docs" / "results_bandai.md"))
    p.add_argument("--json", default=str(ROOT / "out" / "results_bandai.json"))
    p.add_argument("--side", choices=("shipped", "retrained"), default=None,
                   help="evaluate one side of the pairs only, into --json with .SIDE before .json (nothing else "
                        "written); --merge joins the two")
    p.add_argument("--merge", action="store_true",
                   help="join the two --side files of --json instead of evaluating, then write as usual")
    p.add_argument("--cards", action="store_true",
                   help="also write the retrained models' cards (motion2video/weights/NAME.md; then run "
                        "scripts/shipped_licences.py for their data licence sections)")
    p.add_argument("--logs", default=str(ROOT / "out" / "train_bandai"),
                   help="where scripts/train_shipped.sh --bandai logged the training commands (for --cards)")
    args = p.parse_args(argv)
    pairs = [tuple(x.split("=", 1)) for x in args.pair] or [tuple(x) for x in BANDAI_PAIRS]
    if any(len(x) != 2 or not all(x) for x in pairs):
        raise InputError(f"--pair takes SHIPPED=RETRAINED, got {args.pair!r}")
    json_path = Path(args.json)
    side_path = {side: json_path.with_suffix(f".{side}.json") for side in ("shipped", "retrained")}
    kw = dict(mocap=args.mocap, bandai=args.bandai, samples=args.samples, stride=args.stride,
              subject_stride=args.subject_stride, windows_from=pairs[0][0])
    t0 = time.time()
    if args.side is not None:
        models = [pair[0 if args.side == "shipped" else 1] for pair in pairs]
        record = {**bandai_evaluate(models, **kw), "minutes": (time.time() - t0) / 60}
        write_json(side_path[args.side], record)
        print(f"wrote {side_path[args.side]} ({record['minutes']:.1f} min)")
        return 0
    if args.merge:
        parts = [json.loads(side_path[s].read_text()) for s in ("shipped", "retrained")]
        record = merge_bandai(parts)
        minutes = sum(part["minutes"] for part in parts)
    else:
        record = bandai_evaluate([m for pair in pairs for m in pair], **kw)
        minutes = (time.time() - t0) / 60
    write_json(json_path, {**record, "pairs": pairs, "minutes": minutes})
    subjects, corpus = record["subjects"], record["corpus"]
    if args.cards:
        for card in write_bandai_cards(subjects, corpus, pairs, logs=Path(args.logs)):
            print(f"wrote {card}")
    asked = [a for a in (sys.argv[2:] if argv is None else argv) if a not in ("--cards", "--merge")]
    command = shlex.join(["python", "scripts/make_results.py", "bandai", *asked])
    section = bandai_section(subjects, corpus, pairs, command=command, minutes=minutes)
    write_section(args.doc, BANDAI_BEGIN, BANDAI_END, section)
    print(section)
    print(f"wrote {args.doc} and {json_path} ({minutes:.1f} min)")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# transfer-unseen: behaviour transfer on clips the shipped behaviour model never saw

TRANSFER_UNSEEN_DOC = """Behaviour transfer on clips the shipped ``behavior`` model never saw: CMU jumps and leg lifts of the corpus's
test subjects and Bandai-Namco waves, a bow and a punch (a source no shipped model trained on), each re-enacted
from walking postures of OTHER test subjects, scored by the root-relative signatures
(``motion2video.evaluation.signatures``) as ratios of the source's.

Two ways, the same source window, target posture, z and step count (300, ``--adapt-steps``' default):

- ``before``: the decoder fitted to the source from the source's OWN start posture, then run from the target's
  (what ``transfer`` did before), the root path shifted by the difference of the start heights;
- ``after``: ``motion2video transfer`` now (``stages.latents.reenact_source``): the decoder fitted to the source
  retargeted onto the target's posture and bones, run from the target's posture along the goal's root path.

Writes a markdown table (per clip: the median over its targets), the macro over clips, the raw numbers as JSON,
and a contact sheet PNG (source | before | after, every 8th frame) of chosen pairs drawn with the project's mesh
renderer.

    python scripts/make_results.py transfer-unseen --json out/transfer_unseen.json --sheet out/transfer_unseen.png

About 25 minutes on a loaded 2-core machine (two fits per pair). ``--held-out-benchmark`` prints the known-answer
transfer benchmark's held-out rows instead (``evaluation.transfer_benchmark``, one fit per case and target).
"""

UNSEEN_MOCAP = ROOT / ".." / "shared" / "data" / "mocap"
UNSEEN_BANDAI = ROOT / ".." / "shared" / "data" / "bandai" / "bvh"
UNSEEN_HORIZON = 48
UNSEEN_FPS = 25.0
UNSEEN_SIGNATURES = ("leg_extension", "arm_swing", "knee_bend", "ankle_lift")

# (label, file, subject, start at 25 fps or None: the window with the largest summed root-relative signatures of
# the SOURCE, stride 4). CMU: the corpus's test subjects (docs/data.md); Bandai: no shipped model trained on it.
UNSEEN_SOURCES = (
    ("jump", UNSEEN_MOCAP / "cmu/02_04.bvh", "cmu-02", 0),
    ("hop", UNSEEN_MOCAP / "cmu/131_03.bvh", "cmu-131", 124),
    ("leg lift (dance)", UNSEEN_MOCAP / "cmu/05_14.bvh", "cmu-05", 64),
    ("leg lift (dance)", UNSEEN_MOCAP / "cmu/05_15.bvh", "cmu-05", None),
    ("wave (Bandai 2C)", UNSEEN_BANDAI / "dataset-2_wave-both-hands_feminine_001.bvh.xz", "bandai-2C", None),
    ("bow (Bandai 1B)", UNSEEN_BANDAI / "dataset-1_bow_active_001.bvh.xz", "bandai-1B", None),
    ("punch (Bandai 1A)", UNSEEN_BANDAI / "dataset-1_punch_normal_001.bvh.xz", "bandai-1A", None),
)
# Walking postures (file, frame at 25 fps, subject); every source uses the first two of other subjects.
UNSEEN_TARGETS = (
    (UNSEEN_MOCAP / "cmu/07_03.bvh", 30, "cmu-07"),
    (UNSEEN_MOCAP / "cmu/05_01.bvh", 42, "cmu-05"),
    (UNSEEN_MOCAP / "cmu/02_02.bvh", 42, "cmu-02"),
)
UNSEEN_SHEET = (("jump", "cmu/07_03.bvh"), ("wave (Bandai 2C)", "cmu/07_03.bvh"), ("punch (Bandai 1A)", "cmu/05_01.bvh"))


def _unseen_best_window(clip: np.ndarray) -> int:
    """Start (25 fps) of the 1 + UNSEEN_HORIZON window with the largest summed root-relative signatures."""
    starts = range(0, clip.shape[0] - UNSEEN_HORIZON - 1, 4)
    return max(starts, key=lambda s: sum(S.signature(n, clip[s:s + 1 + UNSEEN_HORIZON], UNSEEN_FPS) for n in UNSEEN_SIGNATURES))


def _unseen_fitted_to_own_start(bundle, source: np.ndarray, start: np.ndarray) -> np.ndarray:
    """The previous re-enactment: the decoder fitted to the source from its own start, run from ``start``."""
    model = behavior_model(bundle)
    src, _ = encode_sequences(bundle, source[None])
    tgt, frame = encode_sequences(bundle, start[None, None])
    z = behavior_latents(model, src)
    fitted = adapt_to_source(model, src, z, steps=ADAPT_STEPS)
    gen = reenact(fitted, z, tgt[:, 0], horizon=UNSEEN_HORIZON, root=behavior_root(fitted, src, tgt[:, 0]))
    seq = np.concatenate([tgt, gen], axis=1)
    return rigid_bones("body3d", decode_sequences(bundle, seq[:, None], frame)[0])[0]


def _unseen_ratios(source: np.ndarray, made: np.ndarray) -> dict[str, float]:
    out = {}
    for name in UNSEEN_SIGNATURES:
        src = S.signature(name, source, UNSEEN_FPS)
        out[name] = S.signature(name, made, UNSEEN_FPS) / src if src >= MIN_RELATIVE_AMPLITUDE else float("nan")
    return out


def _unseen_fmt(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{x:.2f}"


def transfer_unseen_main(argv: list[str]) -> None:
    p = argparse.ArgumentParser(description=TRANSFER_UNSEEN_DOC.split("\n\n")[0])
    p.add_argument("--json", type=Path, default=None)
    p.add_argument("--sheet", type=Path, default=None, help="contact sheet PNG of the pairs in UNSEEN_SHEET")
    p.add_argument("--held-out-benchmark", action="store_true",
                   help="instead: the known-answer transfer benchmark's held-out cases (transfer rows, medians)")
    args = p.parse_args(argv)
    torch.set_num_threads(1)
    bundle = load_model("behavior")
    if args.held_out_benchmark:
        _unseen_held_out_benchmark(bundle)
        return
    rows, pairs, sheet = [], [], []
    for label, path, subject, start in UNSEEN_SOURCES:
        clip = load_clip(bundle, path).data
        start = _unseen_best_window(clip) if start is None else start
        source = clip[start:start + 1 + UNSEEN_HORIZON]
        targets = [t for t in UNSEEN_TARGETS if t[2] != subject][:2]
        per = {"before": [], "after": []}
        for tpath, tframe, _ in targets:
            posture = load_clip(bundle, tpath).data[tframe]
            t0 = time.time()
            before = _unseen_fitted_to_own_start(bundle, source, posture)
            _, after, shown = reenact_source(bundle, source, posture, adapt_steps=ADAPT_STEPS)
            after = after[0]
            r = {"before": _unseen_ratios(shown, before), "after": _unseen_ratios(shown, after)}
            for k in per:
                per[k].append(r[k])
            pair = {"clip": path.name, "label": label, "start_25fps": int(start), "target": tpath.name,
                    "target_frame_25fps": int(tframe), **r,
                    "source_amplitude_m": {n: S.signature(n, shown, UNSEEN_FPS) for n in UNSEEN_SIGNATURES},
                    "start_error_m": S.posture_error(after[1:2], posture),
                    "bone_spread": S.bone_length_spread(after[1:]), "seconds": time.time() - t0}
            pairs.append(pair)
            print(json.dumps(pair), flush=True)
            if (label, f"cmu/{tpath.name}") in UNSEEN_SHEET:
                sheet.append((label, path, tpath, shown, before, after))
        row = {"clip": path.name, "label": label, "start_25fps": int(start),
               "targets": [t[0].name for t in targets]}
        for k in per:
            row[k] = {n: float(np.nanmedian([d[n] for d in per[k]])) if any(np.isfinite(d[n]) for d in per[k])
                      else float("nan") for n in UNSEEN_SIGNATURES}
        rows.append(row)
    macro = {k: {n: float(np.nanmean([r[k][n] for r in rows])) for n in UNSEEN_SIGNATURES} for k in ("before", "after")}
    head = "| clip | " + " | ".join(f"{n.replace('_', ' ')} before / after" for n in UNSEEN_SIGNATURES) + " |"
    lines = [head, "| --- |" + " ---: |" * len(UNSEEN_SIGNATURES)]
    for r in rows:
        lines.append(f"| {r['label']}: `{r['clip']}` from {r['start_25fps']} | "
                     + " | ".join(f"{_unseen_fmt(r['before'][n])} / **{_unseen_fmt(r['after'][n])}**" for n in UNSEEN_SIGNATURES) + " |")
    lines.append("| macro (mean over clips) | " + " | ".join(f"{_unseen_fmt(macro['before'][n])} / **{_unseen_fmt(macro['after'][n])}**"
                                                      for n in UNSEEN_SIGNATURES) + " |")
    print("\n".join(lines))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"rows": rows, "macro": macro, "pairs": pairs}, indent=1, default=float))
    if args.sheet and sheet:
        write_image(args.sheet, _unseen_contact_sheet(sheet))
        print(f"wrote {args.sheet}")


def _unseen_held_out_benchmark(bundle) -> None:
    """Print the held-out rows of :mod:`motion2video.evaluation.transfer_benchmark` for ``transfer`` as it is."""
    from motion2video.evaluation import transfer_benchmark as B

    cases = tuple(c for c in B.CASES if c.split == "held-out")
    for row in B.summarise(B.run_benchmark(str(UNSEEN_MOCAP), transfer=bundle, cases=cases)):
        if row["method"] == "transfer":
            print(f"| {row['behaviour']} | {row['median_ratio']:.2f} | "
                  + " | ".join(_unseen_fmt(row["relative"][n]) for n in UNSEEN_SIGNATURES)
                  + f" | {row['start_error']:.3f} | {_unseen_fmt(row['posture_kept'])} |", flush=True)


def _unseen_contact_sheet(items) -> np.ndarray:
    """One row per pair: the source, then the re-enactment before and after, every 8th frame (mesh style)."""
    from motion2video.formats.video import label as put_label

    picks = np.arange(0, UNSEEN_HORIZON + 1, 8)
    rows = []
    for label, path, tpath, shown, before, after in items:
        cells = []
        for name, made in (("before", before), ("after", after)):
            result = TransferResult(source=shown[picks].astype(np.float32),
                                    reenacted=made[None, picks].astype(np.float32), z=np.zeros((1, 1)), fps=UNSEEN_FPS / 8, layout="body3d", source_name=str(path),
                                    target_name=str(tpath), target_frame=0)
            frames = render_transfer(result, style="mesh", size=160)  # (7, 160, 322, 3): source | re-enactment
            if not cells:
                cells.append(np.concatenate(list(frames[:, :, :160]), axis=1))
            right = np.concatenate(list(frames[:, :, 162:]), axis=1)
            cells.append(put_label(right[None], f"{name}: {label} from {tpath.stem}")[0])
        cells[0] = put_label(cells[0][None], f"source: {path.name.split('.')[0]}")[0]
        rows.append(np.concatenate(cells, axis=0))
    gap = np.full((6, rows[0].shape[1], 3), 255, np.uint8)
    return np.concatenate([x for r in rows for x in (r, gap)][:-1], axis=0)


# ----------------------------------------------------------------------------------------------------------------

COMMANDS = {
    "forecasting": (forecasting_main, FORECASTING_DOC),
    "card": (forecasting_main, "Write a model card for a trained checkpoint (from its `motion2video evaluate --json`)."),
    "corpus": (corpus_main, CORPUS_DOC),
    "known-answer": (known_answer_main, KNOWN_ANSWER_DOC),
    "per-action": (per_action_main, PER_ACTION_DOC),
    "five-minute-models": (five_minute_main, FIVE_MINUTE_DOC),
    "skeleton-figure": (skeleton_figure_main, SKELETON_FIGURE_DOC),
    "frames": (frames_main, FRAMES_DOC),
    "frames-analysis": (frames_analysis_main, FRAMES_ANALYSIS_DOC),
    "frames-real": (frames_real_main, FRAMES_REAL_DOC),
    "transfer": (transfer_main, TRANSFER_DOC),
    "transfer-benchmark": (transfer_benchmark_main, TRANSFER_BENCHMARK_DOC),
    "transfer-unseen": (transfer_unseen_main, TRANSFER_UNSEEN_DOC),
    "face-sheet": (face_sheet_main, FACE_SHEET_DOC),
    "bandai": (bandai_main, BANDAI_DOC),
}


def main(argv: list[str] | None = None) -> int:
    """``make_results.py SUB-COMMAND [options]``: regenerate one table (``SUB-COMMAND --help`` for its options)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] not in COMMANDS:
        asked = argv[:1] in (["-h"], ["--help"])
        lines = [f"  {name:<19} {doc.splitlines()[0]}" for name, (_, doc) in COMMANDS.items()]
        print("usage: make_results.py {" + ",".join(COMMANDS) + "} [options]\n\ntables:\n" + "\n".join(lines),
              file=sys.stdout if asked else sys.stderr)
        return 0 if asked else 2
    run, _ = COMMANDS[argv[0]]
    try:
        # forecasting and card share one parser (card writes what forecasting's evaluation measured)
        return run(argv if run is forecasting_main else argv[1:]) or 0
    except InputError as err:  # e.g. a page without the sub-command's markers: one line, nothing written
        print(f"make_results.py {argv[0]}: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
