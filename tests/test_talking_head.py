"""evaluate-frames --video for face models: the talking-head protocol (frame 0 of a face video the reference, the
tracked later frames drive the generator, the real frames the truth) on the first two seconds of the real face video
of ../shared, with the shipped face mesh generator."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.evaluation.talking_head import (close_up_box, crop_face_motion, face_points, face_video_frames,
                                                  hull_masks)
from tests.test_pose import _cut_video

pytestmark = pytest.mark.slow  # real video decoded and tracked, the Anny head rendered: seconds each

FRAMES = 60


@pytest.fixture(autouse=True)
def private_cache(tmp_path_factory, monkeypatch):
    """The face track is cached in a temporary folder, not the user's ~/.cache."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.fixture(scope="module")
def woman_clip(shared_dir, tmp_path_factory) -> Path:
    src = shared_dir / "data" / "video" / "face_talking_woman.mp4"
    if not src.is_file():
        pytest.fail(f"shared video not found: {src}")
    return _cut_video(src, tmp_path_factory.mktemp("clip") / "woman60.avi", FRAMES)


@pytest.fixture(scope="module")
def woman_track(woman_clip):
    from motion2video.pose.face_track import track_face_video

    return track_face_video(woman_clip)


def test_hull_masks_fill_the_points_convex_hull():
    square = np.array([[[10.5, 10.5], [30.5, 10.5], [30.5, 30.5], [10.5, 30.5], [20.5, 20.5]]])
    mask = hull_masks(square, 40)[0]
    assert mask[20, 20] and mask[10, 10] and mask[30, 30] and not mask[5, 20] and not mask[20, 35]
    assert 400 <= mask.sum() <= 441  # the 21 x 21 pixel square, edges included


def test_the_rendered_head_lands_on_the_tracked_face_in_the_close_up(woman_track):
    """The fitted head posed by crop_face_motion and seen by its camera: its landmark points within 3% of the face
    size of the tracked ones (the person's own face shape, not in Anny's mesh, is most of what is left), and the
    face's centre near the square's middle, as in the training close-ups."""
    from motion2video.pose.face_anny import posed_landmarks

    rows = np.array([0, 20, 40, 59])
    box = close_up_box(woman_track, rows)
    params, camera = crop_face_motion(woman_track, rows, box, 128)
    drawn = camera.project(posed_landmarks(params[:, :52], params[:, 52:55], params[:, 55:]))[..., :2]
    tracked = (woman_track.landmarks2d[rows] - np.array(box[:2])) * 128 / box[2]
    face = np.max(tracked.max(axis=1) - tracked.min(axis=1), axis=1)
    error = np.linalg.norm(drawn - tracked, axis=2).mean(axis=1) / face
    assert (error < 0.03).all(), error
    assert (np.abs(tracked.mean(axis=1) - 64) < 20).all()
    assert (face > 40).all() and (face < 100).all()  # the face mesh's points span about half the close-up


def test_the_moved_head_is_laid_over_the_reference_frame(woman_clip, woman_track):
    """Away from the head the generated frame is the reference's picture (mesh_face_frames' plate); on the head it
    is not the reference (the head moved and changed expression by frame 58)."""
    from motion2video.evaluation.talking_head import face_pairs, mesh_face_frames
    from motion2video.generator.checkpoint import load_frame_model

    frames = face_video_frames(woman_clip, woman_track, size=128, targets=1, stride=58)
    pairs = face_pairs(frames)
    out = mesh_face_frames(load_frame_model("frames-face-mesh-128").model, pairs)
    assert out.shape == (1, 128, 128, 3)
    diff = np.abs(out[0].astype(int) - pairs.ref_images[0]).mean(axis=-1)
    corners = np.concatenate([diff[:12, :12].ravel(), diff[:12, -12:].ravel()])
    assert corners.max() <= 2
    head = hull_masks(pairs.tgt_points, 128)[0]
    assert diff[head].mean() > 4


def test_evaluate_frames_face_video_command(woman_clip, woman_track, tmp_path):
    out, sheet = tmp_path / "talking.json", tmp_path / "talking.png"
    assert main(["evaluate-frames", "--model", "frames-face-mesh-128", "--video", str(woman_clip),
                 "--video-frames", "2", "--json", str(out), "--contact-sheet", str(sheet), "--no-progress"]) == 0
    payload = json.loads(out.read_text())
    assert payload["num_frames"] == 3 and payload["frames"] == [0, 58] and payload["image_size"] == 128
    results = payload["results"]
    assert set(results) == {"generator", "copy-reference", "landmark-warp", "frames-face-128"}
    for scores in results.values():
        assert 0 <= scores["l1"] <= 1 and scores["psnr"] > 0 and np.isfinite(scores["head_psnr"])
        assert 0 <= scores["landmark_missing"] <= 1 and scores["landmark_error"] >= 0
    assert set(payload["targets_met"]) == {"l1_below_copy-reference", "l1_below_landmark-warp"}
    assert sheet.is_file()
    # copy-reference is frame 0 itself: its L1 is that of frame 0 against the two targets, its landmark error that of
    # the face points found on frame 0 against those found on the targets
    frames = face_video_frames(woman_clip, woman_track, size=128, targets=2)
    np.testing.assert_array_equal(frames.frame_index, [0, 29, 58])
    real = frames.images.astype(np.float64)
    assert results["copy-reference"]["l1"] == pytest.approx(np.abs(real[1:] - real[0]).mean() / 255, abs=1e-5)
    from motion2video.pose.facemesh import FaceMesh

    model = FaceMesh(num_threads=1)
    found = [face_points(image, model) for image in frames.images]
    size = [np.max(p.max(axis=0) - p.min(axis=0)) for p in found[1:]]
    expected = np.mean([np.linalg.norm(found[0] - p, axis=1).mean() / s for p, s in zip(found[1:], size)])
    assert results["copy-reference"]["landmark_error"] == pytest.approx(expected, abs=1e-5)
    assert results["copy-reference"]["landmark_missing"] == 0


def test_a_body_video_without_a_face_is_one_line_and_no_json(dancer_video, tmp_path, capsys):
    clip = _cut_video(dancer_video, tmp_path / "dancer20.avi", 20)
    out = tmp_path / "talking.json"
    assert main(["evaluate-frames", "--model", "frames-face-mesh-128", "--video", str(clip),
                 "--json", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "dancer20.avi" in err and "no face found" in err
    assert not out.exists()
    assert main(["evaluate-frames", "--model", "frames-face-mesh-128", "--video", str(clip),
                 "--video-start-fraction", "0.8"]) == 2
    assert "--video-start-fraction goes with body frame models" in capsys.readouterr().err
