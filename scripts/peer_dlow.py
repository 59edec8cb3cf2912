"""Train DLow's own code (github.com/Khrylx/DLow) on the project's training windows and score it with the
project's metric on the project's test windows, beside the project's samplers.

    python scripts/peer_dlow.py --dlow /path/to/DLow --out out/peer_dlow              # train VAE, DLow, score
    python scripts/peer_dlow.py --dlow /path/to/DLow --out out/peer_dlow --stage score  # score the last checkpoints
    python scripts/peer_dlow.py --dlow /path/to/DLow --out out/peer_dlow_subjects --split subjects \
        --model mtvae-add-dlow-bandai --data ../shared/data/mocap --data ../shared/data/bandai --stride 128 \
        --train-stride 4 --compare mixture-periodic mixture-periodic-bandai   # the subject split

Nothing of DLow is part of this repository: the script re-runs itself with the ``--dlow`` checkout on PYTHONPATH
and imports DLow's modules from there. The training
steps are DLow's own ``train`` functions of ``motion_pred/exp_vae.py`` and ``motion_pred/exp_dlow.py`` (losses,
optimiser, learning-rate schedule, batch sizes, samples per epoch), run on its ``VAE`` and ``NFDiag`` models with
the settings of its ``motion_pred/cfg/h36m_nsamp50.yml``; the futures are drawn by its ``eval.get_prediction``
(50 affine maps of one noise through the VAE decoder). What differs from that recipe:

- the windows: the reference model's training windows (every start, 16 observed + 48 future frames at 25 fps,
  canonical heading, the 16 root-relative joints in metres), where DLow reads Human3.6M at 50 fps with 25 + 100
  frames; t_his / t_pred follow;
- the epoch counts (``--vae-epochs`` / ``--dlow-epochs``, for CPU time), the constant-rate epochs scaled with them
  (DLow: 100 of 500);
- the dataset class passed in draws a uniformly random training window (the project's sampler draws windows
  in proportion to each clip's count too), where DLow's draws a subject, one of its sequences and a start.

Scoring: best of 50 ADE / FDE, MMADE / MMFDE and APD per window, per action and macro over actions
(:mod:`motion2video.evaluation.forecasting`), on the windows ``motion2video evaluate`` scores the reference model
on, beside the ``--compare`` models and zero-velocity. DLow's futures are scored as its sampler draws them (the
project's learned models continue the observed motion, as ``evaluate`` scores them).
Writes ``OUT/eval.json`` (the ``evaluate`` JSON with the DLow row) and prints the per-action and macro tables.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pickle
import sys
import time
from pathlib import Path

import numpy as np
import torch

from motion2video.core.atomic import write_json
from motion2video.core.errors import InputError
from motion2video.data.dataset import WindowSet, build_dataset
from motion2video.data.windows import FeatureLayout, metric_vectors
from motion2video.evaluation.forecasting import (EvalProtocol, dlow_metrics_per_window, evaluate_bundles, rows_table,
                                                 subject_split_tables, subject_windows)
from motion2video.evaluation.per_action import group_by_action, macro_average, per_action_means
from motion2video.models.baselines import BASELINES
from motion2video.models.checkpoint import baseline_bundle, load_model

CFG_ID = "m2v_nsamp50"
PEER = "dlow-peer"  # the method name of DLow's own code in the tables and JSON

RECIPE = Path("motion_pred") / "cfg" / "h36m_nsamp50.yml"  # DLow's Human3.6M recipe, read from the checkout


def dlow_config(recipe: dict, *, t_his: int, t_pred: int, vae_epochs: int, dlow_epochs: int, save_every: int) -> dict:
    """DLow's settings ``recipe`` (its h36m_nsamp50.yml) for windows of t_his + t_pred frames and the given epoch
    counts, the constant-rate epochs keeping the recipe's share (100 of 500)."""
    if min(t_his, t_pred, vae_epochs, dlow_epochs, save_every) < 1:
        raise InputError("t_his, t_pred, the epoch counts and the save interval must be at least 1")
    cfg = dict(recipe, t_his=int(t_his), t_pred=int(t_pred), save_model_interval=int(save_every))
    for part, epochs in (("vae", vae_epochs), ("dlow", dlow_epochs)):
        share = recipe[f"num_{part}_epoch_fix"] / recipe[f"num_{part}_epoch"]
        cfg[f"num_{part}_epoch"] = int(epochs)
        cfg[f"num_{part}_epoch_fix"] = int(round(share * epochs))
    return cfg


