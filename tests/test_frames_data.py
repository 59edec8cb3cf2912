"""The synthetic appearance data rendered with the Anny body and face renderers from the real captures in
../shared/data, and the train-frames / evaluate-frames commands end to end (tiny sizes)."""

from __future__ import annotations

import json
import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.generator.specs import DatasetSpec, is_test_clip
from motion2video.generator.data import body_structures, cache_folder, evaluation_pair_index, load_or_generate, make_pairs
from motion2video.generator.render_data import is_test_face_clip

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def tiny_spec(domain: str, split: str) -> DatasetSpec:
    return DatasetSpec(domain=domain, split=split, image_size=64, num_sequences=2, frames_per_sequence=3,
                       num_identities=2, sequences_per_shard=1, window_seconds=1.0 if domain == "body" else 3.0)


def test_held_out_clip_rules():
    from motion2video.formats.manifest import read_manifest

    names = list(read_manifest(DATA / "mocap" / "manifest.csv"))
    test = [n for n in names if is_test_clip(n)]
    assert 0.1 <= len(test) / len(names) <= 0.3 and len(names) - len(test) >= 50
    assert is_test_face_clip("livelinkface/S07-001.csv") and not is_test_face_clip("llv/dao.csv")


@pytest.mark.slow
def test_rendered_body_sequences(tmp_path):
    spec = tiny_spec("body", "test")
    seqs = load_or_generate(spec, cache_dir=tmp_path, progress=False)
    assert seqs.images.shape == (2, 3, 64, 64, 3) and seqs.images.dtype == np.uint8
    assert seqs.points.shape == (2, 3, 17, 2) and seqs.structure_images is None
    assert all(is_test_clip(str(c)) for c in seqs.clip)  # held-out clips only
    # Silhouettes come with the frames: the person covers some of the picture, and its pixels differ
    # from the background pixels of another frame where the person is not.
    assert seqs.masks.shape == (2, 3, 64, 64) and 0.01 < seqs.masks.mean() < 0.5
    # The person moves between frames, the joints project inside the picture, the background is kept.
    assert not np.array_equal(seqs.images[0, 0], seqs.images[0, 2])
    assert np.all((seqs.points > -2) & (seqs.points < 66))
    st = body_structures(seqs.points[0], 64)
    assert st.shape == (3, 33, 64, 64) and st.max() == pytest.approx(1.0, abs=0.05)
    # Cached: a second call loads the same shards without rendering.
    shards = sorted(cache_folder(tmp_path, spec).glob("shard-*.npz"))
    assert len(shards) == 2
    mtimes = [p.stat().st_mtime_ns for p in shards]
    again = load_or_generate(spec, cache_dir=tmp_path, progress=False)
    np.testing.assert_array_equal(again.images, seqs.images)
    assert [p.stat().st_mtime_ns for p in shards] == mtimes
    # An interrupted generation resumes: delete one shard, and it is re-rendered identically.
    shards[1].unlink()
    redone = load_or_generate(spec, cache_dir=tmp_path, progress=False)
    np.testing.assert_array_equal(redone.images, seqs.images)
    np.testing.assert_allclose(redone.points, seqs.points)


@pytest.mark.slow
def test_rendered_face_sequences(tmp_path):
    seqs = load_or_generate(tiny_spec("face", "train"), cache_dir=tmp_path, progress=False)
    assert seqs.images.shape == (2, 3, 64, 64, 3)
    assert seqs.structure_images.shape == (2, 3, 64, 64)
    assert seqs.points.shape[:2] == (2, 3) and seqs.points.shape[2] >= 40
    assert all(not is_test_face_clip(str(c)) for c in seqs.clip)
    # The grey structure render is black background + grey face, where the appearance render has a face.
    assert (seqs.structure_images > 0).mean() > 0.2
    pairs = make_pairs(seqs, evaluation_pair_index(seqs))
    assert pairs.ref_structures.shape == (4, 1, 64, 64)


