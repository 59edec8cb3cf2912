"""Exact resume: a training run killed with SIGKILL after a periodic checkpoint and then resumed ends
with the same weights and the same optimiser state, bit for bit, as the run that was never interrupted (CPU, one
torch thread). The data order is a function of (seed, step) in both training loops, and so is torch's random
state (each step reseeds it), so nothing else needs saving. One test for a motion model (``motion2video train``),
one for the frame generator (``train_frames`` on the toy set, in a child process)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import torch
from safetensors.torch import load_file

REPO = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(REPO), "TQDM_DISABLE": "1", "OMP_NUM_THREADS": "1"}


def _tensors_equal(a: Path, b: Path) -> None:
    ta, tb = load_file(str(a)), load_file(str(b))
    assert sorted(ta) == sorted(tb), (a, b)
    different = [k for k in ta if not torch.equal(ta[k], tb[k])]
    assert not different, f"{len(different)} tensors differ between {a.name} and {b.name}: {different[:3]}"


def _kill_when(proc: subprocess.Popen, ready, timeout: float = 300.0) -> None:
    end = time.monotonic() + timeout
    while not ready():
        if proc.poll() is not None:
            pytest.fail(f"the run finished before it could be killed: {proc.communicate()[1][-2000:]}")
        if time.monotonic() > end:
            proc.kill()
            pytest.fail("no periodic checkpoint appeared")
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL


def _motion_steps_done(last: Path) -> int:
    from motion2video.models.checkpoint import read_meta

    if not last.exists():
        return 0
    try:
        return int(read_meta(last).training["steps"])
    except Exception:  # noqa: BLE001 - not there yet
        return 0


@pytest.mark.slow
def test_motion_model_killed_and_resumed_matches_the_uninterrupted_run(tmp_path, mocap_dir):
    config = ('{"model": {"hidden_dim": 16, "latent_dim": 4}, '
              '"train": {"batch_size": 8, "checkpoint_every": 20, "val_every": 0}}')
    base = [sys.executable, "-m", "motion2video.cli", "train", "--model", "cvae", "--data",
            str(mocap_dir / "cmu"), "--steps", "240", "--config", config, "--no-progress", "--threads", "1"]
    straight = tmp_path / "straight.safetensors"
    subprocess.run(base + ["-o", str(straight)], env=ENV, check=True, capture_output=True, timeout=900)

    killed = tmp_path / "killed.safetensors"
    proc = subprocess.Popen(base + ["-o", str(killed)], env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    _kill_when(proc, lambda: _motion_steps_done(tmp_path / "killed.last.safetensors") >= 60)
    assert not killed.exists()
    stopped_at = _motion_steps_done(tmp_path / "killed.last.safetensors")
    assert 60 <= stopped_at < 240
    subprocess.run(base + ["-o", str(killed), "--resume"], env=ENV, check=True, capture_output=True, timeout=900)

    _tensors_equal(straight, killed)  # weights
    _tensors_equal(tmp_path / "straight.last.optim.safetensors", tmp_path / "killed.last.optim.safetensors")


FRAMES_DRIVER = """
import sys
from motion2video.generator.data import toy_sequences
from motion2video.generator.model import FrameGeneratorConfig
from motion2video.generator.training import TrainFramesConfig, train_frames
import torch
torch.set_num_threads(1)
seqs = toy_sequences("body", num_sequences=6, frames_per_sequence=4, image_size=32)
cfg = TrainFramesConfig(steps=int(sys.argv[2]), batch_size=4, warmup_steps=3, log_every=5, checkpoint_every=5)
model = FrameGeneratorConfig(domain="body", image_size=32, channels=(8, 16, 16), structure_channels=33)
train_frames(seqs, output=sys.argv[1], config=cfg, model_config=model, resume=sys.argv[3] == "resume",
             progress=False)
"""


@pytest.mark.slow
def test_frame_generator_killed_and_resumed_matches_the_uninterrupted_run(tmp_path):
    from motion2video.generator.checkpoint import load_frame_model, state_path

    steps = "150"
    straight, killed = tmp_path / "straight.safetensors", tmp_path / "killed.safetensors"
    subprocess.run([sys.executable, "-c", FRAMES_DRIVER, str(straight), steps, "fresh"], env=ENV, check=True,
                   capture_output=True, timeout=900)

    def steps_done() -> int:
        try:
            return load_frame_model(killed).step if state_path(killed).exists() else 0
        except Exception:  # noqa: BLE001 - being written
            return 0

    proc = subprocess.Popen([sys.executable, "-c", FRAMES_DRIVER, str(killed), steps, "fresh"], env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _kill_when(proc, lambda: steps_done() >= 20)
    assert 20 <= load_frame_model(killed).step < 150
    subprocess.run([sys.executable, "-c", FRAMES_DRIVER, str(killed), steps, "resume"], env=ENV, check=True,
                   capture_output=True, timeout=900)

    assert load_frame_model(killed).step == 150
    _tensors_equal(straight, killed)  # weights
    _tensors_equal(state_path(straight), state_path(killed))  # optimiser state
