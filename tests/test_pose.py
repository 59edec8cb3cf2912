"""Pose estimation (motion2video.pose, `motion2video pose`): BlazePose's geometry on synthetic inputs, and the
estimator on the real photos and video of ../shared."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.core.skeletons import H36M_17
from motion2video.pose import blazepose as bp
from motion2video.pose.estimate import (default_model, estimate_image, estimate_video, interpolate_gaps,
                                        landmark_extent, poses_from_landmarks, read_image_rgb)
from motion2video.pose.h36m import HEAD_PER_LEG, NECK_PER_LEG, blazepose_to_h36m, world_to_project

J = {name: i for i, name in enumerate(H36M_17.joints)}


# --- pure geometry ----------------------------------------------------------------------------------------------

def test_ssd_anchors_match_the_detector_outputs():
    anchors = bp.ssd_anchors()
    assert anchors.shape == (2254, 2)
    # stride 8: 28 x 28 cells, 2 anchors each, row-major from the top-left cell.
    np.testing.assert_allclose(anchors[0], [0.5 / 28, 0.5 / 28])
    np.testing.assert_allclose(anchors[1], anchors[0])
    np.testing.assert_allclose(anchors[2], [1.5 / 28, 0.5 / 28])
    # stride 32 (three layers share a 7 x 7 grid): 6 anchors per cell at the end.
    np.testing.assert_allclose(anchors[-6:], np.tile([[6.5 / 7, 6.5 / 7]], (6, 1)))


def test_decode_detections_puts_a_zero_offset_box_on_its_anchor():
    anchors = bp.ssd_anchors()
    raw = np.zeros((2254, 12), np.float32)
    raw[100, 2:4] = 22.4  # 0.1 of the input wide and high
    raw[100, 6:8] = [11.2, -11.2]  # keypoint 1: +0.05, -0.05
    scores = np.full(2254, -10.0, np.float32)
    scores[100] = 3.0
    boxes, s = bp.decode_detections(raw, scores, anchors)
    assert boxes.shape == (1, 12) and s[0] == pytest.approx(1 / (1 + np.exp(-3.0)))
    ax, ay = anchors[100]
    np.testing.assert_allclose(boxes[0, :4], [ax - 0.05, ay - 0.05, ax + 0.05, ay + 0.05], atol=1e-6)
    np.testing.assert_allclose(boxes[0, 4:6], [ax, ay], atol=1e-6)
    np.testing.assert_allclose(boxes[0, 6:8], [ax + 0.05, ay - 0.05], atol=1e-6)


def test_weighted_nms_merges_overlaps_by_score_and_keeps_separate_boxes():
    boxes = np.array([[0.0, 0.0, 1.0, 1.0, 5.0], [0.1, 0.0, 1.1, 1.0, 7.0], [3.0, 3.0, 4.0, 4.0, 9.0]])
    scores = np.array([0.9, 0.6, 0.7])
    out, s = bp.weighted_nms(boxes, scores)
    assert len(out) == 2
    np.testing.assert_allclose(s, [0.9, 0.7])
    np.testing.assert_allclose(out[0], (0.9 * boxes[0] + 0.6 * boxes[1]) / 1.5)
    np.testing.assert_allclose(out[1], boxes[2])


def test_roi_of_an_upright_person_is_unrotated_and_125_percent_of_twice_the_scale_distance():
    roi = bp.roi_from_points(np.array([100.0, 200.0]), np.array([100.0, 120.0]))
    assert roi.rotation == pytest.approx(0.0)
    assert roi.size == pytest.approx(2 * 80 * 1.25)
    # a person lying with the head to the right: the crop's "up" is the image's +x.
    lying = bp.roi_from_points(np.array([100.0, 200.0]), np.array([180.0, 200.0]))
    assert lying.rotation == pytest.approx(np.pi / 2)
    up_in_image = bp.roi_matrix(lying, 1)[:, :2] @ np.array([0.0, -1.0])
    np.testing.assert_allclose(up_in_image / np.linalg.norm(up_in_image), [1.0, 0.0], atol=1e-12)


def test_crop_roi_and_roi_matrix_are_the_same_map():
    image = np.zeros((300, 400, 3), np.uint8)
    cv2.circle(image, (250, 90), 4, (255, 255, 255), -1)
    roi = bp.Roi(np.array([220.0, 140.0]), 180.0, 0.6)
    crop = bp.crop_roi(image, roi)  # (256, 256, 3)
    w = crop[..., 0]
    vs, us = np.mgrid[0:256, 0:256]
    u, v = (us * w).sum() / w.sum(), (vs * w).sum() / w.sum()  # the dot's centroid in the crop
    mat = bp.roi_matrix(roi)
    back = mat[:, :2] @ np.array([u + 0.5, v + 0.5]) + mat[:, 2]
    assert np.hypot(*(back - [250.5, 90.5])) < 0.3


def _synthetic_landmarks(leg: float = 100.0) -> np.ndarray:
    """(33, 2) a front-facing person in image pixels, y down; hip to ankle = ``leg``."""
    p = np.zeros((33, 2))
    for side, x in (("left", 120.0), ("right", 80.0)):  # the person's left is the image's right
        hip, knee, ankle = {"left": (23, 25, 27), "right": (24, 26, 28)}[side]
        p[hip], p[knee], p[ankle] = (x, 300), (x, 300 + leg / 2), (x, 300 + leg)
        sh, el, wr, ear = {"left": (11, 13, 15, 7), "right": (12, 14, 16, 8)}[side]
        p[sh], p[el], p[wr] = (x + (10 if side == "left" else -10), 180), (x + 20, 240), (x + 20, 290)
        p[ear] = (x - 8 if side == "left" else x + 8, 140)
    return p


def test_blazepose_to_h36m_follows_the_canonical_definition():
    p = _synthetic_landmarks()
    joints, conf = blazepose_to_h36m(p)
    assert joints.shape == (17, 2) and conf.shape == (17,)
    np.testing.assert_allclose(joints[J["pelvis"]], [100, 300])
    np.testing.assert_allclose(joints[J["right_hip"]], p[24])  # index 1 is the RIGHT hip
    np.testing.assert_allclose(joints[J["left_wrist"]], p[15])
    np.testing.assert_allclose(joints[J["thorax"]], [100, 180])
    # neck/nose and head straight up towards the ears, 0.135 and 0.135 + 0.128 leg above the thorax.
    np.testing.assert_allclose(joints[J["neck"]], [100, 180 - NECK_PER_LEG * 100])
    np.testing.assert_allclose(joints[J["head"]], [100, 180 - (NECK_PER_LEG + HEAD_PER_LEG) * 100])
    assert 300 > joints[J["spine"], 1] > 180
    vis = np.ones(33)
    vis[27] = 0.2
    _, conf = blazepose_to_h36m(p, vis)
    assert conf[J["left_ankle"]] == pytest.approx(0.2) and conf[J["right_ankle"]] == 1.0


def test_world_landmarks_turn_z_up_without_mirroring():
    world = np.array([[0.1, -0.5, 0.2]])  # right of the hips, above them (y down), further from the camera
    np.testing.assert_allclose(world_to_project(world), [[0.1, 0.2, 0.5]])
    assert np.linalg.det(np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])) == pytest.approx(1.0)


def test_interpolate_gaps_is_linear_inside():
    values = np.array([[0.0], [9.0], [9.0], [3.0]])
    out = interpolate_gaps(values, np.array([True, False, False, True]))
    np.testing.assert_allclose(out[:, 0], [0, 1, 2, 3])


def _fake_landmarks(shift: float) -> bp.Landmarks:
    xy = np.zeros((39, 2))
    xy[:33] = _synthetic_landmarks() + shift
    world = np.zeros((39, 3))
    world[:33, :2] = (_synthetic_landmarks() - [100, 300]) / 200.0
    roi = bp.Roi(np.array([100.0, 300.0]), 300.0, 0.0)
    return bp.Landmarks(xy, np.zeros(39), np.ones(39), np.ones(39), world, 1.0, roi)


def test_poses_from_landmarks_trims_the_ends_and_interpolates_the_gaps():
    results = [None, _fake_landmarks(0), None, None, _fake_landmarks(30), None]
    pose = poses_from_landmarks(results, fps=30.0, width=640, height=480)
    assert pose.num_frames == 4 and pose.first_frame == 1 and pose.gaps == 2
    np.testing.assert_array_equal(pose.unsure, [False, True, True, False])  # the gaps are unsure frames
    np.testing.assert_allclose(pose.points2d[1:3, 0, 0], [110, 120])
    assert (pose.confidence[1:3] == 0).all() and (pose.confidence[[0, 3]] > 0).all()
    # the 3D body stands on the floor and moves sideways with the 2D pelvis.
    assert pose.joints3d[..., 2].min() >= 0.0
    assert pose.joints3d[3, 0, 0] > pose.joints3d[0, 0, 0]
    with pytest.raises(InputError, match="no person"):
        poses_from_landmarks([None, None], fps=30.0, width=10, height=10)
    with pytest.raises(InputError, match="only one frame"):
        poses_from_landmarks([None, _fake_landmarks(0), None], fps=30.0, width=10, height=10)


# --- real photos ---------------------------------------------------------------------------------------------------

def _check_plausible_body(points2d: np.ndarray, joints3d: np.ndarray) -> None:
    """A standing person: image y grows head -> thorax -> pelvis -> knees -> ankles; 3D floor at 0, height 1.2-2 m."""
    y = points2d[:, 1]
    assert y[J["head"]] < y[J["neck"]] < y[J["thorax"]] < y[J["pelvis"]]
    for side in ("left", "right"):
        assert y[J[f"{side}_hip"]] < y[J[f"{side}_knee"]] < y[J[f"{side}_ankle"]]
    lowest_ankle = joints3d[[J["left_ankle"], J["right_ankle"]], 2].min()
    assert 0.06 <= lowest_ankle < 0.15  # the floor is 7 cm under the clip's 1st-percentile lowest ankle
    assert 1.2 < joints3d[J["head"], 2] < 2.0


def test_skier_photo(photos_dir):
    image = read_image_rgb(photos_dir / "skier.jpg")
    pose = estimate_image(image)
    assert pose.people == 1 and (pose.width, pose.height) == (640, 425)
    _check_plausible_body(pose.points2d, pose.joints3d)
    # she faces the camera: her right hip is on the image's left, and every joint is in the picture.
    assert pose.points2d[J["right_hip"], 0] < pose.points2d[J["left_hip"], 0]
    assert ((pose.points2d >= 0) & (pose.points2d < [640, 425])).all()
    # the skier stands within x 280..500, y 40..400 of the picture (checked on the overlay)
    assert 280 < pose.points2d[:, 0].min() and pose.points2d[:, 0].max() < 500
    assert 40 < pose.points2d[:, 1].min() and pose.points2d[:, 1].max() < 400
    assert pose.confidence.mean() > 0.8


def test_several_people_are_chosen_largest_or_left_to_right(photos_dir):
    image = read_image_rgb(photos_dir / "three_walking.jpg")
    left = estimate_image(image, person=0)
    right = estimate_image(image, person=1)
    assert left.people >= 2
    assert left.points2d[J["pelvis"], 0] < right.points2d[J["pelvis"], 0]
    largest = estimate_image(image)
    sizes = [landmark_extent(p.landmarks) for p in (left, right)]
    assert landmark_extent(largest.landmarks) == pytest.approx(max(sizes))
    with pytest.raises(InputError, match="people found"):
        estimate_image(image, person=7)


def test_a_person_the_detector_scores_under_its_threshold_gets_a_second_look(photos_dir):
    """Her face covered by a black square twice its size, BlazePose's detector (which keys on a face) scores the
    tracksuit woman 0.49, under its threshold of 0.5; the second look finds her body where the whole photo has it."""
    from motion2video.pose.estimate import SECOND_CHANCE_SCORE

    image = read_image_rgb(photos_dir / "woman_blue_tracksuit.jpg")
    whole = estimate_image(image)
    face = whole.landmarks.xy[:11]  # BlazePose's nose, eyes, ears and mouth
    (cx, cy), r = face.mean(axis=0), 2.0 * np.ptp(face, axis=0).max()
    covered = image.copy()
    covered[int(cy - r):int(cy + r), int(cx - r):int(cx + r)] = 0
    model = default_model()
    assert not model.detect(covered) and model.detect(covered, min_score=SECOND_CHANCE_SCORE)
    with pytest.raises(InputError, match="no person"):
        estimate_image(covered, second_look=False)
    found = estimate_image(covered)
    assert found.people == 1 and found.landmarks.score >= 0.9
    height = np.ptp(whole.points2d[:, 1])
    error = np.linalg.norm(found.points2d - whole.points2d, axis=1) / height  # (17,) of her height
    # her legs, far from the square, where the whole photo has them (the square hides her neck and shoulders too)
    legs = [J[n] for n in ("left_knee", "right_knee", "left_ankle", "right_ankle")]
    hips = [J[n] for n in ("pelvis", "left_hip", "right_hip")]
    assert error[legs].max() < 0.03 and error[hips].max() < 0.07


def test_a_photo_without_a_person_is_refused():
    empty = np.full((240, 320, 3), 200, np.uint8)
    with pytest.raises(InputError, match="no person"):
        estimate_image(empty, source="blank.png")


def test_crop_person_makes_a_person_fill_a_square(photos_dir):
    from motion2video.stages.reference import ReferencePose, crop_to_person

    image = read_image_rgb(photos_dir / "man_by_truck.jpg")  # 1280 x 720, the man in the middle third
    pose = estimate_image(image)
    crop, moved, (left, top, side) = crop_to_person(image, ReferencePose("body", 1280, 720, points=pose.points2d))
    assert crop.shape == (side, side, 3) and side < 720 * 1.1
    np.testing.assert_allclose(moved.points, pose.points2d - (left, top))
    assert ((moved.points > 0.05 * side) & (moved.points < 0.95 * side)).all()
    # the crop is the image's pixels where it lies inside the image
    inside = crop[max(0, -top):, max(0, -left):][:100, :100]
    np.testing.assert_array_equal(inside, image[max(0, top):, max(0, left):][:100, :100])


def test_crop_person_takes_in_as_much_of_the_image_as_it_can(photos_dir):
    """The man of ``three_walking.jpg`` walks at the image's right edge: a square centred on him reached 278 px past
    it (a third of the picture replicated border); moved while keeping him inside, it holds the image's whole width
    and reaches past it by the 124 px its side exceeds the width by."""
    from motion2video.stages.reference import ReferencePose, crop_to_person

    image = read_image_rgb(photos_dir / "three_walking.jpg")  # 665 x 1000
    pose = estimate_image(image)
    crop, moved, (left, top, side) = crop_to_person(image, ReferencePose("body", 665, 1000, points=pose.points2d))
    assert side > 665 and left == 0  # the whole width, the border on one side only
    assert 0 <= top and top + side <= 1000  # the square fits the height: no border above or below
    assert (moved.points[:, 0] > 0.05 * side).all() and (moved.points[:, 0] < 0.95 * side).all()
    np.testing.assert_array_equal(crop[:, :665], image[top:top + side])


def test_an_estimated_reference_keeps_the_person_found_in_the_photo(photos_dir):
    """The person's mask and eyes are found once, in the photo as given, and cut and resized with it: the border
    the crop replicates below the man's shoes is never the person (segmenting the cut picture again, as the mesh
    generator did, takes those replicated pixels for him: his trousers, repeated down to the frame's edge)."""
    from motion2video.stages.generation import reference_person
    from motion2video.stages.reference import ReferencePose, crop_to_person, load_reference

    path = photos_dir / "man_by_truck.jpg"
    reference = load_reference(path, size=256, domain="body", crop_person=True)
    assert reference.person is not None
    image = read_image_rgb(path)
    _, _, (left, top, side) = crop_to_person(image, ReferencePose("body", 1280, 720,
                                                                  points=estimate_image(image).points2d))
    photo_bottom = (720 - top) / side * 256  # the photo's last row in the reference's pixels; the crop goes below
    assert photo_bottom < 254
    carried, eyes, visibility = reference.person.segmented(), reference.person.eyes, reference.person.eye_visibility
    below = int(np.ceil(photo_bottom)) + 1
    assert not carried[below:].any()
    again_found = reference_person(reference.image)
    again, eyes_again = again_found.segmented(), again_found.eyes
    assert again[below:].sum() > 20  # the replicated trousers segmented as him (56 pixels on 2026-11-26)
    above = slice(0, int(photo_bottom) - 1)
    iou = (carried[above] & again[above]).sum() / (carried[above] | again[above]).sum()
    assert iou > 0.9  # the same person where the photo is
    np.testing.assert_allclose(eyes, eyes_again, atol=3.0)
    assert carried[tuple(np.round(reference.pose.points[0, ::-1]).astype(int))]  # the pelvis is on him
    assert visibility.shape == (2,)


