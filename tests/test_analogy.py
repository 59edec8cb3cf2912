"""Analogy-based motion transfer (`motion2video analogy`): tiny models trained here on real body and face
clips, the known-answer analogy on procedural transitions, and the bad-input errors."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from motion2video.evaluation.analogy_benchmark import (known_answer_labels, procedural_analogy_case,
                                                      procedural_transition_dataset)
from motion2video.stages.latents import stitch_after
from motion2video.models.checkpoint import load_model
from motion2video.cli import main
from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.data.procedural import BodyParams, generate
from motion2video.core.rotations import heading_of
from motion2video.data.windows import resample
from motion2video.formats.io import load_motion, save_motion
from motion2video.core.motion import Motion
from motion2video.models.training import TrainConfig, train_model
from motion2video.formats.video import read_video

CLIPS = ("cmu/131_01.bvh", "cmu/131_03.bvh", "cmu/01_01.bvh")
OBSERVED, HORIZON = 8, 12
LATENT = {"latent_dim": 4}


def _train(name: str, data, out, *, steps: int = 3, model: dict | None = None, **data_kw):
    dataset = build_dataset(data, DatasetConfig(val_fraction=0.0, test_fraction=0.0, **data_kw))
    train_model(model_name=name, model_config={"hidden_dim": 16, **(model or {})}, dataset=dataset,
                config=TrainConfig(steps=steps, batch_size=4, warmup_steps=0, checkpoint_every=1000, val_every=0,
                                   flow_steps=5, flow_windows=16),
                out=out, progress=False)
    return out


@pytest.fixture(scope="module")
def ckpts(tmp_path_factory, mocap_dir, face_dir):
    root = tmp_path_factory.mktemp("mocap_analogy")
    for rel in CLIPS:
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).symlink_to(mocap_dir / rel)
    d = tmp_path_factory.mktemp("analogy_ckpt")
    return {
        "mtvae": _train("mtvae-add", root, d / "mtvae.safetensors", model=LATENT, observed=OBSERVED, future=HORIZON),
        "pred": _train("pred-lstm", root, d / "pred.safetensors"),
        "face": _train("mtvae-add", face_dir / "llv" / "dao.csv", d / "face.safetensors", model=LATENT,
                       layout="face", observed=4, future=6),
    }


@pytest.fixture(scope="module")
def clips(mocap_dir, face_dir):
    return {"walk": str(mocap_dir / "cmu/131_01.bvh"), "hop": str(mocap_dir / "cmu/131_03.bvh"),
            "jump": str(mocap_dir / "cmu/01_01.bvh"), "dao": str(face_dir / "llv" / "dao.csv"),
            "s07": str(face_dir / "livelinkface" / "S07-001.csv")}


def _at25(path) -> np.ndarray:
    m = load_motion(path)
    return resample(m.joints, m.fps, 25.0)


def test_analogy_of_consecutive_windows(ckpts, clips, tmp_path, capsys):
    out, npz = tmp_path / "a.mp4", tmp_path / "a.npz"
    code = main(["analogy", "--model", str(ckpts["mtvae"]), clips["walk"], clips["walk"], clips["jump"],
                 "--a-start", "480", "--c-start", "240", "--size", "48", "-o", str(out), "--npz", str(npz)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "B placed after A" not in printed
    # the model the user gave (mtvae.safetensors), not its architecture's name (mtvae-add)
    assert "(A:B::C:D with mtvae;" in printed and "mtvae-add" not in printed, printed
    frames, fps = read_video(out)
    assert fps == 25.0 and frames.shape == (OBSERVED + HORIZON, 48, 98, 3)
    saved = np.load(npz)
    walk, jump = _at25(clips["walk"]), _at25(clips["jump"])
    np.testing.assert_allclose(saved["ab"], walk[100:100 + OBSERVED + HORIZON], atol=1e-5)  # 480 / 120 * 25
    np.testing.assert_allclose(saved["cd"][:OBSERVED], jump[50:50 + OBSERVED], atol=1e-5)  # 240 / 120 * 25
    assert saved["cd"].shape == (OBSERVED + HORIZON, 17, 3) and saved["z"].shape == (4,)
    assert np.all(np.isfinite(saved["cd"]))


def test_b_from_another_file_is_placed_after_a(ckpts, clips, tmp_path, capsys):
    npz = tmp_path / "a.npz"
    code = main(["analogy", "--model", str(ckpts["mtvae"]), clips["walk"], clips["hop"], clips["jump"],
                 "--b-start", "120", "--size", "32", "-o", str(tmp_path / "a.mp4"), "--npz", str(npz)])
    assert code == 0 and "B placed after A" in capsys.readouterr().out
    ab = np.load(npz)["ab"]
    hop = _at25(clips["hop"])[25:25 + HORIZON]
    b = ab[OBSERVED:]
    # B keeps its pose (root-relative joints up to a rotation about z) and its root path
    np.testing.assert_allclose(np.linalg.norm(b - b[:, :1], axis=-1), np.linalg.norm(hop - hop[:, :1], axis=-1),
                               atol=1e-4)
    np.testing.assert_allclose(b[:, 0, 2], hop[:, 0, 2], atol=1e-5)


def test_stitch_after_continues_heading_and_root_step():
    a = generate([("walk", 1.0)], fps=25.0, seed=1).joints[:16]
    b = generate([("turn", 1.0)], fps=25.0, seed=2, params=BodyParams(height=1.8)).joints
    b = b + np.float32([4.0, -2.0, 0.0])
    placed = stitch_after(a, b)
    assert heading_of(placed[0]) == pytest.approx(heading_of(a[-1]), abs=1e-6)
    np.testing.assert_allclose(placed[0, 0, :2], a[-1, 0, :2] + (a[-1, 0, :2] - a[-2, 0, :2]), atol=1e-6)
    np.testing.assert_allclose(placed[:, :, 2], b[:, :, 2], atol=1e-6)  # heights unchanged
    step_b = np.linalg.norm(np.diff(b[:, 0, :2], axis=0), axis=-1)
    np.testing.assert_allclose(np.linalg.norm(np.diff(placed[:, 0, :2], axis=0), axis=-1), step_b, atol=1e-6)


def test_procedural_case_is_x_then_y_and_another_x():
    ab, c = procedural_analogy_case("walk", "run", seed=5)
    assert ab.shape == (64, 17, 3) and c.shape == (16, 17, 3)
    height = lambda j: j[:, 10, 2].max() - j[:, [3, 6], 2].min()  # noqa: E731  head above the ankles
    assert height(c) > height(ab[:16])  # C is another, taller body


@pytest.mark.slow
def test_known_answer_analogy_walk_to_run(tmp_path):
    """A -> B: walking turns into running; C: another walker (other speed, other height). Across 20 seeds the
    mode classifier labels D as running more often than as anything else. The model is a small mtvae-add
    trained here for 500 steps on the multimodal benchmark's context -> future transitions."""
    dataset = procedural_transition_dataset(600, seed=1)
    out = train_model(model_name="mtvae-add",
                      model_config={"hidden_dim": 64, "latent_dim": 8, "mlp_dim": 64, "kl_anneal_steps": 250},
                      dataset=dataset,
                      config=TrainConfig(steps=500, batch_size=32, lr=3e-3, warmup_steps=20, checkpoint_every=10_000,
                                         val_every=0, val_windows=32, seed=0),
                      out=tmp_path / "procedural.safetensors", progress=False)
    bundle = load_model(out.path)
    labels = known_answer_labels(bundle, "walk", "run", seeds=range(20))
    counts = Counter(labels.tolist())
    top, n_top = counts.most_common(1)[0]
    assert top == "run" and all(n < n_top for m, n in counts.items() if m != "run"), counts


