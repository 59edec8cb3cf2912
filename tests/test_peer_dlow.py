"""scripts/peer_dlow.py's own parts (DLow's checkout is not needed): the recipe it writes, the windows it hands
to DLow's dataset class, and the refusal of a folder that is not a DLow checkout."""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.data.windows import FeatureLayout, metric_vectors

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


@pytest.fixture()
def peer(monkeypatch):
    monkeypatch.syspath_prepend(str(SCRIPTS))  # as when the script runs: its folder first on the path
    return importlib.import_module("peer_dlow")


# a few settings of DLow's motion_pred/cfg/h36m_nsamp50.yml
RECIPE = {"nz": 128, "t_his": 25, "t_pred": 100, "nk": 50, "num_vae_epoch": 500, "num_vae_epoch_fix": 100,
          "num_dlow_epoch": 500, "num_dlow_epoch_fix": 100, "dlow_specs": {"model_name": "NFDiag"}}


def test_config_keeps_dlows_recipe_and_scales_the_constant_rate_epochs(peer):
    cfg = peer.dlow_config(RECIPE, t_his=16, t_pred=48, vae_epochs=30, dlow_epochs=9, save_every=1)
    changed = {"t_his", "t_pred", "save_model_interval", "num_vae_epoch", "num_vae_epoch_fix", "num_dlow_epoch",
               "num_dlow_epoch_fix"}
    assert {k: v for k, v in cfg.items() if k not in changed} == {
        k: v for k, v in RECIPE.items() if k not in changed}
    assert (cfg["t_his"], cfg["t_pred"], cfg["nk"], cfg["nz"]) == (16, 48, 50, 128)
    assert (cfg["num_vae_epoch"], cfg["num_vae_epoch_fix"]) == (30, 6)  # DLow: 100 of 500 at the full rate
    assert (cfg["num_dlow_epoch"], cfg["num_dlow_epoch_fix"]) == (9, 2)
    full = peer.dlow_config(RECIPE, t_his=25, t_pred=100, vae_epochs=500, dlow_epochs=500, save_every=20)
    assert (full["num_vae_epoch_fix"], full["num_dlow_epoch_fix"]) == (100, 100)
    with pytest.raises(InputError):
        peer.dlow_config(RECIPE, t_his=16, t_pred=48, vae_epochs=0, dlow_epochs=9, save_every=1)


def test_windows_reach_dlow_as_root_relative_joints_with_a_zero_root(peer, mocap_dir):
    ds = build_dataset(mocap_dir / "cmu" / "131_02.bvh", DatasetConfig(stride=8), stats=None)
    windows = ds.windows("all")
    layout = FeatureLayout(kind="body3d")
    seq = peer.dlow_sequences(windows.raw, layout)
    n, length = windows.raw.shape[:2]
    assert seq.shape == (n, length, 17, 3) and seq.dtype == np.float64 and n > 10
    assert np.all(seq[:, :, 0] == 0.0)
    # DLow's models read traj[..., 1:, :] flattened: exactly the vectors the project's metric compares
    assert np.array_equal(seq[:, :, 1:].reshape(n, length, -1), metric_vectors(windows.raw, layout))
    with pytest.raises(InputError, match="face"):
        peer.dlow_sequences(np.zeros((1, 4, 58)), FeatureLayout(kind="face"))


def test_a_folder_that_is_not_a_dlow_checkout_is_refused_in_one_line(peer, tmp_path, capsys):
    assert peer.main(["--dlow", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "not a DLow checkout" in err and str(tmp_path) in err
    assert not (tmp_path / "out").exists()