def dlow_sequences(raw: np.ndarray, layout: FeatureLayout) -> np.ndarray:
    """Un-normalised body3d windows raw (N, L, F) as DLow's dataset arrays: (N, L, J + 1, 3) float64, joint 0
    the root (zeros: DLow drops it) and joints 1..J the root-relative joints of the metric vectors."""
    if layout.kind != "body3d":
        raise InputError(f"DLow forecasts 3D body joints, not the {layout.kind} layout")
    vec = metric_vectors(raw, layout)
    joints = vec.reshape(*vec.shape[:2], -1, 3)
    return np.concatenate([np.zeros_like(joints[:, :, :1]), joints], axis=2)


def predictions_to_metric(pred: np.ndarray, num_windows: int, nk: int) -> np.ndarray:
    """DLow's sampler output (num_windows, nk, T, 3 J) checked and returned as float64 metric vectors."""
    pred = np.asarray(pred, np.float64)
    if pred.shape[:2] != (num_windows, nk):
        raise ValueError(f"expected ({num_windows}, {nk}, T, D) futures, got {pred.shape}")
    return pred


def check_checkout(path: Path) -> Path:
    """The resolved DLow checkout, or InputError naming the folder."""
    if not all((path / part).is_file() for part in ("motion_pred/exp_dlow.py", "models/motion_pred.py", RECIPE)):
        raise InputError(f"not a DLow checkout (no motion_pred/exp_dlow.py, models/motion_pred.py or {RECIPE})", path)
    return path.resolve()


def rerun_with_checkout_on_path(path: Path, argv: list[str]) -> None:
    """Re-run this script with the DLow checkout first on PYTHONPATH unless it is there already (DLow's modules
    import each other from its root: ``from utils import *``, ``from models.mlp import MLP``)."""
    entries = [e for e in os.environ.get("PYTHONPATH", "").split(os.pathsep) if e]
    if str(path) in entries:
        return
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(path), *entries]))
    sys.stdout.flush()
    os.execve(sys.executable, [sys.executable, str(Path(__file__).resolve()), *argv], env)


def import_dlow():
    """DLow's modules, from the checkout on PYTHONPATH: (Config, Dataset, models module, exp_vae, exp_dlow,
    eval)."""
    config = importlib.import_module("motion_pred.utils.config")
    dataset = importlib.import_module("motion_pred.utils.dataset")
    models = importlib.import_module("models.motion_pred")
    exp_vae = importlib.import_module("motion_pred.exp_vae")
    exp_dlow = importlib.import_module("motion_pred.exp_dlow")
    evaluation = importlib.import_module("motion_pred.eval")
    return config.Config, dataset.Dataset, models, exp_vae, exp_dlow, evaluation


def window_dataset_class(base):
    """A subclass of DLow's Dataset over fixed windows (DLow's sampling_generator and normalize_data kept)."""

    class WindowDataset(base):
        def __init__(self, sequences: np.ndarray, t_his: int, t_pred: int):
            self.sequences = sequences
            super().__init__("train", t_his, t_pred)

        def prepare_data(self):
            self.kept_joints = np.arange(self.sequences.shape[2])
            self.subjects = ["train"]
            self.data = {"train": {"windows": self.sequences.reshape(-1, *self.sequences.shape[2:])}}

        def sample(self):
            i = np.random.randint(len(self.sequences))
            return self.sequences[i][None, ...]

    return WindowDataset