# --- real video --------------------------------------------------------------------------------------------------

def _cut_video(src: Path, dst: Path, frames: int, *, size: tuple[int, int] | None = None) -> Path:
    """The first ``frames`` frames of ``src`` as an MJPG .avi (optionally resized), for a fast test."""
    cap = cv2.VideoCapture(str(src))
    fps = cap.get(cv2.CAP_PROP_FPS)
    writer = None
    for _ in range(frames):
        ok, frame = cap.read()
        assert ok
        if size is not None:
            frame = cv2.resize(frame, size)
        if writer is None:
            writer = cv2.VideoWriter(str(dst), cv2.VideoWriter_fourcc(*"MJPG"), fps,
                                     (frame.shape[1], frame.shape[0]))
        writer.write(frame)
    writer.release()
    cap.release()
    return dst


@pytest.fixture(scope="module")
def dancer_clip(dancer_video, tmp_path_factory) -> Path:
    return _cut_video(dancer_video, tmp_path_factory.mktemp("clip") / "dancer40.avi", 40)


@pytest.mark.slow
def test_dancer_video_is_tracked_every_frame(dancer_clip):
    pose = estimate_video(dancer_clip)
    assert pose.num_frames == 40 and pose.fps == pytest.approx(25.0) and pose.gaps == 0
    _check_plausible_body(pose.points2d[0], pose.joints3d[0])
    # one person followed smoothly: the pelvis moves less than 8 pixels between frames (518 x 496 video)
    assert np.abs(np.diff(pose.points2d[:, J["pelvis"]], axis=0)).max() < 8.0
    # frame 0: front view, arms down (README): wrists below elbows below shoulders
    p = pose.points2d[0]
    for side in ("left", "right"):
        assert p[J[f"{side}_shoulder"], 1] < p[J[f"{side}_elbow"], 1] < p[J[f"{side}_wrist"], 1]


