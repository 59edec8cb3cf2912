"""Real people through the commands: a video as the observed clip, a photo with no pose file as the
reference, --crop-person, OpenPose folders at their true rate, 2D keypoints for the 2D body model."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.models.checkpoint import load_model
from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.core.skeletons import H36M_17, OPENPOSE_18
from motion2video.pose.h36m import LEG_METRES, image_to_plane
from motion2video.stages.clips import load_clip
from tests.test_pipeline import TINY_MOTION, train_body_motion_model, train_face_motion_model
from tests.test_pose import _cut_video

pytestmark = pytest.mark.slow  # tiny models trained and real video decoded: seconds each

J = {name: i for i, name in enumerate(H36M_17.joints)}


@pytest.fixture(autouse=True)
def private_cache(tmp_path_factory, monkeypatch):
    """Pose caches go to a temporary folder, not the user's ~/.cache."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.fixture(scope="module")
def models(tmp_path_factory, mocap_dir, face_dir) -> dict[str, Path]:
    """Tiny 2-step 3D body, 2D body and face motion models (the shipped ones may predate the current skeleton)."""
    folder = tmp_path_factory.mktemp("real_inputs_ckpt")
    body = train_body_motion_model(mocap_dir, folder)
    flat = folder / "body2d.safetensors"
    assert main(["train", "--model", "mtvae-add", "--data", str(folder / "mocap"), "-o", str(flat), "--steps", "2",
                 "--config", TINY_MOTION, "--layout", "body2d", "--no-progress"]) == 0
    return {"body": body, "body2d": flat, "face": train_face_motion_model(face_dir, folder)}


@pytest.fixture(scope="module")
def dancer_clip(dancer_video, tmp_path_factory) -> Path:
    return _cut_video(dancer_video, tmp_path_factory.mktemp("clip") / "dancer80.avi", 80)


def test_image_to_plane_is_a_similarity_onto_the_floor():
    t = np.arange(3)[:, None, None]
    pts = np.zeros((3, 17, 2))
    pts[:, :, 0] = 100 + np.arange(17)[None] * 2.0 + 10 * t[..., 0]
    for side in ("right", "left"):  # vertical legs
        pts[:, [J[f"{side}_knee"], J[f"{side}_ankle"]], 0] = pts[:, [J[f"{side}_hip"]], 0]
    for side in ("right", "left"):
        pts[:, J[f"{side}_hip"], 1], pts[:, J[f"{side}_knee"], 1], pts[:, J[f"{side}_ankle"], 1] = 300, 350, 400
    pts[:, J["head"], 1], pts[:, J["pelvis"], 1] = 120, 300
    out = image_to_plane(pts)
    assert out.shape == (3, 17, 3) and np.all(out[..., 1] == 0)
    scale = LEG_METRES / 100.0  # hip -> ankle is 100 pixels
    np.testing.assert_allclose(out[1, :, 0] - out[0, :, 0], 10 * scale)  # moves right as in the image
    assert out[0, J["head"], 2] - out[0, J["pelvis"], 2] == pytest.approx(180 * scale)  # y down -> z up
    assert out[:, J["left_ankle"], 2].min() == pytest.approx(0.07)  # the floor 7 cm under the lowest ankle


def test_a_video_is_an_observed_clip_for_3d_and_2d_models(models, dancer_clip, capsys):
    bundle = load_model(models["body"])
    clip = load_clip(bundle, dancer_clip)
    assert clip.source_fps == pytest.approx(25.0) and clip.source_frames == 80
    assert clip.data.shape[1:] == (17, 3)
    assert 1.3 < clip.data[0, J["head"], 2] < 2.0  # a standing dancer, metres, z up
    assert "estimated the pose of dancer80.avi" in capsys.readouterr().err
    again = load_clip(bundle, dancer_clip)  # the second time from the cache
    np.testing.assert_array_equal(again.data, clip.data)
    assert "read from the cache" in capsys.readouterr().err
    flat = load_clip(load_model(models["body2d"]), dancer_clip)  # the 2D keypoints, on a plane facing its camera
    assert flat.data.shape == clip.data.shape and np.all(flat.data[..., 1] == 0)