@pytest.mark.slow
def test_face_analogy_renders_two_faces(ckpts, clips, tmp_path):
    out, npz = tmp_path / "face.mp4", tmp_path / "face.npz"
    code = main(["analogy", "--model", str(ckpts["face"]), clips["s07"], clips["s07"], clips["dao"],
                 "--a-start", "300", "--observed", "3", "--horizon", "3", "--size", "48", "-o", str(out),
                 "--npz", str(npz)])
    assert code == 0
    frames, _ = read_video(out)
    assert frames.shape == (6, 48, 98, 3)
    cd = np.load(npz)["cd"]
    assert cd.shape == (6, 58) and np.all((cd[:, :52] >= 0) & (cd[:, :52] <= 1))
    dao = load_motion(clips["dao"])
    np.testing.assert_allclose(cd[:3], resample(dao.params, dao.fps, 25.0)[:3], atol=1e-5)
    assert np.abs(frames[:, 10:, 6:44].astype(int) - frames[:, 10:, 56:94].astype(int)).mean() > 3  # two faces


# --- bad input ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("case", ["pred-lstm", "baseline", "face-model-body-clip", "body-model-face-clip",
                                  "c-start-out-of-range", "a-too-short", "other-skeleton", "observed-1"])
def test_bad_input(case, ckpts, clips, tmp_path, capsys):
    out, npz = tmp_path / "out.mp4", tmp_path / "out.npz"
    w, j = clips["walk"], clips["jump"]
    tail = ["-o", str(out), "--npz", str(npz), "--size", "32"]
    if case == "other-skeleton":
        j = str(save_motion(Motion(_at25(j), 25.0, skeleton="coco-17"), tmp_path / "coco.npz"))
    argv = {
        "pred-lstm": ["--model", str(ckpts["pred"]), w, w, j],
        "baseline": ["--model", "zero-velocity", w, w, j],
        "face-model-body-clip": ["--model", str(ckpts["face"]), clips["dao"], clips["dao"], w],
        "body-model-face-clip": ["--model", str(ckpts["mtvae"]), w, w, clips["dao"]],
        "c-start-out-of-range": ["--model", str(ckpts["mtvae"]), w, w, j, "--c-start", "99999"],
        "a-too-short": ["--model", str(ckpts["mtvae"]), w, w, j, "--a-start", "950"],
        "other-skeleton": ["--model", str(ckpts["mtvae"]), w, w, j],
        "observed-1": ["--model", str(ckpts["mtvae"]), w, w, j, "--observed", "1"],
    }[case]
    code = main(["analogy"] + argv + tail)
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and err.startswith("motion2video analogy: error:"), err
    assert not out.exists() and not npz.exists()
    expected = {"pred-lstm": "pred is a deterministic 'pred-lstm' model", "baseline": "baseline",
                "face-model-body-clip": "face is a face model, but this file holds body motion",
                "body-model-face-clip": "mtvae is a body model, but this file holds face motion",
                "c-start-out-of-range": "the C start frame 99999 is outside", "a-too-short": "needs",
                "other-skeleton": "coco-17", "observed-1": "--observed must be >= 2"}[case]
    assert expected in err


def test_errors_name_the_shipped_model_given(clips, tmp_path, capsys):
    """Body motion given to the shipped mtvae-add-face names mtvae-add-face, not its architecture mtvae-add."""
    out = tmp_path / "a.mp4"
    code = main(["analogy", "--model", "mtvae-add-face", clips["walk"], clips["walk"], clips["jump"],
                 "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and not out.exists()
    assert "mtvae-add-face is a face model, but this file holds body motion" in err, err
    assert "131_01.bvh" in err and "mtvae-add is" not in err, err