class Logger:
    """The logger DLow's train functions write their epoch lines to: printed and appended to a file."""

    def __init__(self, path: Path):
        self.path = path

    def info(self, text: str):
        print(text, flush=True)
        with open(self.path, "a") as f:
            f.write(text + "\n")


def train_dlow(args, train_seq: np.ndarray, dlow_mods) -> None:
    """DLow's two training stages (exp_vae.py's then exp_dlow.py's main, their train functions as they are)."""
    Config, Dataset, models, exp_vae, exp_dlow, _ = dlow_mods
    from torch import optim
    from torch.utils.tensorboard import SummaryWriter
    cfg = Config(CFG_ID)
    dtype = torch.float64
    torch.set_default_dtype(dtype)
    device = torch.device("cpu")
    dataset = window_dataset_class(Dataset)(train_seq, cfg.t_his, cfg.t_pred)
    logger = Logger(Path(cfg.log_dir) / "log.txt")
    tb = SummaryWriter(cfg.tb_dir)
    sched = importlib.import_module("utils.torch").get_scheduler
    if args.stage in ("all", "vae"):
        np.random.seed(args.seed)
        torch.manual_seed(args.seed)
        model = models.get_vae_model(cfg, dataset.traj_dim)
        optimizer = optim.Adam(model.parameters(), lr=cfg.vae_lr)
        scheduler = sched(optimizer, policy="lambda", nepoch_fix=cfg.num_vae_epoch_fix, nepoch=cfg.num_vae_epoch)
        for name, value in dict(cfg=cfg, dataset=dataset, model=model, optimizer=optimizer, scheduler=scheduler,
                                t_his=cfg.t_his, t_pred=cfg.t_pred, nz=cfg.nz, device=device, dtype=dtype,
                                logger=logger, tb_logger=tb).items():
            setattr(exp_vae, name, value)
        model.train()
        for i in range(cfg.num_vae_epoch):
            exp_vae.train(i)
            if (i + 1) % cfg.save_model_interval == 0 or i + 1 == cfg.num_vae_epoch:
                pickle.dump({"model_dict": model.state_dict(), "meta": {"std": None, "mean": None}},
                            open(cfg.vae_model_path % (i + 1), "wb"))
    if args.stage in ("all", "dlow"):
        np.random.seed(args.seed)
        torch.manual_seed(args.seed)
        vae = models.get_vae_model(cfg, dataset.traj_dim)
        vae.load_state_dict(pickle.load(open(cfg.vae_model_path % cfg.num_vae_epoch, "rb"))["model_dict"])
        dlow = models.get_dlow_model(cfg, dataset.traj_dim)
        optimizer = optim.Adam(dlow.parameters(), lr=cfg.dlow_lr)
        scheduler = sched(optimizer, policy="lambda", nepoch_fix=cfg.num_dlow_epoch_fix, nepoch=cfg.num_dlow_epoch)
        for name, value in dict(cfg=cfg, dataset=dataset, vae=vae, dlow=dlow, optimizer=optimizer,
                                scheduler=scheduler, t_his=cfg.t_his, t_pred=cfg.t_pred, nz=cfg.nz, nk=cfg.nk,
                                device=device, dtype=dtype, logger=logger, tb_logger=tb).items():
            setattr(exp_dlow, name, value)
        vae.eval()
        dlow.train()
        for i in range(cfg.num_dlow_epoch):
            exp_dlow.train(i)
            if (i + 1) % cfg.save_model_interval == 0 or i + 1 == cfg.num_dlow_epoch:
                pickle.dump({"model_dict": dlow.state_dict(), "meta": {"std": None, "mean": None}},
                            open(cfg.dlow_model_path % (i + 1), "wb"))
    tb.close()


