"""`motion2video train / evaluate / sample` end to end on a few real clips, and their bad-input errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from safetensors.torch import save_file

from motion2video.cli import main
from motion2video.models.checkpoint import load_model
from tests.conftest import link_clips

CLIPS = ("cmu/131_01.bvh", "cmu/131_02.bvh", "cmu/01_01.bvh", "mass/mass_pirouette.bvh",
         "deepmimic/humanoid3d_spin.bvh")
TINY = json.dumps({"model": {"hidden_dim": 8, "latent_dim": 4},
                   "train": {"batch_size": 4, "checkpoint_every": 2, "val_every": 2, "val_windows": 8}})


@pytest.fixture(scope="module")
def small_data(tmp_path_factory, mocap_dir):
    return link_clips(tmp_path_factory.mktemp("mocap_cli"), mocap_dir, CLIPS)


@pytest.fixture(scope="module")
def trained(small_data, tmp_path_factory):
    """A tiny cvae trained for 4 steps through the CLI."""
    out = tmp_path_factory.mktemp("ckpt") / "cvae.safetensors"
    code = main(["train", "--model", "cvae", "--data", str(small_data), "-o", str(out), "--steps", "4",
                 "--seed", "1", "--config", TINY, "--no-progress"])
    assert code == 0
    return out


@pytest.fixture
def wrong_kind(tmp_path):
    path = tmp_path / "frames.safetensors"
    save_file({"w": torch.zeros(1)}, str(path), metadata={"format": "motion2video-frames"})
    return path


def test_train_writes_a_resumable_checkpoint(trained, small_data, capsys):
    bundle = load_model(trained)
    assert bundle.name == "cvae" and bundle.meta.training["steps"] == 4 and bundle.meta.training["seed"] == 1
    assert bundle.meta.config["hidden_dim"] == 8 and bundle.meta.split is not None
    assert trained.with_name("cvae.last.safetensors").is_file()
    assert trained.with_name("cvae.last.optim.safetensors").is_file()
    code = main(["train", "--model", "cvae", "--data", str(small_data), "-o", str(trained), "--steps", "6",
                 "--seed", "1", "--config", TINY, "--resume", "--no-progress"])
    assert code == 0 and load_model(trained).meta.training["steps"] == 6
    assert "wrote" in capsys.readouterr().out


def test_evaluate_writes_the_json_table(trained, small_data, tmp_path, capsys):
    out = tmp_path / "eval.json"
    code = main(["evaluate", "--model", str(trained), "--data", str(small_data), "--samples", "3",
                 "--stride", "32", "--json", str(out)])
    assert code == 0
    result = json.loads(out.read_text())
    assert set(result) == {"protocol", "results", "per_action", "macro", "ade_per_frame"}
    assert list(result["results"]) == ["cvae", "zero-velocity", "last-step", "sequence-motion"]
    assert list(result["per_action"]) == list(result["macro"]) == list(result["results"])
    counts = {a: row["windows"] for a, row in result["per_action"]["cvae"].items()}
    assert counts == result["protocol"]["actions"] and sum(counts.values()) == result["protocol"]["windows"]
    for row in result["results"].values():
        assert {"ade", "fde", "mmade", "mmfde", "apd"} <= set(row)
        assert all(np.isfinite(v) for v in row.values())
    assert result["results"]["zero-velocity"]["apd"] == 0.0
    assert result["protocol"]["samples"] == 3 and result["protocol"]["windows"] > 0
    assert result["protocol"]["rigid_bones"] is False
    assert result["results"]["zero-velocity"]["velocity_ratio"] == 0.0  # standing still
    assert result["results"]["cvae"]["velocity_ratio"] > 0.0
    assert "zero-velocity" in capsys.readouterr().out


def evaluate_variants(trained, small_data, tmp_path, variants: dict[str, list[str]]) -> dict[str, dict]:
    """``motion2video evaluate`` of ``trained`` once per variant (its extra options): name -> the JSON result."""
    runs = {}
    for name, extra in variants.items():
        out = tmp_path / f"{name}.json"
        assert main(["evaluate", "--model", str(trained), "--data", str(small_data), "--samples", "3",
                     "--stride", "32", "--json", str(out)] + extra) == 0
        runs[name] = json.loads(out.read_text())
    return runs


def test_evaluate_rigid_bones_scores_futures_with_the_observed_bone_lengths(trained, small_data, tmp_path):
    """--rigid-bones changes the learned model's scores, not the baselines' (zero-velocity repeats the last
    observed frame, whose bones already have those lengths), and the projection keeps the observed lengths."""
    from motion2video.core.skeletons import bone_lengths
    from motion2video.evaluation.forecasting import rigid_vectors

    runs = evaluate_variants(trained, small_data, tmp_path, {"raw": [], "rigid": ["--rigid-bones"]})
    assert runs["rigid"]["protocol"]["rigid_bones"] is True
    assert runs["rigid"]["results"]["cvae"]["ade"] != runs["raw"]["results"]["cvae"]["ade"]
    assert runs["rigid"]["results"]["zero-velocity"]["ade"] == pytest.approx(runs["raw"]["results"]["zero-velocity"]["ade"])
    rng = np.random.default_rng(0)
    last, pred = rng.normal(size=(2, 48)), rng.normal(size=(2, 3, 4, 48))
    joints = np.concatenate([np.zeros((2, 3, 4, 1, 3)), rigid_vectors(pred, last).reshape(2, 3, 4, 16, 3)], axis=-2)
    want = bone_lengths(np.concatenate([np.zeros((2, 1, 3)), last.reshape(2, 16, 3)], axis=1))  # (2, 17)
    np.testing.assert_allclose(bone_lengths(joints)[..., 1:], np.broadcast_to(want[:, None, None, 1:], (2, 3, 4, 16)))


def test_evaluate_scores_futures_that_continue_the_observed_motion_unless_raw(trained, small_data, tmp_path):
    """By default a learned model's first future frame is the last observed frame plus its last step: the same
    error as the last-step baseline's first frame. --raw-futures scores the network's own futures; the baselines are
    the same either way."""
    runs = evaluate_variants(trained, small_data, tmp_path, {"continued": [], "raw": ["--raw-futures"]})
    assert runs["continued"]["protocol"]["continue_motion"] is True
    assert runs["raw"]["protocol"]["continue_motion"] is False
    first = {name: r["ade_per_frame"] for name, r in runs.items()}
    assert first["continued"]["cvae"][0] == pytest.approx(first["continued"]["last-step"][0], rel=1e-4)
    assert first["raw"]["cvae"][0] != pytest.approx(first["raw"]["last-step"][0], rel=1e-2)
    for baseline in ("zero-velocity", "last-step", "sequence-motion"):
        assert runs["raw"]["results"][baseline] == runs["continued"]["results"][baseline]


def test_sample_writes_video_and_npz_deterministically(trained, mocap_dir, tmp_path):
    clip = mocap_dir / "cmu" / "131_02.bvh"
    args = ["sample", "--model", str(trained), str(clip), "--samples", "3", "--horizon", "10", "--seed", "4",
            "--size", "64"]
    assert main(args + ["-o", str(tmp_path / "a.mp4"), "--npz", str(tmp_path / "a.npz")]) == 0
    assert main(args + ["-o", str(tmp_path / "b.mp4"), "--npz", str(tmp_path / "b.npz")]) == 0
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    assert a["observed"].shape == (16, 17, 3) and a["futures"].shape == (3, 10, 17, 3)
    np.testing.assert_array_equal(a["futures"], b["futures"])
    assert (tmp_path / "a.mp4").stat().st_size > 0
    # The futures continue from the observed clip (world coordinates, not the canonical frame).
    assert np.linalg.norm(a["futures"][:, 0, 0] - a["observed"][-1, 0], axis=-1).max() < 0.5


def test_sample_rigid_bones_keeps_the_observed_bone_lengths(mocap_dir, tmp_path):
    """--rigid-bones: every future frame of the shipped model has the last observed frame's bone lengths (the
    raw futures do not), the pelvis and the bone directions stay, and the npz says which it is."""
    from motion2video.core.skeletons import bone_lengths

    clip = mocap_dir / "cmu" / "02_01.bvh"
    args = ["sample", "--model", "mtvae-add", str(clip), "--samples", "3", "--size", "64"]
    assert main(args + ["-o", str(tmp_path / "raw.mp4"), "--npz", str(tmp_path / "raw.npz")]) == 0
    assert main(args + ["--rigid-bones", "-o", str(tmp_path / "rigid.mp4"), "--npz", str(tmp_path / "rigid.npz")]) == 0
    raw, rigid = np.load(tmp_path / "raw.npz"), np.load(tmp_path / "rigid.npz")
    assert not bool(raw["rigid_bones"]) and bool(rigid["rigid_bones"])
    observed = bone_lengths(rigid["observed"][-1])[1:]
    np.testing.assert_allclose(bone_lengths(rigid["futures"])[..., 1:], np.broadcast_to(observed, (3, 48, 16)),
                               rtol=1e-4)
    assert np.abs(bone_lengths(raw["futures"])[..., 1:] / observed - 1).max() > 0.02
    np.testing.assert_allclose(rigid["futures"][:, :, 0], raw["futures"][:, :, 0], atol=1e-6)  # pelvis


def test_sample_with_a_baseline_name(mocap_dir, tmp_path):
    out = tmp_path / "zv.mp4"
    assert main(["sample", "--model", "zero-velocity", str(mocap_dir / "cmu" / "131_02.bvh"), "--samples", "1",
                 "--horizon", "4", "--size", "64", "-o", str(out), "--npz", str(tmp_path / "zv.npz")]) == 0
    z = np.load(tmp_path / "zv.npz")
    np.testing.assert_allclose(z["futures"][0, -1], z["observed"][-1], atol=1e-4)


def _fails(args, capsys, *outputs) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "error:" in err
    for out in outputs:
        assert not out.exists()
    return err


def test_bad_input_gets_one_line_and_exit_code_2(trained, small_data, mocap_dir, wrong_kind, tmp_path, capsys):
    video, js = tmp_path / "x.mp4", tmp_path / "x.json"
    clip = str(mocap_dir / "cmu" / "131_02.bvh")
    short = str(mocap_dir / "mass" / "mass_run.bvh")  # 14 frames at 25 fps
    missing = str(tmp_path / "missing.safetensors")
    # sample
    assert "no such checkpoint" in _fails(["sample", "--model", missing, clip, "--samples", "2", "-o", str(video)],
                                          capsys, video)
    assert "wrong kind" in _fails(["sample", "--model", str(wrong_kind), clip, "--samples", "2", "-o", str(video)],
                                  capsys, video)
    assert "shorter than the observed" in _fails(
        ["sample", "--model", str(trained), short, "--samples", "2", "-o", str(video)], capsys, video)
    # a shipped name whose weights were retired says so, and what to use instead
    retired = _fails(["sample", "--model", "mixer-dct", clip, "--samples", "2", "-o", str(video)], capsys, video)
    assert "retired" in retired and "mixer-cvae-dlow" in retired and "696e72f" in retired
    assert "--samples" in _fails(["sample", "--model", str(trained), clip, "--samples", "0", "-o", str(video)],
                                 capsys, video)
    # evaluate
    assert "no such checkpoint" in _fails(["evaluate", "--model", missing, "--data", clip, "--json", str(js)],
                                          capsys, js)
    assert "wrong kind" in _fails(["evaluate", "--model", str(wrong_kind), "--data", clip, "--json", str(js)],
                                  capsys, js)
    assert "long enough" in _fails(["evaluate", "--model", str(trained), "--data", short, "--json", str(js)],
                                   capsys, js)
    assert "--samples" in _fails(["evaluate", "--model", str(trained), "--data", clip, "--samples", "0",
                                  "--json", str(js)], capsys, js)
    # train
    ckpt = tmp_path / "t.safetensors"
    assert "unknown model" in _fails(["train", "--model", "nope", "--data", str(small_data), "-o", str(ckpt)],
                                     capsys, ckpt)
    assert "baseline" in _fails(["train", "--model", "last-step", "--data", str(small_data), "-o", str(ckpt)],
                                capsys, ckpt)
    assert "long enough" in _fails(["train", "--model", "cvae", "--data", short, "-o", str(ckpt)], capsys, ckpt)
    assert "no such file" in _fails(["train", "--model", "cvae", "--data", str(tmp_path / "nodata"), "-o", str(ckpt)],
                                    capsys, ckpt)
    assert "unknown field" in _fails(["train", "--model", "cvae", "--data", str(small_data), "-o", str(ckpt),
                                      "--config", '{"model": {"bogus": 1}}'], capsys, ckpt)


def test_face_model_evaluates_a_face_capture(face_dir, tmp_path, capsys):
    ckpt = tmp_path / "face.safetensors"
    assert main(["train", "--model", "mtvae-add", "--data", str(face_dir / "llv" / "dao.csv"), "-o", str(ckpt),
                 "--steps", "2", "--config", json.dumps({"model": {"hidden_dim": 8, "latent_dim": 4, "mlp_dim": 8},
                                                         "train": {"batch_size": 2}}), "--no-progress"]) == 0
    bundle = load_model(ckpt)
    assert bundle.layout.kind == "face" and bundle.meta.config["feature_dim"] == 58
    out = tmp_path / "face.json"
    assert main(["evaluate", "--model", str(ckpt), "--data", str(face_dir / "llv" / "dao.csv"), "--samples", "2",
                 "--split", "all", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["protocol"]["layout"] == "face"
    err = _fails(["evaluate", "--model", str(ckpt), "--data", str(face_dir.parent / "mocap" / "cmu" / "131_02.bvh")],
                 capsys)
    assert "face" in err


@pytest.mark.slow
def test_sample_mesh_style(trained, mocap_dir, tmp_path):
    out = tmp_path / "mesh.mp4"
    assert main(["sample", "--model", str(trained), str(mocap_dir / "cmu" / "131_02.bvh"), "--samples", "1",
                 "--horizon", "2", "--style", "mesh", "--size", "64", "-o", str(out)]) == 0
    from motion2video.formats.video import read_video

    frames, fps = read_video(out)
    assert frames.shape[0] == 18 and fps == pytest.approx(25.0)
    assert frames[:, 10:-10, 10:-10].std() > 5  # a body was drawn, not a blank frame


@pytest.mark.slow
def test_face_model_samples_a_face_capture(face_dir, tmp_path):
    ckpt = tmp_path / "face.safetensors"
    assert main(["train", "--model", "cvae", "--data", str(face_dir / "llv" / "dao.csv"), "-o", str(ckpt),
                 "--steps", "1", "--config", json.dumps({"model": {"hidden_dim": 8, "latent_dim": 4},
                                                         "train": {"batch_size": 2}}), "--no-progress"]) == 0
    out = tmp_path / "face.mp4"
    assert main(["sample", "--model", str(ckpt), str(face_dir / "llv" / "dao.csv"), "--samples", "2", "--horizon", "3",
                 "--size", "64", "-o", str(out), "--npz", str(tmp_path / "face.npz")]) == 0
    z = np.load(tmp_path / "face.npz")
    assert z["observed"].shape == (16, 58) and z["futures"].shape == (2, 3, 58)
    assert z["futures"][..., :52].min() >= 0.0 and z["futures"][..., :52].max() <= 1.0
    assert str(z["layout"]) == "face" and out.stat().st_size > 0


def test_sample_help_lists_every_shipped_motion_model_and_names_the_best(capsys):
    """`sample --help` lists the shipped motion models (every checkpoint in motion2video/weights
    that is not a frame generator or the pose estimator), the best body sampler first."""
    from motion2video.models.checkpoint import shipped_names

    with pytest.raises(SystemExit):
        main(["sample", "--help"])
    text = capsys.readouterr().out
    listed = text.split("shipped motion models")[1]
    motion = [n for n in shipped_names() if not n.startswith("frames-")]
    assert motion and all(f"  {name} " in listed for name in motion), motion
    first = listed.strip().splitlines()[1].split()
    assert first[0] == "mixture-periodic" and "best" in " ".join(first)


def test_every_shipped_weight_file_has_a_model_card_and_stays_under_30_mb():
    """The house rule for motion2video/weights: plain files under 30 MB, each with a card saying how it was made."""
    from motion2video.models.checkpoint import WEIGHTS_DIR

    files = sorted(p for p in WEIGHTS_DIR.iterdir() if p.suffix in (".safetensors", ".tflite"))
    assert len(files) >= 10
    for path in files:
        assert path.stat().st_size < 30 * 2**20, path.name
        card = {"pose_detection": "blazepose", "pose_landmark_full": "blazepose",
                "face_detection_short_range": "facemesh", "face_landmark": "facemesh",
                "iris_landmark": "facemesh"}.get(path.stem, path.stem)
        assert (WEIGHTS_DIR / f"{card}.md").is_file(), f"{path.name} has no model card"
