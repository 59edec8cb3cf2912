"""Formats out: ``--bvh DIR`` writes BVH files that the project's own reader reads back onto the
joints they were written from."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.core.skeletons import BODY_POINT_RIGS, h36m_body_points
from motion2video.formats.bvh import canonical_positions, read_bvh
from motion2video.formats.bvh_write import NODES, RIG, write_bvh
from motion2video.formats.io import load_motion
from tests.conftest import link_clips

TINY = json.dumps({"model": {"hidden_dim": 8, "latent_dim": 4},
                   "train": {"batch_size": 4, "checkpoint_every": 2, "val_every": 2, "val_windows": 8}})


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory, mocap_dir):
    """A cvae trained for 4 steps: its futures move, unlike a baseline's."""
    data = link_clips(tmp_path_factory.mktemp("bvh_out_data"), mocap_dir,
                      ("cmu/131_01.bvh", "cmu/131_02.bvh", "cmu/01_01.bvh"))
    out = tmp_path_factory.mktemp("bvh_out_ckpt") / "cvae.safetensors"
    assert main(["train", "--model", "cvae", "--data", str(data), "-o", str(out), "--steps", "4", "--seed", "1",
                 "--config", TINY, "--no-progress"]) == 0
    return out


def test_real_clip_round_trips_through_bvh(mocap_dir, tmp_path):
    """CMU 13_10 at 120 fps -> BVH at 25 fps -> the BVH reader: the resampled joints within 1 mm, rig
    detected, floor kept, y up in the file (the pelvis's file y is its height)."""
    motion = load_motion(mocap_dir / "cmu" / "13_10.bvh")
    path = write_bvh(tmp_path / "walk.bvh", motion.joints[:600], motion.fps)
    back = load_motion(path)
    want = load_motion(mocap_dir / "cmu" / "13_10.bvh", target_fps=25).joints[:back.num_frames]
    assert back.fps == 25.0 and back.num_frames == 125
    err = np.linalg.norm(back.joints - want, axis=-1)
    assert err.max() < 0.001, err.max()
    clip = read_bvh(path)
    assert canonical_positions(clip).rig == RIG and RIG in BODY_POINT_RIGS
    hips = clip.values[:, :3]  # root position channels, metres, y up
    np.testing.assert_allclose(hips[:, 1], want[:, 0, 2], atol=1e-5)
    assert [n for n in clip.names if not n.endswith(":end")] == [n.name for n in NODES]
    # h36m_body_points is near identity on canonical joints, but only near: on this 5 s window it moves the
    # spine by 1.2 cm (its spine split uses the window's longest pelvis-thorax distance), so the reader
    # skips it for this rig and the round trip stays under 1 mm
    moved = np.linalg.norm(h36m_body_points(want) - want, axis=-1)
    assert moved.max() < 0.02 and moved.max() > 20 * err.max()


def test_sample_bvh_reads_back_onto_the_npz_joints(tiny_model, mocap_dir, tmp_path):
    """sample --rigid-bones --bvh DIR: one file per future (observed then future), read back within 2 cm of
    the --npz joints (measured: 0.07 mm)."""
    npz, folder = tmp_path / "s.npz", tmp_path / "bvh"
    assert main(["sample", "--model", str(tiny_model), str(mocap_dir / "cmu" / "02_01.bvh"), "--samples", "3",
                 "--size", "64", "--rigid-bones", "-o", str(tmp_path / "s.mp4"), "--npz", str(npz),
                 "--bvh", str(folder)]) == 0
    data = np.load(npz)
    assert sorted(p.name for p in folder.iterdir()) == ["sample_1.bvh", "sample_2.bvh", "sample_3.bvh"]
    for k in range(3):
        want = np.concatenate([data["observed"], data["futures"][k]])  # (64, 17, 3)
        back = load_motion(folder / f"sample_{k + 1}.bvh")
        assert back.fps == 25.0 and back.num_frames == len(want)
        err = np.linalg.norm(back.joints - want, axis=-1)
        assert err.max() < 0.02, err.max()
    # the futures differ, so the files do
    assert (folder / "sample_1.bvh").read_text() != (folder / "sample_2.bvh").read_text()


