"""evaluate-frames --video: the reconstruction protocol (frame 0 the reference, later frames the truth) on the
real dancer video."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.evaluation.reconstruction import keypoint_distance, video_frames, video_pairs
from tests.test_pipeline import train_frame_model
from tests.test_pose import _cut_video


pytestmark = pytest.mark.slow  # real video decoded and a tiny generator trained: seconds each


@pytest.fixture(autouse=True)
def private_cache(tmp_path_factory, monkeypatch):
    """The video's track is cached in a temporary folder, not the user's ~/.cache."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.fixture(scope="module")
def dancer_clip(dancer_video, tmp_path_factory) -> Path:
    return _cut_video(dancer_video, tmp_path_factory.mktemp("clip") / "dancer120.avi", 120)


def test_video_frames_are_the_person_square_with_masks_and_joints(dancer_clip):
    frames = video_frames(dancer_clip, size=96, targets=4)
    assert frames.images.shape == (5, 96, 96, 3) and frames.points.shape == (5, 17, 2)
    np.testing.assert_array_equal(frames.frame_index, [0, 29, 58, 87, 116])
    assert frames.skipped == 0
    # the dancer fills the square: joints inside it, the mask covers 5-40% of it and holds the pelvis
    assert ((frames.points > 0) & (frames.points < 96)).all()
    cover = frames.masks.mean(axis=(1, 2))
    assert ((cover > 0.05) & (cover < 0.4)).all()
    px, py = np.round(frames.points[:, 0]).astype(int).T
    assert frames.masks[np.arange(5), py, px].all()
    pairs = video_pairs(frames)
    assert len(pairs) == 4 and (pairs.ref_images == frames.images[0]).all()


def test_akd_of_the_real_frames_against_themselves_is_small(dancer_clip):
    frames = video_frames(dancer_clip, size=128, targets=3)
    akd, missing = keypoint_distance(frames.images, frames.points)
    assert missing == 0 and akd < 2.0  # pixels at 128: single-image estimates vs tracked ones


def test_evaluate_frames_video_command(dancer_clip, tmp_path, capsys):
    model = train_frame_model("body", tmp_path)
    out = tmp_path / "eval.json"
    assert main(["evaluate-frames", "--model", str(model), "--video", str(dancer_clip), "--video-frames", "3",
                 "--json", str(out)]) == 0
    payload = json.loads(out.read_text())
    assert payload["num_frames"] == 4 and payload["person_mask"] == "BlazePose segmentation"
    results = payload["results"]
    assert set(results) == {"generator", "copy-reference", "limb-warp"}
    for scores in results.values():
        assert 0 <= scores["l1"] <= 1 and scores["person_psnr"] > 0 and 0 <= scores["akd_missing"] <= 1
        assert np.isfinite(scores["head_psnr"]) and np.isfinite(scores["head_ssim"])
    # copy-reference is frame 0 itself: BlazePose finds the dancer in it, at her frame-0 pose
    assert results["copy-reference"]["akd_missing"] == 0 and results["copy-reference"]["akd"] > 0
    assert main(["evaluate-frames", "--model", str(model), "--video", str(tmp_path / "nope.mp4")]) == 2
    assert "no such video file" in capsys.readouterr().err


def test_head_box_is_a_square_around_the_head_and_neck_joints():
    from motion2video.evaluation.reconstruction import head_box_masks

    points = np.zeros((2, 17, 2))
    points[:, 8] = (50, 60)  # thorax
    points[:, 9] = (50, 50)  # neck/nose
    points[:, 10] = (50, 40)  # head
    points[1] += (45, -35)  # the second frame's head leaves the top-right corner: the square is clipped
    boxes = head_box_masks(points, 100)
    ys, xs = np.nonzero(boxes[0])
    assert (xs.min(), xs.max(), ys.min(), ys.max()) == (38, 61, 33, 56)  # 24 px = 1.2 x thorax-to-head, centred
    assert boxes[0].sum() == 24 * 24 and 0 < boxes[1].sum() < 24 * 24