@pytest.mark.slow
def test_unreadable_and_one_frame_videos_are_refused(dancer_video, tmp_path):
    fake = tmp_path / "fake.mp4"
    fake.write_text("not a video")
    with pytest.raises(InputError, match="fake.mp4"):
        estimate_video(fake)
    one = _cut_video(dancer_video, tmp_path / "one.avi", 1)
    with pytest.raises(InputError, match="at least two"):
        estimate_video(one)


# --- the command ---------------------------------------------------------------------------------------------------

def test_pose_command_on_a_photo_writes_the_reference_pose_file(photos_dir, tmp_path, capsys):
    from motion2video.stages.reference import load_reference_pose

    out, overlay = tmp_path / "skier.pose.npz", tmp_path / "skier.png"
    assert main(["pose", str(photos_dir / "skier.jpg"), "-o", str(out), "--overlay", str(overlay)]) == 0
    ref = load_reference_pose(out)
    assert ref.kind == "body" and (ref.width, ref.height) == (640, 425) and ref.points.shape == (17, 2)
    # The pictured 3D pose in the camera's axes (x right, y up, z away), which the mesh generator's body fit lifts
    # the joints with: the skier stands, so her head is about a body height above her ankles.
    joints = ref.camera_joints
    assert joints.shape == (17, 3)
    assert 1.0 < joints[10, 1] - joints[[3, 6], 1].mean() < 2.0
    assert abs(joints[10, 0] - joints[0, 0]) < 0.4  # upright: the head above the pelvis
    drawn = cv2.imread(str(overlay))
    assert drawn.shape == (425, 640, 3)
    original = cv2.imread(str(photos_dir / "skier.jpg"))
    assert np.abs(drawn.astype(int) - original).max() > 100  # the skeleton is on it
    assert "found 1 person" in capsys.readouterr().out