def test_bvh_option_errors_write_nothing(tiny_model, mocap_dir, tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("x")
    out = tmp_path / "s.mp4"
    args = ["sample", "--model", str(tiny_model), str(mocap_dir / "cmu" / "02_01.bvh"), "--samples", "1",
            "-o", str(out)]
    assert main(args + ["--bvh", str(afile)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "afile" in err[0] and "--bvh" in err[0]
    assert main(args + ["--bvh", str(tmp_path / "no" / "such" / "dir")]) == 2
    assert "parent does not exist" in capsys.readouterr().err
    assert not out.exists()


@pytest.fixture(scope="module")
def tiny_latent_models(tmp_path_factory, mocap_dir):
    """A behaviour model and an MT-VAE trained 3 steps on three CMU clips."""
    from motion2video.data.dataset import DatasetConfig, build_dataset
    from motion2video.models.training import TrainConfig, train_model

    root = link_clips(tmp_path_factory.mktemp("bvh_latent_data"), mocap_dir,
                      ("cmu/131_01.bvh", "cmu/131_03.bvh", "cmu/01_01.bvh"))
    d = tmp_path_factory.mktemp("bvh_latent_ckpt")
    out = {}
    for name, kind, data_kw in (("behavior", "behavior", {}), ("mtvae", "mtvae-add", {"observed": 8, "future": 12})):
        dataset = build_dataset(root, DatasetConfig(val_fraction=0.0, test_fraction=0.0, **data_kw))
        train_model(model_name=kind, model_config={"hidden_dim": 16, "latent_dim": 4}, dataset=dataset,
                    config=TrainConfig(steps=3, batch_size=4, warmup_steps=0, checkpoint_every=1000, val_every=0,
                                       flow_steps=5, flow_windows=16),
                    out=d / f"{name}.safetensors", progress=False)
        out[name] = d / f"{name}.safetensors"
    return out


def _bone_spread(joints: np.ndarray) -> float:
    """The largest change of a bone's length over the frames (m): what a rigid-bone BVH cannot follow."""
    from motion2video.core.skeletons import bone_lengths

    lengths = bone_lengths(joints)  # (T, 17)
    return float((lengths.max(axis=0) - lengths.min(axis=0)).max())


def test_transfer_and_analogy_write_bvh(tiny_latent_models, mocap_dir, tmp_path):
    """transfer --bvh: one file per re-enactment; analogy --bvh: C then D. Read back, each is within its
    own bone-length change of the --npz joints (these outputs have no --rigid-bones: the model's bones
    stretch, the file's bones cannot)."""
    target, source = str(mocap_dir / "cmu/01_01.bvh"), str(mocap_dir / "cmu/131_03.bvh")
    npz, folder = tmp_path / "t.npz", tmp_path / "t"
    assert main(["transfer", "--model", str(tiny_latent_models["behavior"]), "--sample", "2", "--target", target,
                 "--horizon", "10", "--style", "skeleton", "--size", "48", "-o", str(tmp_path / "t.mp4"),
                 "--npz", str(npz), "--bvh", str(folder)]) == 0
    reenacted = np.load(npz)["reenacted"]  # (2, 11, 17, 3)
    assert sorted(p.name for p in folder.iterdir()) == ["reenacted_1.bvh", "reenacted_2.bvh"]
    for k in range(2):
        back = load_motion(folder / f"reenacted_{k + 1}.bvh")
        assert back.num_frames == reenacted.shape[1] and back.fps == 25.0
        err = np.linalg.norm(back.joints - reenacted[k], axis=-1).max()
        assert err <= 2 * _bone_spread(reenacted[k]) + 1e-3, (err, _bone_spread(reenacted[k]))
    npz, folder = tmp_path / "a.npz", tmp_path / "a"
    assert main(["analogy", "--model", str(tiny_latent_models["mtvae"]), target, target, source,
                 "--size", "48", "-o", str(tmp_path / "a.mp4"), "--npz", str(npz), "--bvh", str(folder)]) == 0
    cd = np.load(npz)["cd"]  # (20, 17, 3)
    back = load_motion(folder / "analogy_1.bvh")
    assert back.num_frames == len(cd)
    assert np.linalg.norm(back.joints - cd, axis=-1).max() <= 2 * _bone_spread(cd) + 1e-3
