"""The training loop and checkpoints, with tiny models on a handful of real BVH clips."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import torch
from safetensors.torch import save_file

from motion2video.models import checkpoint as C
from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.core.errors import InputError
from motion2video.models.training import TrainConfig, last_paths, schedule_step, train_model, validation_loss
from motion2video.core.schedule import learning_rate
from tests.conftest import link_clips

CLIPS = ("cmu/131_01.bvh", "cmu/131_02.bvh", "cmu/01_01.bvh", "mass/mass_pirouette.bvh",
         "deepmimic/humanoid3d_spin.bvh")
TINY = {"hidden_dim": 16}


@pytest.fixture(scope="module")
def small_data(tmp_path_factory, mocap_dir):
    """Five real clips (four split groups) linked into a temporary folder (no manifest: header rates)."""
    return link_clips(tmp_path_factory.mktemp("mocap_small"), mocap_dir, CLIPS)


@pytest.fixture(scope="module")
def dataset(small_data):
    return build_dataset(small_data, DatasetConfig(stride=8))


def _quick(**kw) -> TrainConfig:
    base = dict(steps=20, batch_size=8, lr=3e-3, warmup_steps=0, final_lr_fraction=1.0, checkpoint_every=10,
                val_every=10, val_windows=16, flow_steps=5, flow_windows=32, seed=0)
    return TrainConfig(**{**base, **kw})


def test_learning_rate_schedule():
    cfg = TrainConfig(steps=100, lr=1.0, warmup_steps=10, final_lr_fraction=0.1)
    assert learning_rate(0, cfg) == pytest.approx(0.1)
    assert learning_rate(10, cfg) == pytest.approx(1.0)
    assert learning_rate(100, cfg) == pytest.approx(0.1)
    assert learning_rate(55, cfg) == pytest.approx(0.55)


def test_time_budget_schedule_follows_whichever_of_steps_and_time_is_further():
    cfg = TrainConfig(steps=100, max_minutes=10.0)
    assert schedule_step(5, cfg, elapsed_s=0.0) == 5
    assert schedule_step(5, cfg, elapsed_s=300.0) == 50  # half the time spent: half-way down the schedule
    assert schedule_step(5, cfg, elapsed_s=6000.0) == 99  # never past the last step
    assert schedule_step(70, cfg, elapsed_s=300.0) == 70
    assert schedule_step(70, TrainConfig(steps=100), elapsed_s=1e9) == 70  # no budget: steps only
    with pytest.raises(ValueError, match="max_minutes"):
        TrainConfig(max_minutes=-1.0)


def test_a_spent_time_budget_ends_the_run_with_a_checkpoint_of_the_steps_done(dataset, tmp_path):
    out = tmp_path / "budget.safetensors"
    result = train_model(model_name="pred-lstm", model_config=TINY, dataset=dataset,
                         config=_quick(steps=1000, max_minutes=1e-6), out=out, progress=False)
    assert result.steps == 1  # one step always runs, then the budget is spent
    meta = C.read_meta(out)
    assert meta.training["steps"] == 1 and meta.training["config"]["max_minutes"] == 1e-6
    assert result.history[-1]["step"] == 1


def test_mixer_dct_trains_with_the_training_feature_scales_and_reloads(dataset, tmp_path):
    out = tmp_path / "mixer.safetensors"
    cfg = {"hidden_dim": 16, "context_blocks": 1, "sample_blocks": 1, "num_coeffs": 16, "train_samples": 2}
    data = dataclasses.replace(dataset.config, balance_actions=0.5)
    ds = dataclasses.replace(dataset, config=data)
    train_model(model_name="mixer-dct", model_config=cfg, dataset=ds, config=_quick(steps=4), out=out,
                progress=False)
    bundle = C.load_model(out)
    assert bundle.meta.data_config.balance_actions == 0.5
    assert np.allclose(bundle.model.config.feature_scale, dataset.stats.std)  # the loss is in metres
    windows = dataset.windows("test")
    gen = torch.Generator().manual_seed(0)
    samples = bundle.model.sample(torch.from_numpy(windows.obs[:2]), num_samples=3, horizon=48, generator=gen)
    assert samples.shape == (2, 3, 48, 51) and torch.isfinite(samples).all()


def test_dataset_split_of_the_small_folder(dataset):
    assert dataset.split.test and dataset.split.val and dataset.split.train
    assert {n.split("/")[1].split("_")[0] for n in dataset.split.test if n.startswith("cmu/")}


@pytest.mark.slow
def test_training_lowers_the_validation_loss_and_writes_a_full_checkpoint(dataset, tmp_path):
    out = tmp_path / "lstm.safetensors"
    torch.manual_seed(0)
    from motion2video.models.base import build_model

    untrained = build_model("pred-lstm", {**TINY, "feature_dim": 51})
    before = validation_loss(untrained, dataset, step=0, max_windows=16)["total"]
    result = train_model(model_name="pred-lstm", model_config=TINY, dataset=dataset,
                         config=_quick(steps=60, checkpoint_every=30, val_every=30), out=out, progress=False)
    assert result.path == out and out.is_file()
    assert result.val_loss < 0.8 * before
    assert [h["step"] for h in result.history] == [30, 60]
    last, sidecar = last_paths(out)
    assert last.is_file() and sidecar.is_file()

    bundle = C.load_model(out)
    meta = bundle.meta
    assert bundle.name == "pred-lstm" and bundle.kind == "deterministic"
    assert meta.config["hidden_dim"] == 16 and meta.config["feature_dim"] == 51
    assert meta.training["steps"] == 60 and meta.training["seed"] == 0
    assert meta.split == dataset.split and meta.data_config == dataset.config
    assert meta.skeleton == "h36m-17" and meta.version
    np.testing.assert_allclose(bundle.stats.mean, dataset.stats.mean)
    assert meta.data_summary["clips"] == len(CLIPS)
    obs = torch.from_numpy(dataset.windows("val").obs[:4])
    again = C.load_model(out).model.sample(obs, num_samples=2, horizon=8)
    assert torch.allclose(bundle.model.sample(obs, num_samples=2, horizon=8), again)


@pytest.mark.slow
def test_resume_continues_exactly(dataset, tmp_path):
    """20 steps in one go == 10 steps, then --resume to 20 (same batches, noise and optimiser state)."""
    full = train_model(model_name="cvae", model_config={**TINY, "latent_dim": 4}, dataset=dataset,
                       config=_quick(steps=20), out=tmp_path / "a.safetensors", progress=False)
    train_model(model_name="cvae", model_config={**TINY, "latent_dim": 4}, dataset=dataset,
                config=_quick(steps=10), out=tmp_path / "b.safetensors", progress=False)
    resumed = train_model(model_name="cvae", model_config={**TINY, "latent_dim": 4}, dataset=dataset,
                          config=_quick(steps=20), out=tmp_path / "b.safetensors", resume=True, progress=False)
    assert resumed.steps == 20
    a = C.load_model(full.path).model.state_dict()
    b = C.load_model(resumed.path).model.state_dict()
    for key in a:
        torch.testing.assert_close(a[key], b[key], rtol=1e-5, atol=1e-6, msg=key)
    with pytest.raises(InputError, match="config differs"):
        train_model(model_name="cvae", model_config={**TINY, "latent_dim": 5}, dataset=dataset,
                    config=_quick(steps=30), out=tmp_path / "b.safetensors", resume=True, progress=False)
    with pytest.raises(InputError, match="nothing to resume"):
        train_model(model_name="cvae", model_config=TINY, dataset=dataset, config=_quick(),
                    out=tmp_path / "never.safetensors", resume=True, progress=False)


@pytest.mark.slow
def test_behavior_trains_with_two_optimisers_and_a_flow(dataset, tmp_path):
    cfg = {"hidden_dim": 16, "latent_dim": 4, "regressor_dim": 16, "flow_blocks": 2, "flow_hidden": 16}
    result = train_model(model_name="behavior", model_config=cfg, dataset=dataset, config=_quick(steps=6),
                         out=tmp_path / "beh.safetensors", progress=False)
    bundle = C.load_model(result.path)
    assert bool(bundle.model.flow_fitted)
    sidecar = last_paths(result.path)[1]
    from safetensors import safe_open

    with safe_open(str(sidecar), framework="pt") as f:
        groups = json.loads(f.metadata()["param_groups"])
    assert set(groups) == {"main", "auxiliary"}
    obs = torch.from_numpy(dataset.windows("val").obs[:2])
    out = bundle.model.sample(obs, num_samples=3, horizon=5, generator=torch.Generator().manual_seed(0))
    assert out.shape == (2, 3, 5, 51) and torch.isfinite(out).all()


def test_baselines_cannot_be_trained(dataset, tmp_path):
    with pytest.raises(InputError, match="baseline"):
        train_model(model_name="zero-velocity", model_config={}, dataset=dataset, config=_quick(),
                    out=tmp_path / "zv.safetensors", progress=False)
    with pytest.raises(InputError, match="unknown model"):
        train_model(model_name="nope", model_config={}, dataset=dataset, config=_quick(),
                    out=tmp_path / "x.safetensors", progress=False)


def test_checkpoint_errors(tmp_path, monkeypatch):
    with pytest.raises(InputError, match="no such checkpoint"):
        C.load_model(tmp_path / "missing.safetensors")
    with pytest.raises(InputError, match="no such checkpoint"):
        C.load_model("not-a-shipped-model")
    plain = tmp_path / "plain.safetensors"
    save_file({"w": torch.zeros(2)}, str(plain))
    with pytest.raises(InputError, match="wrong kind"):
        C.load_model(plain)
    frames = tmp_path / "frames.safetensors"
    save_file({"w": torch.zeros(2)}, str(frames), metadata={"format": "motion2video-frames"})
    with pytest.raises(InputError, match="frame-generator"):
        C.load_model(frames)
    junk = tmp_path / "junk.safetensors"
    junk.write_bytes(b"not a safetensors file at all")
    with pytest.raises(InputError, match="safetensors"):
        C.load_model(junk)


def test_shipped_names_resolve_to_the_weights_folder(tmp_path, monkeypatch):
    monkeypatch.setattr(C, "WEIGHTS_DIR", tmp_path)
    bundle = C.baseline_bundle("last-step", DatasetConfig())
    # A saved baseline is a valid (weightless) checkpoint: enough to test name resolution.
    C.save_checkpoint(tmp_path / "my-model.safetensors", model=bundle.model, meta=bundle.meta)
    assert C.resolve_checkpoint("my-model") == tmp_path / "my-model.safetensors"
    assert C.shipped_names() == ["my-model"]
    loaded = C.load_model("my-model")
    assert loaded.name == "last-step" and loaded.data_config == DatasetConfig()
    meta = dataclasses.replace(bundle.meta, model="unregistered-model")
    C.save_checkpoint(tmp_path / "odd.safetensors", model=bundle.model, meta=meta)
    with pytest.raises(InputError, match="not a known model"):
        C.load_model("odd")