def test_the_mesh_generators_reconstruction_has_head_metrics(dancer_clip, tmp_path):
    """The mesh generator in the protocol (its frames composited over frame 0's inpainted background): every method
    has finite head PSNR and SSIM over the truth frame's head square."""
    out = tmp_path / "eval.json"
    assert main(["evaluate-frames", "--model", "frames-body-mesh-128", "--video", str(dancer_clip),
                 "--video-frames", "3", "--json", str(out), "--no-progress"]) == 0
    results = json.loads(out.read_text())["results"]
    assert {"generator", "copy-reference", "limb-warp"} <= set(results)
    for name, scores in results.items():
        assert np.isfinite(scores["head_psnr"]) and 5 < scores["head_psnr"] < 60, name
        assert np.isfinite(scores["head_ssim"]) and -1 <= scores["head_ssim"] <= 1, name
    assert results["generator"]["person_psnr"] > 15


def test_the_mesh_generator_lays_frame_0s_face_over_its_heads(dancer_clip):
    """The protocol draws the mesh generator's frames as synthesize does: the face found in frame 0 (the reference)
    is laid over each generated head. It changes pixels only around the truth's head (its square grown by a
    quarter), and a target whose head turns away from frame 0's view is the generator's own frame."""
    from dataclasses import replace

    import cv2

    from motion2video.evaluation.reconstruction import head_box_masks, with_mesh
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.generator.scores import run_generator

    def grown(box: np.ndarray) -> np.ndarray:  # a head square grown by a quarter of its side each way
        side = int(np.sqrt(box.sum()))
        return cv2.dilate(box.astype(np.uint8), np.ones((side // 4 * 2 + 1,) * 2, np.uint8)) > 0

    frames = video_frames(dancer_clip, size=128, targets=4)
    pairs = with_mesh(video_pairs(frames), frames)
    assert pairs.head_mattes is not None and pairs.head_mattes.shape == (4, 128, 128)
    head0 = grown(head_box_masks(frames.points[:1], 128)[0])
    assert pairs.head_mattes[0].max() > 0.9 and pairs.head_mattes[0][~head0].max() < 0.01  # her face, at her head
    assert ((pairs.head_weights >= 0) & (pairs.head_weights <= 1)).all() and pairs.head_weights.max() > 0.9
    net = load_frame_model("frames-body-mesh-128").model
    with_face = run_generator(net, pairs)
    without = run_generator(net, replace(pairs, head_mattes=None, head_affines=None, head_weights=None))
    heads = head_box_masks(pairs.tgt_points, 128)
    for i, weight in enumerate(pairs.head_weights):
        changed = np.any(with_face[i] != without[i], axis=-1)
        if weight == 0:
            assert not changed.any()
            continue
        assert changed.any() and not (changed & ~grown(heads[i])).any()


def test_the_mesh_generator_draws_no_halo_around_her_head(dancer_clip):
    """The fitted body's grown silhouette reaches past the dancer's slim head; where its flow lands beside the
    pictured head the pixel is background (mesh_warp.head_cut). Next to her head (the head square, outside her
    truth mask grown by a pixel), under 20% of the generated pixels differ from the real frame by more than 30 grey
    levels (0-13%: 3 of 23 pixels in one frame, where her head's hidden side, completed from her hair's core, is
    darker than the blue-fringed outline it took before; without the cut 86-90%: a halo of face and hair colours)."""
    import cv2

    from motion2video.evaluation.reconstruction import head_box_masks, with_mesh
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.generator.scores import run_generator

    frames = video_frames(dancer_clip, size=128, targets=4)
    pairs = with_mesh(video_pairs(frames), frames)
    pred = run_generator(load_frame_model("frames-body-mesh-128").model, pairs)
    heads = head_box_masks(pairs.tgt_points, 128)
    for i in range(len(pred)):
        person = cv2.dilate(pairs.tgt_masks[i].astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
        beside = heads[i] & ~person
        error = np.abs(pred[i].astype(np.float64) - pairs.tgt_images[i]).mean(axis=-1)
        assert beside.sum() > 10 and (error[beside] > 30).mean() < 0.2