@pytest.mark.slow
def test_train_and_evaluate_commands(tmp_path, capsys):
    ckpt = tmp_path / "tiny.safetensors"
    cache = tmp_path / "cache"
    rc = main(["train-frames", "--domain", "body", "-o", str(ckpt), "--steps", "2", "--size", "64",
               "--batch-size", "2", "--train-sequences", "2", "--cache", str(cache), "--no-progress"])
    assert rc == 0 and ckpt.is_file() and ckpt.with_name("tiny.state.safetensors").is_file()
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert report["steps"] == 2
    rc = main(["train-frames", "--domain", "body", "-o", str(ckpt), "--steps", "3", "--size", "64",
               "--batch-size", "2", "--train-sequences", "2", "--cache", str(cache), "--no-progress", "--resume"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["steps"] == 3
    out_json = tmp_path / "eval.json"
    sheet = tmp_path / "sheet.png"
    rc = main(["evaluate-frames", "--model", str(ckpt), "--json", str(out_json), "--cache", str(cache),
               "--test-sequences", "1", "--contact-sheet", str(sheet), "--no-progress"])
    assert rc == 0 and sheet.is_file()
    results = json.loads(out_json.read_text())["results"]
    assert set(results) == {"generator", "copy-reference", "limb-warp"}  # frames-body-128-v1 is 128 px
    assert all(np.isfinite(v["psnr"]) and np.isfinite(v["person_psnr"]) and v["person_sharpness"] > 0
               for v in results.values())
    # The warp generator trains and evaluates through the same commands, with the old one as a baseline.
    warp = tmp_path / "warp.safetensors"
    rc = main(["train-frames", "--domain", "body", "--model-kind", "warp", "-o", str(warp), "--steps", "2",
               "--size", "64", "--batch-size", "2", "--train-sequences", "2", "--cache", str(cache), "--no-progress"])
    assert rc == 0
    capsys.readouterr()
    rc = main(["evaluate-frames", "--model", str(warp), "--json", str(out_json), "--cache", str(cache),
               "--test-sequences", "1", "--baseline-model", str(ckpt), "--no-progress"])
    assert rc == 0
    payload = json.loads(out_json.read_text())
    assert payload["model_kind"] == "warp" and set(payload["results"]) == {"generator", "copy-reference",
                                                                            "limb-warp", "tiny"}
    assert "person_psnr_vs_tiny_2db" in payload["targets_met"]


def test_commands_refuse_bad_input(tmp_path, capsys):
    assert main(["evaluate-frames", "--model", str(tmp_path / "missing.safetensors")]) == 2
    assert "missing.safetensors" in capsys.readouterr().err
    assert main(["train-frames", "--domain", "face", "-o", str(tmp_path / "x.pt"), "--steps", "1"]) == 2
    assert main(["train-frames", "--domain", "face", "-o", str(tmp_path / "x.safetensors"), "--steps", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 2 and "error:" in err


def test_warp_settings_without_the_warp_model_are_refused_before_any_rendering(tmp_path, capsys):
    """--sample-mode / --flow-correction / --net-scale on an analogy model: one line, exit 2, and the data
    (minutes to render) is never touched: the cache folder is not even created."""
    cache = tmp_path / "cache"
    for flag in (["--sample-mode", "bicubic"], ["--flow-correction"], ["--net-scale", "2"]):
        assert main(["train-frames", "--domain", "face", "-o", str(tmp_path / "x.safetensors"), "--steps", "1",
                     "--cache", str(cache), *flag]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "settings of --model-kind warp" in err
    assert not cache.exists() and not (tmp_path / "x.safetensors").exists()


# --- evaluate-frames --poses: held-out identities posed by real mocap ----------------------------------

WALK = DATA / "mocap" / "cmu" / "08_01.bvh"  # a held-out clip of the frame data (is_test_clip)


def test_pose_windows_spread_over_the_clip():
    from motion2video.generator.poses import PoseEvalSpec, window_frames

    spec = PoseEvalSpec(windows_per_clip=3, frames_per_window=5, window_seconds=1.0)
    w = window_frames(273, 120.0, spec)
    assert w.shape == (3, 5) and w[0, 0] == 0 and w[-1, -1] == 272 and np.all(np.diff(w, axis=1) == 30)
    short = window_frames(10, 25.0, spec)  # shorter than a window: every window is the whole clip
    assert np.all(short[:, 0] == 0) and np.all(short[:, -1] == 9)


@pytest.mark.slow
def test_posed_windows_render_visible_heads():
    from motion2video.generator.poses import PoseEvalSpec, load_body_clips, render_posed_sequences

    assert is_test_clip("cmu/08_01.bvh")
    spec = PoseEvalSpec(image_size=64, windows_per_clip=2, frames_per_window=3, num_identities=2)
    posed = render_posed_sequences(load_body_clips(WALK), spec)
    seqs, heads = posed.sequences, posed.head_masks
    assert seqs.images.shape == (2, 3, 64, 64, 3) and heads.shape == seqs.masks.shape == (2, 3, 64, 64)
    assert list(seqs.identity) == [0, 1] and list(seqs.clip) == ["08_01.bvh"] * 2
    # The head is part of the silhouette, seen in every frame, small, and at its top.
    assert not np.any(heads & ~seqs.masks)
    head_px, body_px = heads.sum(axis=(2, 3)), seqs.masks.sum(axis=(2, 3))
    assert np.all(head_px > 0) and np.all(head_px < 0.3 * body_px)
    rows = np.arange(64)[None, None, :, None]
    assert np.all((rows * heads).sum(axis=(2, 3)) / head_px < (rows * seqs.masks).sum(axis=(2, 3)) / body_px)


@pytest.mark.slow
def test_evaluate_frames_posed_by_real_motion(tmp_path, capsys):
    from motion2video.generator.checkpoint import save_frame_model
    from motion2video.generator.warp import WarpGenerator, WarpGeneratorConfig

    ckpt = save_frame_model(WarpGenerator(WarpGeneratorConfig(image_size=64)), tmp_path / "warp.safetensors", step=0)
    out = tmp_path / "real.json"
    rc = main(["evaluate-frames", "--model", str(ckpt), "--poses", str(WALK), "--windows", "1", "--json", str(out),
               "--no-progress"])
    assert rc == 0
    payload = json.loads(out.read_text())
    assert payload["pairs"] == "poses" and payload["num_pairs"] == 8  # one window of 9 frames
    assert payload["poses"]["clips"] == [{"name": "08_01.bvh", "frames": 273, "fps": 120.0, "window_starts": [0]}]
    keys = {"psnr", "ssim", "person_psnr", "person_ssim", "person_sharpness", "moving_psnr", "moving_sharpness",
            "head_psnr", "head_ssim"}
    assert set(payload["results"]) == {"generator", "copy-reference", "limb-warp"}  # the 128 px v1 is left out
    for scores in payload["results"].values():
        assert set(scores) == keys and all(np.isfinite(v) for v in scores.values())
        assert 0 < scores["head_ssim"] < 1 and scores["head_psnr"] < 60
    assert set(payload["targets_met"]) == {"person_psnr_vs_limb_warp_3db", "head_psnr_vs_limb_warp_3db",
                                           "person_sharpness_0.9"}
    assert json.loads(capsys.readouterr().out[: -1].split("\nwrote")[0]) == payload


def test_evaluate_frames_poses_refuses_bad_input(tmp_path, capsys):
    from motion2video.generator.checkpoint import save_frame_model
    from motion2video.generator.warp import WarpGenerator, WarpGeneratorConfig

    ckpt = save_frame_model(WarpGenerator(WarpGeneratorConfig(image_size=32)), tmp_path / "warp.safetensors", step=0)
    repo = Path(__file__).resolve().parents[1]
    for poses, words in ((tmp_path / "missing.bvh", "no such file"), (repo / "demo_inputs" / "smile.npz", "face"),
                         (tmp_path, "no motion files")):
        assert main(["evaluate-frames", "--model", str(ckpt), "--poses", str(poses), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and words in err and str(poses) in err
    from motion2video.generator.model import FrameGenerator, FrameGeneratorConfig

    face = save_frame_model(FrameGenerator(FrameGeneratorConfig(domain="face", structure_channels=1, image_size=32,
                                                                channels=(8, 12, 16))),
                            tmp_path / "face.safetensors", step=0)
    assert main(["evaluate-frames", "--model", str(face), "--poses", str(WALK), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs a body frame model" in err and "face.safetensors" in err


@pytest.mark.slow
def test_head_masks_are_kept_beside_the_body_test_shards(tmp_path):
    """A body test split keeps the visible head of every frame beside its shards: inside the silhouettes, read
    back without rendering, and a shard without them (a cache written before they were kept) rendered again
    with the same frames; a training split keeps none unless asked."""
    from motion2video.generator.data import heads_file, load_or_generate_with_heads

    spec = tiny_spec("body", "test")
    seqs = load_or_generate(spec, cache_dir=tmp_path, progress=False)
    shards = sorted(cache_folder(tmp_path, spec).glob("shard-*.npz"))
    assert len(shards) == 2 and all(heads_file(p).is_file() for p in shards)
    rendered = load_or_generate_with_heads(spec, cache_dir=tmp_path, progress=False)
    heads = rendered.head_masks
    np.testing.assert_array_equal(rendered.sequences.images, seqs.images)
    assert heads.shape == seqs.masks.shape and heads.any(axis=(2, 3)).all() and not np.any(heads & ~seqs.masks)
    heads_file(shards[0]).unlink()
    kept = shards[1].stat().st_mtime_ns
    again = load_or_generate_with_heads(spec, cache_dir=tmp_path, progress=False)
    np.testing.assert_array_equal(again.sequences.images, seqs.images)
    np.testing.assert_array_equal(again.sequences.masks, seqs.masks)
    np.testing.assert_array_equal(again.head_masks, heads)
    assert heads_file(shards[0]).is_file() and shards[1].stat().st_mtime_ns == kept
    train = replace(spec, split="train", num_sequences=1)
    plain = load_or_generate(train, cache_dir=tmp_path, progress=False)
    assert not list(cache_folder(tmp_path, train).glob("heads-*.npz"))
    # the head masks' depth pass changes nothing of the frames
    with_heads = load_or_generate_with_heads(train, cache_dir=tmp_path / "with-heads", progress=False)
    np.testing.assert_array_equal(with_heads.sequences.images, plain.images)
    np.testing.assert_array_equal(with_heads.sequences.masks, plain.masks)
    np.testing.assert_array_equal(with_heads.sequences.points, plain.points)
    assert with_heads.head_masks.any() and not np.any(with_heads.head_masks & ~plain.masks)


@pytest.mark.slow
def test_evaluate_frames_reports_the_head_on_held_out_body_pairs(tmp_path):
    from motion2video.generator.checkpoint import save_frame_model
    from motion2video.generator.warp import WarpGenerator, WarpGeneratorConfig

    ckpt = save_frame_model(WarpGenerator(WarpGeneratorConfig(image_size=64)), tmp_path / "warp.safetensors", step=0)
    out = tmp_path / "eval.json"
    assert main(["evaluate-frames", "--model", str(ckpt), "--test-sequences", "1", "--json", str(out),
                 "--cache", str(tmp_path / "cache"), "--no-progress"]) == 0
    payload = json.loads(out.read_text())
    assert payload["pairs"] == "held-out" and payload["num_pairs"] == 8
    for scores in payload["results"].values():
        assert np.isfinite(scores["head_psnr"]) and 0 < scores["head_ssim"] < 1
    # The held-out targets, not the real-motion ones.
    assert "psnr_29db" in payload["targets_met"] and "head_psnr_vs_limb_warp_3db" not in payload["targets_met"]


def test_pose_clips_from_a_folder_pass_over_what_is_not_a_body_motion(tmp_path):
    """A folder's face motions and non-motion text files are skipped with a note; its body motions load in
    name order."""
    import shutil

    from motion2video.generator.poses import load_body_clips

    repo = Path(__file__).resolve().parents[1]
    for name in ("jump.npz", "smile.npz", "wave.npz", "reference_body.pose.npz"):
        shutil.copy(repo / "demo_inputs" / name, tmp_path / name)
    (tmp_path / "notes.txt").write_text("not a motion\n")
    skipped = []
    clips = load_body_clips(tmp_path, on_skip=lambda file, why: skipped.append(file.name))
    assert [name for name, _ in clips] == ["jump.npz", "wave.npz"]
    assert sorted(skipped) == ["notes.txt", "smile.npz"]
    assert clips[0][1].num_frames == 102 and clips[0][1].skeleton == "h36m-17"