def last_checkpoint(pattern: str) -> tuple[Path, int]:
    """The checkpoint of pattern (``.../dlow_%04d.p``) with the most epochs, and that count."""
    folder = Path(pattern).parent
    stem = Path(pattern).name.split("%")[0]
    found = sorted(folder.glob(f"{stem}*.p"))
    if not found:
        raise InputError(f"no {stem}*.p checkpoint to score: train first", folder)
    return found[-1], int(found[-1].stem.split("_")[-1])


@torch.no_grad()
def sample_dlow(args, windows: WindowSet, seq: np.ndarray, dlow_mods) -> tuple[np.ndarray, dict]:
    """50 futures per window from DLow's eval.get_prediction: (N, nk, T_pred, 3 J) metres."""
    Config, _, models, _, _, evaluation = dlow_mods
    cfg = Config(CFG_ID)
    torch.set_default_dtype(torch.float64)
    vae_path, vae_epochs = last_checkpoint(cfg.vae_model_path)
    dlow_path, dlow_epochs = last_checkpoint(cfg.dlow_model_path)
    traj_dim = (seq.shape[2] - 1) * 3
    nets = {"vae": models.get_vae_model(cfg, traj_dim), "dlow": models.get_dlow_model(cfg, traj_dim)}
    for name, path in (("vae", vae_path), ("dlow", dlow_path)):
        nets[name].load_state_dict(pickle.load(open(path, "rb"))["model_dict"])
        nets[name].eval()
    for name, value in dict(models=nets, device=torch.device("cpu"), dtype=torch.float64, t_his=cfg.t_his,
                            nk=cfg.nk).items():
        setattr(evaluation, name, value)
    torch.manual_seed(args.seed)
    out = []
    for i in range(0, len(seq), args.batch_size):
        out.append(evaluation.get_prediction(seq[i:i + args.batch_size], "dlow", cfg.nk, concat_hist=False))
    pred = predictions_to_metric(np.concatenate(out), len(windows), cfg.nk)
    return pred, {"vae_checkpoint": str(vae_path), "vae_epochs": vae_epochs, "dlow_checkpoint": str(dlow_path),
                  "dlow_epochs": dlow_epochs}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dlow", required=True, type=Path, help="a checkout of github.com/Khrylx/DLow")
    p.add_argument("--out", type=Path, default=Path("out/peer_dlow"), help="DLow's results, logs and eval.json")
    p.add_argument("--model", default="mtvae-add-dlow",
                   help="reference model: its data settings, split and normalisation give the windows")
    p.add_argument("--data", action="append", default=None,
                   help="BVH folder; repeat to join folders (--split subjects: ../shared/data/mocap and "
                   "../shared/data/bandai); default ../shared/data/mocap")
    p.add_argument("--compare", nargs="*", default=["mtvae-add-dlow", "mixture-periodic"],
                   help="shipped models scored beside DLow on the same windows (zero-velocity always)")
    p.add_argument("--stage", choices=("all", "vae", "dlow", "score"), default="all")
    p.add_argument("--vae-epochs", type=int, default=500)
    p.add_argument("--dlow-epochs", type=int, default=500)
    p.add_argument("--save-every", type=int, default=5, help="epochs between DLow checkpoints")
    p.add_argument("--train-stride", type=int, default=1, help="frames between exported training windows")
    p.add_argument("--split", default="test", choices=("test", "val", "subjects"),
                   help="test / val: the reference model's split; subjects: the subject split of evaluate "
                   "--split subjects (trained on its training part, scored on its held-out performers)")
    p.add_argument("--stride", type=int, default=16)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--batch-size", type=int, default=32)
    argv = sys.argv[1:] if argv is None else list(argv)
    args = p.parse_args(argv)
    try:
        args.dlow = check_checkout(args.dlow)
        rerun_with_checkout_on_path(args.dlow, argv)
        return run(args)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


