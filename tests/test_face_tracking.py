"""Face tracking (motion2video.pose.facemesh / face_fit / face_track, `motion2video pose --face`): the detector's
and the fit's geometry, and the tracker with the bundled models on the first second of the real face videos of
../shared."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.core.motion import ARKIT_NAMES, FACE_DIM
from motion2video.pose import facemesh as fm
from motion2video.pose.face_fit import FitConfig, fit_frame, project
from tests.test_pose import _cut_video

FRAMES = 30
MAX_MEDIAN_ERROR = 0.03  # landmarks re-projected from the fitted head, in face sizes (median)


# --- pure geometry ------------------------------------------------------------------------------------------------

def test_face_anchors_match_the_detector_outputs():
    anchors = fm.face_anchors()
    assert anchors.shape == (896, 2)
    assert anchors.min() > 0 and anchors.max() < 1
    # 16 x 16 cells with 2 anchors, then 8 x 8 cells with 6 (three stride-16 layers share one grid)
    assert np.allclose(anchors[0], [0.5 / 16, 0.5 / 16]) and np.allclose(anchors[512], [0.5 / 8, 0.5 / 8])
    assert np.allclose(anchors[512:518], anchors[512])


def test_roi_of_level_eyes_is_unrotated_and_150_percent_of_the_long_side():
    roi = fm.rotated_square_roi(np.array([100.0, 50.0, 200.0, 170.0]), np.array([120.0, 90.0]),
                                np.array([180.0, 90.0]))
    assert roi.rotation == pytest.approx(0.0) and roi.size == pytest.approx(180.0)
    assert np.allclose(roi.centre, [150.0, 110.0])
    # the left eye above the right one in the image: the crop's +x axis runs from eye to eye
    tilted = fm.rotated_square_roi(np.array([0.0, 0.0, 10.0, 10.0]), np.array([0.0, 0.0]), np.array([1.0, -1.0]))
    assert tilted.rotation == pytest.approx(-np.pi / 4)
    crop_x = fm.roi_matrix(tilted, 1)[:, 0]
    assert np.allclose(crop_x / np.linalg.norm(crop_x), [np.sqrt(0.5), -np.sqrt(0.5)])


def test_fit_recovers_a_known_pose_and_expression():
    """Points projected from the Anny head with a known rotation, scale, shift and coefficients (the gaze among
    them, carried by the iris centres): the fit finds them back."""
    from motion2video.pose.face_anny import head_basis

    basis = head_basis()
    assert basis.neutral.shape == (fm.NUM_POINTS, 3) and basis.basis.shape == (52, fm.NUM_POINTS, 3)
    truth = np.zeros(len(ARKIT_NAMES))
    truth[[ARKIT_NAMES.index("jawOpen"), ARKIT_NAMES.index("eyeBlinkLeft"), ARKIT_NAMES.index("mouthSmileRight"),
           ARKIT_NAMES.index("eyeLookUpRight")]] = (0.6, 0.8, 0.5, 0.7)
    rotation = np.array([0.15, -0.05, 0.3])
    points = basis.neutral + np.tensordot(truth, basis.basis, axes=1)
    xy = project(points, rotation, 2000.0, np.array([250.0, 240.0]))
    exact = fit_frame(basis.neutral, basis.basis, xy, FitConfig(ridge=0.0), weights=FitConfig().weights())
    assert np.allclose(exact.rotation, rotation, atol=0.005)
    assert exact.scale == pytest.approx(2000.0, rel=0.005)
    assert np.abs(exact.expressions - truth).max() < 0.05
    assert np.median(exact.residual) < 0.1  # pixels, on a face about 400 pixels high
    # the default ridge shrinks the coefficients a little (most the gaze, which two points carry)
    fit = fit_frame(basis.neutral, basis.basis, xy, FitConfig(), weights=FitConfig().weights())
    assert np.allclose(fit.rotation, rotation, atol=0.01)
    assert np.abs(fit.expressions - truth).max() < 0.2


# --- the real face videos -------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def face_clips(shared_dir, tmp_path_factory) -> dict[str, Path]:
    """The first second of the two talking-head videos (``shared/data/video``)."""
    folder = tmp_path_factory.mktemp("faces")
    clips = {}
    for name in ("face_talking_woman", "face_talking_man_glasses"):
        src = shared_dir / "data" / "video" / f"{name}.mp4"
        if not src.is_file():
            pytest.fail(f"shared video not found: {src}")
        clips[name] = _cut_video(src, folder / f"{name}.avi", FRAMES)
    return clips


@pytest.fixture(scope="module")
def tracks(face_clips):
    from motion2video.pose.face_track import track_face_video

    return {name: track_face_video(path) for name, path in face_clips.items()}


@pytest.mark.slow
def test_the_eye_model_puts_both_eyelids_where_the_mesh_has_them_on_open_eyes(face_clips):
    """Frame 0 of the woman: eyes open, frontal. The eye model's lids (the left eye's crop mirrored) land within
    3 pixels of the mesh's on a face about 340 pixels high, and they are its own points, not the mesh's."""
    cap = cv2.VideoCapture(str(face_clips["face_talking_woman"]))
    ok, frame = cap.read()
    cap.release()
    assert ok
    image = cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)
    plain, refined = fm.FaceMesh(refine_eyes=False), fm.FaceMesh()
    roi = fm.detection_roi(plain.detect(image)[0])
    a, b = plain.landmarks(image, roi), refined.landmarks(image, roi)
    for contour in fm.EYE_CONTOUR_IN_MESH:
        lids = list(contour[:16])
        gap = np.linalg.norm(a.xy[lids] - b.xy[lids], axis=1)
        assert 0.1 < gap.mean() < 3.0
    others = np.setdiff1d(np.arange(468), np.concatenate([list(c) for c in fm.EYE_CONTOUR_IN_MESH]))
    np.testing.assert_array_equal(a.xy[others], b.xy[others])


@pytest.mark.slow
@pytest.mark.parametrize("name, size", [("face_talking_woman", (512, 512)), ("face_talking_man_glasses", (720, 1280))])
def test_a_talking_head_is_tracked_and_the_fitted_head_lands_on_its_landmarks(tracks, name, size):
    track = tracks[name]
    assert track.num_frames == FRAMES and track.gaps == 0 and (track.width, track.height) == size
    assert track.motion.params.shape == (FRAMES, FACE_DIM) and track.motion.fps == pytest.approx(30.0)
    assert track.landmarks2d.shape == (FRAMES, 470, 2) and (track.confidence > 0.9).all()
    # the landmarks sit on the face: inside the frame, the face a sizeable part of it (README: 0.66 and 0.36
    # of the frame height for the detector's box)
    assert (track.landmarks2d >= 0).all() and (track.landmarks2d[..., 0] < size[0]).all()
    assert 0.25 * size[1] < np.median(track.face_size()) < 0.8 * size[1]
    error = track.relative_error()
    assert np.median(error) < MAX_MEDIAN_ERROR
    assert np.median(error, axis=1).max() < 2 * MAX_MEDIAN_ERROR  # no frame far off
    # frontal heads: turned by less than 30 degrees, the coefficients in range and not all zero
    assert np.degrees(np.linalg.norm(track.motion.head_rotation, axis=1)).max() < 30
    assert track.motion.expressions.max() > 0.05
    # smooth: the head's turning speed changes by less than 1.5 degrees per frame between frames (the woman turns
    # her head at up to 3 degrees per frame in this second)
    assert np.degrees(np.abs(np.diff(track.motion.head_rotation, n=2, axis=0))).max() < 1.5


@pytest.mark.slow
def test_the_face_motion_file_is_read_by_every_face_reader_and_drawn(face_clips, tmp_path, capsys):
    from motion2video.formats.io import load_motion
    from motion2video.core.motion import FaceMotion
    from motion2video.pose.face_track import load_face_track

    out, overlay = tmp_path / "woman.npz", tmp_path / "woman_overlay.mp4"
    assert main(["pose", "--face", str(face_clips["face_talking_woman"]), "-o", str(out),
                 "--overlay", str(overlay)]) == 0
    printed = capsys.readouterr().out
    assert "30 frames at 30 fps" in printed and "% of the face size" in printed
    motion = load_motion(out)
    assert isinstance(motion, FaceMotion) and motion.params.shape == (FRAMES, FACE_DIM)
    track = load_face_track(out)
    assert np.allclose(track.motion.params, motion.params) and track.confidence.shape == (FRAMES,)
    cap = cv2.VideoCapture(str(overlay))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == FRAMES
    cap.release()
    rendered = tmp_path / "woman_face.mp4"
    assert main(["render", str(out), "--style", "face", "-o", str(rendered), "--size", "128"]) == 0
    cap = cv2.VideoCapture(str(rendered))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == FRAMES
    cap.release()


@pytest.mark.slow
def test_the_face_track_is_cached_by_the_file_hash(face_clips, tmp_path):
    from motion2video.stages.people import face_cache_path, face_video_track

    notes: list[str] = []
    first = face_video_track(face_clips["face_talking_man_glasses"], cache=tmp_path, note=notes.append)
    assert face_cache_path(face_clips["face_talking_man_glasses"], tmp_path).is_file()
    again = face_video_track(face_clips["face_talking_man_glasses"], cache=tmp_path, note=notes.append)
    assert "read from the cache" in notes[-1] and "tracked the face" in notes[0]
    assert np.allclose(first.motion.params, again.motion.params)


def _blank_video(path: Path, frames: int = 5) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (160, 120))
    for k in range(frames):
        writer.write(np.full((120, 160, 3), 180 + k, np.uint8))
    writer.release()
    return path


def test_a_video_without_a_face_is_one_line_naming_it(tmp_path, capsys):
    src = _blank_video(tmp_path / "wall.avi")
    out = tmp_path / "out" / "wall.npz"
    assert main(["pose", "--face", str(src), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "wall.avi" in err and "no face found" in err
    assert not out.exists() and not out.parent.exists()
    from motion2video.pose.face_track import track_face_video

    with pytest.raises(InputError, match="no face found in any frame"):
        track_face_video(src)


def test_face_takes_a_video_only(photos_dir, tmp_path, capsys):
    assert main(["pose", "--face", str(photos_dir / "skier.jpg"), "-o", str(tmp_path / "x.npz")]) == 2
    err = capsys.readouterr().err.strip()
    assert "--face takes a video" in err and "skier.jpg" in err
    assert main(["pose", "--face", str(photos_dir / "skier.jpg"), "--person", "1", "-o", str(tmp_path / "x.npz")]) == 2
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_a_face_video_is_the_observed_clip_of_a_face_model(face_clips, tracks, face_dir, tmp_path_factory,
                                                          monkeypatch, capsys):
    from motion2video.models.checkpoint import load_model
    from motion2video.stages.clips import load_clip
    from tests.test_pipeline import train_face_motion_model

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.mktemp("cache")))  # not the user's ~/.cache
    folder = tmp_path_factory.mktemp("face_model")
    model = train_face_motion_model(face_dir, folder)
    video = face_clips["face_talking_woman"]
    clip = load_clip(load_model(model), video)
    assert clip.source_frames == FRAMES and clip.source_fps == pytest.approx(30.0) and clip.data.shape[1] == FACE_DIM
    assert "tracked the face in face_talking_woman.avi" in capsys.readouterr().err
    # the tracked head pose and coefficients, not a procedural head track
    np.testing.assert_allclose(clip.data[0], tracks["face_talking_woman"].motion.params[0], atol=1e-5)
    out = folder / "futures.mp4"
    assert main(["sample", str(video), "--model", str(model), "--samples", "2", "-o", str(out), "--size", "64",
                 "--observed", "8", "--horizon", "8"]) == 0
    assert "read from the cache" in capsys.readouterr().err  # tracked once, by the file's hash
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 16
    cap.release()