def test_sample_command_with_a_video(models, dancer_clip, tmp_path, capsys):
    out = tmp_path / "futures.mp4"
    assert main(["sample", str(dancer_clip), "--model", str(models["body2d"]), "--samples", "2", "-o", str(out),
                 "--size", "128", "--observed", "8", "--horizon", "8"]) == 0
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 16
    cap.release()


def test_reference_photo_without_a_pose_file_gets_an_estimated_pose(photos_dir, tmp_path):
    from motion2video.stages.reference import load_reference

    photo = tmp_path / "skier.jpg"
    photo.write_bytes((photos_dir / "skier.jpg").read_bytes())  # no skier.pose.npz beside this copy
    ref = load_reference(photo, size=128, domain="body")
    assert ref.pose is not None and ref.pose.points.shape == (17, 2)
    assert any("estimated the person's pose" in n for n in ref.notes)
    # 640 x 425 padded to 640 x 640 and scaled by 0.2: the skier's pelvis (about x 418, y 216 in the photo)
    # lands near (84, 65) in the 128 x 128 reference
    assert np.hypot(*(ref.pose.points[J["pelvis"]] - [84, 65])) < 4
    cropped = load_reference(photo, size=128, domain="body", crop_person=True)
    assert any("cut to the person" in n for n in cropped.notes)
    span = np.ptp(cropped.pose.points, axis=0).max()
    assert span > 1.5 * np.ptp(ref.pose.points, axis=0).max()  # the person fills more of the frame
    with pytest.raises(InputError, match="crop-person"):
        load_reference(photo, size=128, domain="face", crop_person=True)


def _write_openpose(folder: Path, frames: int) -> None:
    folder.mkdir()
    rng = np.random.default_rng(0)
    base = np.stack([np.arange(18) * 5.0 + 100, np.arange(18) * 9.0 + 50], axis=1)
    for t in range(frames):
        kp = np.concatenate([base + rng.normal(0, 1, base.shape), np.full((18, 1), 0.9)], axis=1)
        people = [{"person_id": [-1], "pose_keypoints_2d": kp.reshape(-1).tolist()}]
        (folder / f"clip_{t:012d}_keypoints.json").write_text(json.dumps({"version": 1.3, "people": people}))


def test_render_reads_an_openpose_folder_at_its_true_fps(tmp_path):
    assert OPENPOSE_18.num_joints == 18
    folder = tmp_path / "op"
    _write_openpose(folder, 20)
    out = tmp_path / "op.mp4"
    assert main(["render", str(folder), "-o", str(out), "--fps", "50", "--size", "64", "--no-progress"]) == 0
    cap = cv2.VideoCapture(str(out))
    # 20 frames at their true 50 fps: 20 frames (read at 25 fps and resampled, it would be 39)
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 20 and cap.get(cv2.CAP_PROP_FPS) == pytest.approx(50)
    cap.release()


def test_2d_keypoints_go_to_the_2d_model_and_are_refused_by_3d_models(models, tmp_path):
    folder = tmp_path / "op"
    _write_openpose(folder, 70)
    clip = load_clip(load_model(models["body2d"]), folder)
    assert clip.data.shape[1:] == (17, 3)
    with pytest.raises(InputError, match="2D model"):
        load_clip(load_model(models["body"]), folder / "clip_000000000000_keypoints.json")


def test_sample_reads_an_openpose_folder_at_its_true_fps(models, tmp_path):
    from motion2video.stages.clips import load_clip

    folder = tmp_path / "op"
    _write_openpose(folder, 100)
    bundle = load_model(models["body2d"])
    at_25 = load_clip(bundle, folder)
    at_50 = load_clip(bundle, folder, fps=50.0)
    assert at_25.source_fps == 25.0 and at_50.source_fps == 50.0
    assert at_50.num_frames < 0.6 * at_25.num_frames  # the same 100 frames last half as long
    out = tmp_path / "op.mp4"
    assert main(["sample", str(folder), "--model", str(models["body2d"]), "--fps", "50", "--samples", "1",
                 "--observed", "8", "--horizon", "4", "--size", "64", "-o", str(out)]) == 0
