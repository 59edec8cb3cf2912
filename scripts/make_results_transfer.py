"""Behaviour transfer (Blattmann et al. 2021, Tables 1 and 3) and MT-VAE analogy.

    .venv/bin/python scripts/make_results_transfer.py                       # ~15 min on 2 CPU cores
    .venv/bin/python scripts/make_results_transfer.py --steps 20 --analogy-steps 20 --out /tmp/r.md  # smoke run

What it does (one torch thread; every number comes from this run):

1. Loads the real mocap (default ``../shared/data/mocap``) with the shipped models' data settings
   (25 fps, 16 observed + 48 future frames, ``split_seed`` 1: held-out test clips).
2. Trains five models the same way (same sizes, steps, batches, seed; the behaviour variants also get their
   normalizing flow fitted), differing only in the objective:
   ``behavior`` (gamma_C = 0.1, KL budget with dual ascent), ``behavior, gamma_C = 0`` (no
   disentanglement), a conditional autoencoder (the behaviour architecture with gamma_KL fixed at 0 and
   gamma_C = 0: no KL term; the posterior mean is used everywhere, so the latent is deterministic at
   evaluation), a plain cVAE (the behaviour architecture with the Eq. 1 ELBO: gamma_KL fixed at 1, no budget,
   gamma_C = 0) and MT-VAE (add), whose transfer is the analogy z = E(obs_src, fut_src), x_R = D(obs_tgt, z).
3. On every held-out window (stride 8), transfers the source's behaviour to the start posture of a window
   of another held-out clip and reports TDE, RE and d_beta at T = 1, 10, 20, 30, 40
   (:func:`motion2video.evaluation.transfer.evaluate_transfer`), and the realism classifier's accuracy for
   reconstructions, transfers, prior samples and flow samples.
4. The known-answer analogy: a small mtvae-add trained on the procedural multimodal benchmark's
   transitions; for several X -> Y and 20 seeds each, the mode classifier's label of D, against a prior
   sample from C (what the model does without the A -> B latent).

Writes ``docs/results_transfer.md`` (``--out``) and the raw numbers as JSON (``--json``).
"""

from __future__ import annotations

import argparse
import json
import platform
import shlex
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]