def run(args) -> int:
    t0 = time.time()
    dlow_path = args.dlow
    reference = load_model(args.model)
    cfg = reference.data_config
    if cfg.feature_layout.kind != "body3d":
        raise InputError(f"DLow forecasts 3D body motion, not the {cfg.feature_layout.kind} layout of {args.model}")
    data = args.data or ["../shared/data/mocap"]
    data = data[0] if len(data) == 1 else data
    train_actions = None
    if args.split == "subjects":
        dataset, windows, train_actions = subject_windows(data, cfg, [reference], stride=args.stride, character=None)
    else:
        dataset = build_dataset(data, cfg, split=reference.meta.split, stats=reference.stats)
        windows = dataset.windows(args.split, stride=args.stride)
    out = args.out.resolve()
    (out / "motion_pred" / "cfg").mkdir(parents=True, exist_ok=True)
    import yaml
    recipe = yaml.safe_load((dlow_path / RECIPE).read_text())
    cfg_dict = dlow_config(recipe, t_his=cfg.observed, t_pred=cfg.future, vae_epochs=args.vae_epochs,
                           dlow_epochs=args.dlow_epochs, save_every=args.save_every)
    (out / "motion_pred" / "cfg" / f"{CFG_ID}.yml").write_text(yaml.safe_dump(cfg_dict, sort_keys=False))
    dlow_mods = import_dlow()
    os.chdir(out)  # DLow's Config reads motion_pred/cfg/<id>.yml and writes results/<id>/ under the working folder
    if args.stage != "score":
        train_windows = dataset.windows("train", stride=args.train_stride)
        train_seq = dlow_sequences(train_windows.raw, reference.layout)
        print(f"{len(train_windows)} training windows of {len(set(train_windows.clip_names))} clips, "
              f"{cfg.observed} + {cfg.future} frames at {cfg.fps:g} fps", flush=True)
        train_dlow(args, train_seq, dlow_mods)
        del train_seq
    if args.stage not in ("all", "score"):
        return 0
    test_seq = dlow_sequences(windows.raw, reference.layout)
    pred, info = sample_dlow(args, windows, test_seq, dlow_mods)
    torch.set_default_dtype(torch.float32)  # DLow runs in float64; the project's models are built in float32
    protocol = EvalProtocol(samples=cfg_dict["nk"], stride=args.stride, split=args.split, seed=args.seed)
    compare = [load_model(name) for name in args.compare or []]
    bundles = compare + [baseline_bundle(name, cfg, stats=reference.stats) for name in BASELINES]
    result = evaluate_bundles(bundles, windows, protocol=protocol)
    obs = windows.observed
    gt = metric_vectors(windows.raw[:, obs:], reference.layout)
    last = metric_vectors(windows.raw[:, obs - 1], reference.layout)
    per_window = dlow_metrics_per_window(pred, gt, last, threshold=protocol.threshold(reference.layout))
    by_action = per_action_means(per_window, group_by_action(windows.labels))
    result.results[PEER] = {k: float(v.mean()) for k, v in per_window.items()}
    result.per_action[PEER] = by_action
    result.macro[PEER] = macro_average(by_action)
    result.protocol.update({"peer": {"code": "github.com/Khrylx/DLow", "checkout": str(dlow_path), **info,
                                     "config": cfg_dict, "train_stride": args.train_stride,
                                     "futures": "as DLow's sampler draws them (not continued)"},
                            "reference_model": args.model, "data": str(data)})
    record = result.to_json()
    if train_actions is not None:
        subjects = subject_split_tables(result, compare, train_actions)
        record["subjects"] = subjects.json
        print(rows_table(subjects.rows, ("ade", "fde", "ade_zv", "fde_zv", "apd"), first="row"))
    write_json(out / "eval.json", record)
    print(f"DLow: VAE {info['vae_epochs']} epochs, DLow {info['dlow_epochs']} epochs; "
          f"{len(windows)} {args.split} windows")
    print(result.per_action_table(("ade", "fde", "mmade", "mmfde", "apd")))
    print(result.macro_table(("ade", "fde", "mmade", "mmfde", "apd")))
    print(f"wrote {out / 'eval.json'} ({time.time() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
