"""The ``mixture`` sampler: futures drawn in turn from the shipped DLow samplers, its checkpoint
composed from theirs, and the checks on what may be mixed. Real shipped weights, real CMU walks."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.models.base import build_model
from motion2video.models.checkpoint import compose_mixture, load_model, save_checkpoint
from motion2video.stages.sampling import encode_observation, forecast

REPO = Path(__file__).resolve().parents[1]
WALK = REPO / "demo_inputs" / "cmu_walk.npz"  # CMU 07_04, a slow walk
PARTS = ("mtvae-add-dlow", "mixer-cvae-dlow")


@pytest.fixture(scope="module")
def shipped():
    return load_model("mixture-dlow")


def _walk_features(bundle, start: int = 24) -> torch.Tensor:
    joints = np.load(WALK)["joints"]
    features, _ = encode_observation(joints[start:start + 16], config=bundle.data_config, stats=bundle.stats)
    return torch.as_tensor(features, dtype=torch.float32)


def test_future_k_comes_from_component_k_mod_c(shipped):
    """Futures 0, 2, 4 are mtvae-add-dlow's first three samples, 1, 3 mixer-cvae-dlow's first two, each drawn
    with the one generator in turn (the known answer of the drawing rule)."""
    obs = _walk_features(shipped)
    got = shipped.model.sample(obs, num_samples=5, horizon=48, generator=torch.Generator().manual_seed(3))
    gen = torch.Generator().manual_seed(3)
    first = load_model(PARTS[0]).model.sample(obs, num_samples=3, horizon=48, generator=gen)
    second = load_model(PARTS[1]).model.sample(obs, num_samples=2, horizon=48, generator=gen)
    assert got.shape == (1, 5, 48, 51)
    torch.testing.assert_close(got[:, 0::2], first, rtol=0, atol=0)
    torch.testing.assert_close(got[:, 1::2], second, rtol=0, atol=0)
    assert shipped.model.counts(5) == [3, 2] and shipped.model.counts(50) == [25, 25]
    assert shipped.model.names == list(PARTS)


def test_the_shipped_file_is_the_composition_of_the_shipped_components(shipped, tmp_path):
    """Rebuilt from the two shipped samplers, saved and loaded again, the mixture has the shipped file's weights
    and record: a retrained component without a recomposed mixture fails here."""
    composed = compose_mixture([load_model(n) for n in PARTS])
    path = save_checkpoint(tmp_path / "m.safetensors", model=composed.model, meta=composed.meta)
    again = load_model(path)
    assert again.name == "mixture" and again.kind == "stochastic"
    assert again.meta.split.to_dict() == shipped.meta.split.to_dict()
    ours, theirs = again.model.state_dict(), shipped.model.state_dict()
    assert ours.keys() == theirs.keys()
    assert all(torch.equal(ours[k], theirs[k]) for k in ours)
    assert [c["name"] for c in again.meta.training["composed_from"]] == list(PARTS)


def test_a_walk_keeps_walking_in_some_futures(shipped):
    """The reason for the mixture, on the demo's real CMU walk: mtvae-add-dlow slows every future of it to a
    shuffle (root at most 0.7 of the observed speed), while the mixture's odd futures keep at least 0.55 of it."""
    joints = np.load(WALK)["joints"]

    def speeds(bundle):
        f = forecast(bundle, joints, num_samples=6, start=24, seed=0)
        observed = np.linalg.norm(np.diff(f.observed[:, 0, :2], axis=0), axis=-1).mean()
        return np.linalg.norm(np.diff(f.futures[:, :, 0, :2], axis=1), axis=-1).mean(axis=1) / observed

    mixed, alone = speeds(shipped), speeds(load_model(PARTS[0]))
    assert alone.max() < 0.7, alone
    assert mixed[1::2].min() > 0.55, mixed


def test_what_cannot_be_mixed_is_refused():
    dlow = load_model(PARTS[0])
    with pytest.raises(InputError, match="at least two"):
        compose_mixture([dlow])
    with pytest.raises(InputError, match="windows or feature layout differ"):
        compose_mixture([dlow, load_model("mtvae-add-2d")])
    with pytest.raises(InputError, match="trained stochastic model"):
        compose_mixture([dlow, load_model("mixture-dlow")])
    with pytest.raises(ValueError, match="at least two components"):
        build_model("mixture", {})


def test_the_script_and_train_give_one_line_and_exit_2(tmp_path, capsys):
    out = tmp_path / "m.safetensors"
    run = subprocess.run([sys.executable, str(REPO / "scripts" / "make_mixture.py"), PARTS[0], "mtvae-add-2d",
                          "-o", str(out)], capture_output=True, text=True)
    assert run.returncode == 2 and not out.exists()
    assert len(run.stderr.strip().splitlines()) == 1 and "differ from mtvae-add-dlow" in run.stderr
    assert main(["train", "--model", "mixture", "--data", str(WALK), "-o", str(out), "--steps", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "make_mixture.py" in err[0] and not out.exists()