VARIANTS = (  # (label, registry name, model config on top of SIZES[name])
    ("behavior", "behavior", {"gamma_c": 0.1}),
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
    from motion2video.evaluation.analogy_benchmark import procedural_analogy_case, procedural_transition_dataset
    from motion2video.models.checkpoint import load_model
    from motion2video.data.dataset import decode_samples, encode_windows
    from motion2video.data.multimodal import default_classifier
    from motion2video.models.training import TrainConfig, train_model

    dataset = procedural_transition_dataset(600, seed=1)
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


def _order(scores: dict, key, *, higher_first: bool) -> str:
    items = sorted(scores.items(), key=lambda kv: key(kv[1]), reverse=higher_first)
    sign = " > " if higher_first else " < "
    return sign.join(f"{label} {_fmt(key(s))}" for label, s in items)


def claims(scores: dict) -> list[str]:
    """The paper's Table 1 / 3 statements, checked on these numbers (yes / no, with the numbers)."""
    b, b0 = scores["behavior"], scores["behavior, gamma_C = 0"]
    cae, cvae = scores["cAE (no KL, gamma_C = 0)"], scores["cVAE (Eq. 1 ELBO)"]
    rel = {k: s.d_beta.mean / max(s.d_random.mean, 1e-12) for k, s in scores.items()}
    out = []

    def check(text: str, ok: bool, numbers: str, *, diff: float | None = None, se: float | None = None) -> None:
        noise = ""
        if diff is not None and se is not None and abs(diff) < 2.0 * se:
            noise = f"; the difference {abs(diff):.1f} is within 2 standard errors ({2.0 * se:.1f}): not significant"
        out.append(f"- {text}: **{'yes' if ok else 'no'}** ({numbers}{noise})")

    def se2(a, b, t: int, what: str) -> float:
        return float(np.hypot(getattr(a, what)[t], getattr(b, what)[t]))

    lowest = min(scores, key=lambda k: scores[k].tde[40])
    check("cAE copies the source (its TDE falls with T and is the lowest of all at T = 40)",
          cae.tde[40] < cae.tde[1] and lowest == "cAE (no KL, gamma_C = 0)",
          f"cAE TDE {_fmt(cae.tde[1])} at T = 1 -> {_fmt(cae.tde[40])} at T = 40; lowest at T = 40: {lowest} "
          f"{_fmt(scores[lowest].tde[40])}")
    check("the cVAE's latent collapses (d_beta and d_random near 0: z is ignored)",
          cvae.d_random.mean < 0.1 * b.d_random.mean,
          f"cVAE d_random {cvae.d_random.mean:.3f} vs behavior {b.d_random.mean:.3f}")
    check("disentanglement (gamma_C = 0.1) raises TDE at T = 40 over gamma_C = 0", b.tde[40] > b0.tde[40],
          f"{_fmt(b.tde[40])} vs {_fmt(b0.tde[40])} cm^2", diff=b.tde[40] - b0.tde[40], se=se2(b, b0, 40, "tde_se"))
    check("disentanglement raises the posture-regression error RE (less posture in z) at T = 40",
          b.re[40] > b0.re[40], f"{_fmt(b.re[40])} vs {_fmt(b0.re[40])} cm^2", diff=b.re[40] - b0.re[40],
          se=se2(b, b0, 40, "re_se"))
    check("disentanglement keeps the behaviour closer (smaller relative d_beta) than gamma_C = 0",
          rel["behavior"] < rel["behavior, gamma_C = 0"],
          f"d_beta / d_random {rel['behavior']:.2f} vs {rel['behavior, gamma_C = 0']:.2f}")
    mt = scores["MT-VAE add (analogy)"]
    check("the behaviour model keeps the behaviour closer than MT-VAE's analogy (relative d_beta)",
          rel["behavior"] < rel["MT-VAE add (analogy)"],
          f"{rel['behavior']:.2f} vs {rel['MT-VAE add (analogy)']:.2f}")
    bp, mp = b.realism_poses, mt.realism_poses
    check("flow samples are more realistic than prior samples (lower pose-classifier accuracy)",
          bp.get("flow", 1.0) < bp["prior"], f"behavior: flow {bp.get('flow', float('nan')):.2f} vs prior "
          f"{bp['prior']:.2f}; two-sample test {b.realism.get('flow', float('nan')):.2f} vs {b.realism['prior']:.2f}")
    check("the behaviour model's transfers are more realistic than MT-VAE's (pose classifier)",
          bp["transfer"] < mp["transfer"], f"{bp['transfer']:.2f} vs {mp['transfer']:.2f}; two-sample test "
          f"{b.realism['transfer']:.2f} vs {mt.realism['transfer']:.2f}")
    check("the behaviour model's transfers are more realistic than without disentanglement (pose classifier)",
          bp["transfer"] < b0.realism_poses["transfer"],
          f"{bp['transfer']:.2f} vs {b0.realism_poses['transfer']:.2f}")
    return out


def write_markdown(path: Path, *, scores: dict, trained: dict, analogy: dict, info: dict) -> None:
    from motion2video.evaluation.transfer import TABLE1_TIMESTEPS

    ts = TABLE1_TIMESTEPS
    lines = [
        "## Behaviour transfer and analogy",
        "",
        f"Generated by `{info['command']}` on {info['date']} ({info['machine']}; {info['total_min']:.1f} min for "
        "this run, one torch thread; the per-model training times below are the checkpoints' own records). Every "
        "number below comes from these checkpoints and this evaluation.",
        "",
        "### Setup",
        "",
        f"- Data: the real mocap in `{info['data']}` at 25 fps, windows of 16 observed + 48 future frames, "
        f"`split_seed` 1. Held-out test clips ({len(info['test_clips'])}): {', '.join(info['test_clips'])}; "
        f"{info['test_windows']} test windows (stride {info['stride']}), {info['train_windows']} training "
        f"windows for the RE regressor.",
        f"- Five models trained the same way: {info['steps']} steps, batch {info['batch_size']}, AdamW, seed "
        f"{info['seed']}, hidden 128, latent 32; behaviour variants fit their flow afterwards "
        f"({max(info['steps'] // 2, 10)} steps). Wall time per model: "
        + ", ".join(f"{k} {v:.0f} s" for k, v in info["train_s"].items()) + ".",
        "- cAE = the behaviour architecture with gamma_KL fixed at 0 and gamma_C = 0 (no KL term; the posterior "
        "mean is used at evaluation, so its latent is deterministic there). cVAE = the same architecture with the "
        "plain Eq. 1 ELBO (gamma_KL fixed at 1, no KL budget, gamma_C = 0). MT-VAE transfers by analogy: "
        "z = E(obs_source, future_source), x_R = D(obs_target, z) (posterior means).",
        "- Transfer pairs: each held-out window's behaviour (its last observed frame + 48 future frames) is "
        "re-enacted from the last observed posture of a random window of ANOTHER held-out clip.",
        "- TDE(T): mean squared error per coordinate between re-enactment and source at generated frame T "
        "(root-relative joints, cm^2; large = not copying). RE(T): mean squared error per coordinate of a ridge "
        "regression (closed form, l2 = 1, standardised z) from z(x_beta) to the posture x_beta[T], fitted on the "
        "training windows and scored on the test windows (cm^2; large = little posture in z). d_beta: "
        "||z(x_beta) - z(x_R)|| with x_R re-encoded from its own start; d_random: ||z(x_beta) - z(target's own "
        "behaviour)||, the distance between unrelated behaviours, so d_beta / d_random is comparable across "
        "models whose latent scales differ (< 1: the re-enactment kept the source's behaviour).",
        "- Realism (Table 3): how well the held-out ground-truth futures (pose + root trajectory, 48 frames) are "
        "told from the reconstructions (self), transfers, prior samples (z ~ N(0, I)) and flow samples "
        "(z = T^-1(u)) of the same windows. 'two-sample' = the two-sample test of "
        "`motion2video.evaluation.realism` (a logistic regression on per-window motion features: per joint mean "
        "speed, mean acceleration, positional spread; 5-fold cross-validated over the windows, both futures of a "
        "window in one fold; its control, real against real of two halves of the windows, is about 0.5); "
        "'poses' = a closed-form ridge classifier on the poses every 4th frame (even windows train, odd test). "
        "0.5 = indistinguishable, 1.0 = always told apart; lower is better (the paper reports a score where "
        "higher is better, max 0.5). The two-sample test replaced a ridge classifier on the full sequence "
        "descriptor, which told real motion of different people apart (0.99).",
        "",
        "### Table 1: behaviour transfer on held-out clips",
        "",
        "| model | " + " | ".join(f"RE T={t} | TDE T={t}" for t in ts) + " | d_beta | d_random | d_beta / d_random |",
        "| --- | " + " | ".join("---: | ---:" for _ in ts) + " | ---: | ---: | ---: |",
    ]
    for label, s in scores.items():
        cells = " | ".join(f"{_fmt(s.re[t])} | {_fmt(s.tde[t])}" for t in ts)
        rel = s.d_beta.mean / max(s.d_random.mean, 1e-12)
        lines.append(f"| {label} | {cells} | {s.d_beta.mean:.3f} ± {s.d_beta.std:.3f} | "
                     f"{s.d_random.mean:.3f} | {rel:.2f} |")
    se_t = max(ts)
    lines += ["", f"Standard errors over the {info['test_windows']} windows at T = {se_t}: "
              + "; ".join(f"{label} TDE ± {s.tde_se[se_t]:.0f}, RE ± {s.re_se[se_t]:.0f}"
                          for label, s in scores.items())
              + " (cm^2)."]
    origins = ("self", "transfer", "prior", "flow")
    lines += [
        "",
        "### Table 3: realism classifier accuracy (lower = more realistic, 0.5 = indistinguishable)",
        "",
        "| model | " + " | ".join(f"{o} (two-sample)" for o in origins) + " | " + " | ".join(f"{o} (poses)" for o in origins)
        + " |",
        "| --- |" + " ---: |" * (2 * len(origins)),
    ]
    for label, s in scores.items():
        full = [f"{s.realism[o]:.2f}" if o in s.realism else "-" for o in origins]
        poses = [f"{s.realism_poses[o]:.2f}" if o in s.realism_poses else "-" for o in origins]
        lines.append(f"| {label} | " + " | ".join(full + poses) + " |")
    real_v, real_a = next(iter(scores.values())).motion["real"]
    lines += [
        "",
        "How lively the motion is: mean absolute velocity / acceleration of the features per frame (metres per "
        f"frame, per frame^2). Held-out ground truth: {real_v:.4f} / {real_a:.4f}.",
        "",
        "| model | " + " | ".join(origins) + " |",
        "| --- |" + " ---: |" * len(origins),
    ]
    for label, s in scores.items():
        lines.append(f"| {label} | " + " | ".join(
            f"{s.motion[o][0]:.4f} / {s.motion[o][1]:.4f}" if o in s.motion else "-" for o in origins) + " |")
    lines += [
        "",
        "### What ordering we find",
        "",
        f"- TDE at T = 40 (higher = less copying): {_order(scores, lambda s: s.tde[40], higher_first=True)}.",
        f"- RE at T = 40 (higher = less posture in z): {_order(scores, lambda s: s.re[40], higher_first=True)}.",
        "- d_beta / d_random (lower = behaviour kept): "
        + _order(scores, lambda s: s.d_beta.mean / max(s.d_random.mean, 1e-12), higher_first=False) + ".",
        f"- Realism of transfers, pose classifier (lower = more realistic): "
        f"{_order(scores, lambda s: s.realism_poses['transfer'], higher_first=False)}; the two-sample test: "
        f"{_order(scores, lambda s: s.realism['transfer'], higher_first=False)}.",
        "",
        "The paper's statements, checked on these numbers:",
        "",
        *claims(scores),
        "",
        "The two-sample test's real-vs-real control on these windows: "
        f"{next(iter(scores.values())).realism_control:.2f} (about 0.5 as it must be); an accuracy well above "
        "it says the generated futures move differently from the real futures of the same windows (the "
        "liveliness table says how: speed and acceleration).",
        "",
        "Caveats: the models are small and briefly trained (minutes on 2 CPU cores, a few thousand training "
        "windows of real mocap) against the paper's 1024-unit LSTMs trained for 50 epochs on Human3.6M; the "
        "held-out set is a handful of clips, and the realism classifier is linear with few hundred test "
        "items, so differences of a few hundredths are noise.",
        "",
        "### Known-answer analogy (procedural transitions)",
        "",
        f"A small mtvae-add (hidden {analogy['model']['hidden_dim']}, latent {analogy['model']['latent_dim']}) "
        f"trained {analogy['steps']} steps ({analogy['train_s']:.0f} s) on 600 sequences of the multimodal "
        "benchmark (a context mode, then a future mode from the first future frame). For each X -> Y and "
        f"{analogy['seeds']} seeds: A -> B is a clip where X turns into Y (speed 0.85-1.0, height 1.55-1.72 m), C "
        "another instance of X (speed 1.0-1.15, height 1.72-1.9 m); D = decode(C, E(A, B)) is labelled by the "
        "nearest-template mode classifier. 'prior' labels a sample from C with z ~ N(0, I) instead (no A -> B). "
        "`tests/test_analogy.py::test_known_answer_analogy_walk_to_run` asserts the walk -> run row "
        "(Y is the most frequent label of D).",
        "",
        "| X -> Y | D labelled Y | D labels | prior labelled Y | prior labels |",
        "| --- | ---: | --- | ---: | --- |",
    ]
    for r in analogy["rows"]:
        fmt = lambda c: ", ".join(f"{k} {v}" for k, v in sorted(c.items(), key=lambda kv: -kv[1]))  # noqa: E731
        lines.append(f"| {r['x']} -> {r['y']} | {r['analogy_hits']}/{analogy['seeds']} | {fmt(r['analogy'])} | "
                     f"{r['prior_hits']}/{analogy['seeds']} | {fmt(r['prior'])} |")
    lines += [
        "",
        "### Commands",
        "",
        "```",
        "motion2video transfer --model behavior --behavior ../shared/data/mocap/cmu/131_03.bvh \\",
        "    --target ../shared/data/mocap/cmu/01_01.bvh --target-frame 1200 -o out/transfer.mp4",
        "motion2video transfer --model behavior --sample 6 --target ../shared/data/mocap/cmu/08_01.bvh -o out/flow.mp4",
        "motion2video analogy --model mtvae-add ../shared/data/mocap/cmu/131_01.bvh \\",
        "    ../shared/data/mocap/cmu/131_01.bvh ../shared/data/mocap/cmu/01_01.bvh --a-start 400 --c-start 1200 \\",
        "    -o out/analogy.mp4",
        "motion2video analogy --model mtvae-add-face ../shared/data/face/livelinkface/alex_rom_3.csv \\",
        "    ../shared/data/face/livelinkface/alex_rom_3.csv ../shared/data/face/llv/dao.csv --a-start 2195 \\",
        "    -o out/face_start_smiling.mp4   # A -> B: the capture starts smiling; C: another face and head pose",
        "```",
        "",
    ]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--steps", type=int, default=1200, help="training steps per transfer model")
    parser.add_argument("--batch-size", type=int, default=32)
    parser.add_argument("--analogy-steps", type=int, default=500, help="steps of the procedural analogy model")
    parser.add_argument("--seeds", type=int, default=20, help="known-answer seeds per X -> Y")
    parser.add_argument("--stride", type=int, default=8, help="frames between held-out windows")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workdir", default=None, help="keep / reuse the checkpoints here (default: a temp dir)")
    parser.add_argument("--out", default=str(ROOT / "docs" / "results_transfer.md"))
    parser.add_argument("--json", default=None, help="also write the raw numbers here")
    args = parser.parse_args(argv)

    from motion2video.models.checkpoint import load_model
    from motion2video.data.dataset import DatasetConfig, build_dataset
    from motion2video.evaluation.transfer import evaluate_transfer, transfer_pairs

    torch.set_num_threads(1)
    t_all = time.perf_counter()
    command = "python scripts/make_results_transfer.py " + " ".join(shlex.quote(a) for a in (argv or sys.argv[1:]))
    with tempfile.TemporaryDirectory(prefix="m2v-results-transfer-") as tmp:
        workdir = Path(args.workdir) if args.workdir else Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        dataset = build_dataset(args.data, DatasetConfig(split_seed=1))
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
        "total_min": (time.perf_counter() - t_all) / 60.0, "data": args.data,
        "test_clips": sorted(set(test.clip_names)), "test_windows": len(test), "train_windows": len(train),
        "stride": args.stride, "steps": args.steps, "batch_size": args.batch_size, "seed": args.seed,
        "train_s": {k: v[1] for k, v in trained.items()},
    }
    out = Path(args.out)
    write_markdown(out, scores=scores, trained=trained, analogy=analogy, info=info)
    print(f"wrote {out} in {info['total_min']:.1f} min")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"info": info, "transfer": {k: v.to_json() for k, v in scores.items()},
                                               "analogy": analogy}, indent=1, default=str))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
