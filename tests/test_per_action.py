"""Per-action and macro-averaged forecasting metrics: the grouping functions by hand, and
``evaluate_bundles`` on real clips of three actions (a tiny trained model and the baselines)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from motion2video.models.checkpoint import baseline_bundle, load_model
from motion2video.data import windows as W
from motion2video.data.corpus import action_class
from motion2video.data.dataset import Clip, DatasetConfig, build_dataset
from motion2video.evaluation.forecasting import EvalProtocol, evaluate_bundles
from motion2video.evaluation.per_action import (
    UNLABELLED,
    group_by_action,
    macro_average,
    per_action_means,
    ratios_to,
    window_weighted_average,
)
from motion2video.formats.mocap import load_mocap
from motion2video.models.baselines import BASELINES
from motion2video.models.training import TrainConfig, train_model

# a walk and a hop of CMU subject 131 and a run of subject 2 (labels from the manifest's action column)
CLIPS = ("cmu/131_02.bvh", "cmu/131_03.bvh", "cmu/02_03.bvh")


def test_grouping_and_averages_by_hand():
    groups = group_by_action(["walk", "jump", None, "walk", "walk", "jump"])
    assert list(groups) == ["walk", "jump", UNLABELLED]  # most windows first
    assert groups["walk"].tolist() == [0, 3, 4] and groups[UNLABELLED].tolist() == [2]
    per = per_action_means({"ade": np.array([1.0, 2.0, 9.0, 3.0, 5.0, 4.0])}, groups)
    assert per == {"walk": {"ade": 3.0, "windows": 3}, "jump": {"ade": 3.0, "windows": 2},
                   UNLABELLED: {"ade": 9.0, "windows": 1}}
    assert macro_average(per) == {"ade": 5.0}  # (3 + 3 + 9) / 3
    assert window_weighted_average(per)["ade"] == pytest.approx(24.0 / 6)  # the pooled mean of the 6 windows
    with pytest.raises(ValueError):
        macro_average({})


@pytest.fixture(scope="module")
def labelled(mocap_dir, tmp_path_factory):
    """Three real clips of three actions at 25 fps, a dataset over them, and a 3-step tiny mtvae-add."""
    cfg = DatasetConfig(observed=8, future=12, stride=8, val_fraction=0.0, test_fraction=0.0)
    clips = []
    for rel in CLIPS:
        motion = load_mocap(mocap_dir / rel)  # the manifest beside the file gives rate and label
        clips.append(Clip(name=rel, data=W.resample(motion.joints, motion.fps, cfg.fps).astype(np.float32),
                          label=action_class(motion.label), group=rel))
    ds = build_dataset(mocap_dir, cfg, clips=clips)
    out = tmp_path_factory.mktemp("per_action") / "tiny.safetensors"
    train_model(model_name="mtvae-add", model_config={"hidden_dim": 16, "latent_dim": 4}, dataset=ds, out=out,
                config=TrainConfig(steps=3, batch_size=4, warmup_steps=0, checkpoint_every=1000, val_every=0),
                progress=False)
    return ds, load_model(out)


def test_evaluate_reports_per_action_and_macro_on_real_clips(labelled):
    ds, tiny = labelled
    windows = ds.windows("all", stride=8)
    assert {lab for lab in windows.labels} == {"walk", "jump", "run"}
    bundles = [tiny] + [baseline_bundle(n, ds.config, stats=ds.stats) for n in BASELINES]
    result = evaluate_bundles(bundles, windows, protocol=EvalProtocol(samples=4, stride=8, split="all"))
    counts = result.protocol["actions"]
    assert sum(counts.values()) == len(windows) and set(counts) == {"walk", "jump", "run"}
    pooled_keys = ("ade", "fde", "mmade", "mmfde", "apd")
    for method, pooled in result.results.items():
        per = result.per_action[method]
        assert {a: row["windows"] for a, row in per.items()} == counts
        assert set(result.macro[method]) == set(pooled)  # the same metric keys as the pooled row
        for key in pooled:
            # macro = the unweighted mean over the actions
            assert result.macro[method][key] == pytest.approx(np.mean([row[key] for row in per.values()]), rel=1e-12)
        for key in pooled_keys:
            # pooled = the window-weighted mean of the per-action values
            weighted = sum(row[key] * row["windows"] for row in per.values()) / len(windows)
            assert pooled[key] == pytest.approx(weighted, rel=1e-9, abs=1e-12)
    assert result.results[tiny.label]["apd"] > 0  # a stochastic model: APD is not trivially 0
    # the macro differs from the pooled mean when the actions have different window counts and errors
    zv = result.results["zero-velocity"]
    assert result.macro["zero-velocity"]["ade"] != pytest.approx(zv["ade"], rel=1e-6)
    # a deterministic baseline scored on one action's windows alone gives that action's row
    for action, idx in group_by_action(windows.labels).items():
        frames = dataclasses.replace(windows.frames, origin=windows.frames.origin[idx], angle=windows.frames.angle[idx])
        part = dataclasses.replace(windows, features=windows.features[idx], raw=windows.raw[idx], frames=frames,
                                   clip_names=tuple(windows.clip_names[i] for i in idx), starts=windows.starts[idx],
                                   labels=tuple(windows.labels[i] for i in idx))
        alone = evaluate_bundles(bundles[1:2], part, protocol=EvalProtocol(samples=1, stride=8, split="all"))
        row = result.per_action["zero-velocity"][action]
        for key in ("ade", "fde", "velocity_ratio", "acceleration_ratio"):
            assert alone.results["zero-velocity"][key] == pytest.approx(row[key], rel=1e-9)
    text = result.per_action_table()
    assert all(f"{a} ({n}) zero-velocity" in text for a, n in counts.items())
    assert "walk" in result.to_json()["per_action"]["zero-velocity"]


def test_ratios_to_divides_per_action_and_averages_the_ratios_unweighted():
    """Known answer: two actions of very different window counts count once each in the macro ratio."""
    model = {"walk": {"ade": 0.3, "fde": 0.2, "windows": 40}, "jump": {"ade": 0.9, "fde": 1.2, "windows": 2}}
    zero = {"walk": {"ade": 0.6, "fde": 0.8, "windows": 40}, "jump": {"ade": 1.0, "fde": 1.0, "windows": 2}}
    got = ratios_to(model, zero)
    assert got["walk"] == pytest.approx([0.5, 0.25]) and got["jump"] == pytest.approx([0.9, 1.2])
    assert got["macro"] == pytest.approx([0.7, 0.725])
    assert list(got) == ["walk", "jump", "macro"]