@pytest.mark.slow
def test_pose_command_on_a_video_writes_a_motion_file(dancer_clip, tmp_path, capsys):
    from motion2video.formats.io import load_motion
    from motion2video.pose.files import load_video_pose

    out, overlay = tmp_path / "dancer.npz", tmp_path / "dancer_pose.mp4"
    assert main(["pose", str(dancer_clip), "-o", str(out), "--overlay", str(overlay)]) == 0
    motion = load_motion(out)
    assert motion.joints.shape == (40, 17, 3) and motion.fps == pytest.approx(25.0)
    pose = load_video_pose(out)
    assert pose.points2d.shape == (40, 17, 2) and pose.confidence.shape == (40, 17)
    cap = cv2.VideoCapture(str(overlay))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 40
    cap.release()
    printed = capsys.readouterr().out
    assert "0 gap frames interpolated" in printed and "no unsure frames" in printed
    assert pose.unsure.shape == (40,) and not pose.unsure.any()


@pytest.mark.parametrize("make, message", [
    (lambda d: d / "missing.jpg", "no such file"),
    (lambda d: (d / "notes.txt").write_text("x") and d / "notes.txt", "unsupported input extension"),
    (lambda d: (d / "broken.jpg").write_bytes(b"\xff\xd8 not really") and d / "broken.jpg", "cannot decode"),
    (lambda d: (d / "broken.mov").write_bytes(b"\x00" * 64) and d / "broken.mov", "broken.mov"),
    (lambda d: cv2.imwrite(str(d / "blank.png"), np.full((200, 200, 3), 255, np.uint8)) and d / "blank.png",
     "no person found"),
])
def test_pose_command_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, make, message):
    src = make(tmp_path)
    out = tmp_path / "out" / "x.npz"
    assert main(["pose", str(src), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists() and not out.parent.exists()


def test_a_broken_mp4_gives_only_the_one_line_error(tmp_path):
    """An mp4 without its index (a file cut short while it was written): libav's own "moov atom not found" is not
    printed before the one-line error. A fresh process, as a user runs it: OpenCV's FFmpeg backend reads its log
    level once."""
    broken = tmp_path / "cut.mp4"
    broken.write_bytes(b"\x00\x00\x00\x18ftypmp42\x00\x00\x00\x00mp42isom" + bytes(500))
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENCV_FFMPEG")}
    run = subprocess.run([sys.executable, "-m", "motion2video.cli", "pose", str(broken), "-o", str(tmp_path / "x.npz")],
                         capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 2
    assert run.stderr.splitlines() == [f"motion2video pose: error: {broken}: cannot read the video (not a video file, "
                                       "or an unsupported codec)"]
    assert not (tmp_path / "x.npz").exists()


def test_pose_command_checks_its_options_before_any_work(photos_dir, tmp_path, capsys):
    photo = str(photos_dir / "skier.jpg")
    assert main(["pose", photo, "-o", str(tmp_path / "x.json")]) == 2
    assert main(["pose", photo, "-o", str(tmp_path / "x.npz"), "--overlay", str(tmp_path / "x.mp4")]) == 2
    assert main(["pose", photo, "-o", str(tmp_path / "x.npz"), "--person", "tallest"]) == 2
    assert not list(tmp_path.iterdir())


def test_one_euro_smooths_noise_and_follows_fast_motion():
    from motion2video.pose.smoothing import IMAGE_LANDMARKS, one_euro, runs

    rng = np.random.default_rng(0)
    still = 100 + rng.normal(0, 1.0, (100, 1))
    out = one_euro(still, 25.0, IMAGE_LANDMARKS, scale=np.full(100, 300.0))
    assert np.std(out[50:]) < 0.6 * np.std(still[50:])
    ramp = np.arange(100, dtype=float)[:, None] * 20.0  # 20 pixels a frame: fast for a 300-pixel person
    lag = ramp - one_euro(ramp, 25.0, IMAGE_LANDMARKS, scale=np.full(100, 300.0))
    assert np.abs(lag[50:]).max() < 2.0
    assert runs(np.array([False, True, True, False, True])) == [(1, 3), (4, 5)]


@pytest.mark.slow
def test_video_smoothing_removes_jitter_not_motion(dancer_clip):
    raw = estimate_video(dancer_clip, smooth=False)
    smooth = estimate_video(dancer_clip)
    height = np.ptp(raw.points2d[:, :, 1], axis=1).mean()
    accel = lambda p: np.linalg.norm(np.diff(p, 2, axis=0), axis=-1).mean()  # noqa: E731
    assert accel(smooth.points2d) < 0.5 * accel(raw.points2d)
    assert np.linalg.norm(smooth.points2d - raw.points2d, axis=-1).mean() < 0.01 * height


def test_crop_person_keeps_the_person_and_adds_border_only_where_the_square_exceeds_the_image():
    """Any image size and any person inside it: the square holds every joint, and on each axis it reaches past the
    image only by what its side exceeds the image's (vertically: when the head room above the head and the feet
    room below the ankles lie inside the image; otherwise the person needs the border)."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from motion2video.stages.reference import ReferencePose, crop_to_person

    @settings(max_examples=200, deadline=None)
    @given(w=st.integers(40, 400), h=st.integers(40, 400), fx=st.floats(0, 1), fy=st.floats(0, 1),
           sx=st.floats(0.05, 1), sy=st.floats(0.05, 1), seed=st.integers(0, 1000))
    def check(w, h, fx, fy, sx, sy, seed):
        rng = np.random.default_rng(seed)
        bw, bh = sx * (w - 2), sy * (h - 2)
        x0, y0 = 1 + fx * (w - 2 - bw), 1 + fy * (h - 2 - bh)
        points = np.column_stack([rng.uniform(x0, x0 + bw, 17), rng.uniform(y0, y0 + bh, 17)])
        crop, moved, (left, top, side) = crop_to_person(np.zeros((h, w, 3), np.uint8),
                                                        ReferencePose("body", w, h, points=points))
        assert crop.shape == (side, side, 3)
        assert (moved.points >= 0).all() and (moved.points <= side).all()  # every joint inside the square

        def border(start: int, length: int) -> int:
            return max(0, -start) + max(0, start + side - length)

        assert border(left, w) == max(0, side - w)
        tall = np.ptp(points[:, 1])
        if points[:, 1].min() - 0.12 * tall >= 0 and points[:, 1].max() + 0.06 * tall <= h:
            assert border(top, h) == max(0, side - h)

    check()
