"""One person through a video: followed by appearance and motion past a passer-by, unsure frames reported and
stored, and a root that moves in depth when the person grows in the picture. Real BlazePose on short clips made
here from the shared video and photos."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.pose.depth import default_focal, pixels_per_metre, root_path
from motion2video.pose.follow import (FollowConfig, MotionState, appearance_distance, check_candidate,
                                      torso_histogram)


@pytest.fixture(autouse=True)
def _private_cache(tmp_path_factory, monkeypatch):
    """Pose and track caches go to a temporary folder, not the user's ~/.cache."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


def _write(path: Path, frames: list[np.ndarray], fps: float = 25.0) -> Path:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (w, h))
    for frame in frames:
        writer.write(frame)
    writer.release()
    return path


@pytest.fixture(scope="module")
def passer_by(shared_dir, tmp_path_factory) -> Path:
    """60 frames of the dancer (518 x 496) with a taller person, the red-jersey cut-out of the shared photos,
    walking in front of her from the left edge to the right one: he hides her wholly for about 15 frames."""
    cap = cv2.VideoCapture(str(shared_dir / "data" / "video" / "dancer.avi"))
    rgba = cv2.imread(str(shared_dir / "data" / "photos" / "fashion_man_red_jacket.png"), cv2.IMREAD_UNCHANGED)
    ys, xs = np.nonzero(rgba[..., 3] > 0)
    rgba = rgba[ys.min():ys.max() + 1, xs.min():xs.max() + 1]
    rgba = cv2.resize(rgba, None, fx=470 / rgba.shape[0], fy=470 / rgba.shape[0], interpolation=cv2.INTER_AREA)
    ph, pw = rgba.shape[:2]
    alpha = rgba[..., 3:].astype(np.float32) / 255.0
    frames = []
    for t in range(60):
        ok, frame = cap.read()
        assert ok
        x0, y0 = int(-pw + (518 + pw) * t / 59), 496 - ph - 5
        xa, xb = max(0, x0), min(518, x0 + pw)
        if xb > xa:
            cols = slice(xa - x0, xb - x0)
            under = frame[y0:y0 + ph, xa:xb].astype(np.float32)
            frame[y0:y0 + ph, xa:xb] = (rgba[:, cols, :3] * alpha[:, cols] + under * (1 - alpha[:, cols])).astype(np.uint8)
        frames.append(frame)
    cap.release()
    return _write(tmp_path_factory.mktemp("clips") / "passer_by.avi", frames)


WINDOW_FIRST, WINDOW_LAST = 3400.0, 1900.0  # the approach clip's view, photo pixels tall: the person grows 1.79x


@pytest.fixture(scope="module")
def approach(shared_dir, tmp_path_factory) -> Path:
    """30 frames, 360 x 480, of the tracksuit photo seen through a window that shrinks around the person: a person
    who comes towards the camera (1.79 times larger at the end), standing still in the picture's middle."""
    photo = cv2.imread(str(shared_dir / "data" / "photos" / "woman_blue_tracksuit.jpg"))  # 1080 x 1920
    cx, cy = 515.0, 1100.0
    frames = []
    for t in range(30):
        tall = WINDOW_FIRST + (WINDOW_LAST - WINDOW_FIRST) * t / 29
        wide = 0.75 * tall
        m = np.array([[360 / wide, 0, -(cx - wide / 2) * 360 / wide], [0, 480 / tall, -(cy - tall / 2) * 480 / tall]])
        frames.append(cv2.warpAffine(photo, m, (360, 480), flags=cv2.INTER_AREA, borderMode=cv2.BORDER_REPLICATE))
    return _write(tmp_path_factory.mktemp("clips") / "approach.avi", frames)


# --- the pure parts ------------------------------------------------------------------------------------------

def _body(centre=(100.0, 100.0), torso=60.0) -> np.ndarray:
    """(33, 2) landmarks with the shoulders ``torso`` px above the hips, 40 px apart."""
    xy = np.tile(np.asarray(centre, np.float64), (33, 1))
    xy[[11, 12]] = np.asarray(centre) + [[20.0, -torso], [-20.0, -torso]]
    xy[[23, 24]] = np.asarray(centre) + [[15.0, 0.0], [-15.0, 0.0]]
    return xy


def test_torso_colours_tell_two_people_apart():
    image = np.zeros((200, 300, 3), np.uint8)
    image[:, :150] = (200, 30, 30)  # a red shirt on the left
    image[:, 150:] = (20, 20, 20)  # a black one on the right
    red, black = torso_histogram(image, _body((75, 150))), torso_histogram(image, _body((225, 150)))
    assert appearance_distance(red, red) == pytest.approx(0.0, abs=1e-6)
    assert appearance_distance(red, black) > 0.9
    assert torso_histogram(image, _body((-500, -500))) is None  # a torso outside the picture has no colours


def test_a_candidate_must_be_near_the_predicted_pelvis_and_look_alike():
    image = np.zeros((200, 400, 3), np.uint8)
    image[:, :200] = (40, 40, 160)
    image[:, 200:] = (200, 30, 30)
    config = FollowConfig()
    state = MotionState.start(_body((60, 150)), torso_histogram(image, _body((60, 150))))
    step = check_candidate(image, _body((70, 150)), 0.9, state, config)
    state = state.seen(_body((70, 150)), step, config)  # moving right, 10 px a frame (5 in the velocity average)
    assert state.predicted()[0] == pytest.approx(75.0)
    near = check_candidate(image, _body((78, 150)), 0.9, state, config)
    assert near.matches and near.jump < 0.1
    far = check_candidate(image, _body((120, 150)), 0.9, state, config)  # 45 px: 0.75 torso lengths away
    assert not far.matches and not far.plausible and far.appearance < 0.1
    other = check_candidate(image, _body((280, 150)), 0.9, state, replace(config, max_jump=100.0))
    assert not other.matches and not other.plausible and other.appearance > config.max_appearance_unsure
    absent = check_candidate(image, _body((75, 150)), 0.2, state, config)
    assert not absent.matches and not absent.present
    # frames without the person widen the allowed jump: 27 px (0.45 torso lengths) from the prediction
    assert not check_candidate(image, _body((102, 150)), 0.9, state, config).matches
    assert check_candidate(image, _body((102, 150)), 0.9, state.lost().lost(), config).matches


def test_a_look_somewhat_unlike_is_plausible_and_a_lasting_one_moves_the_model():
    image = np.zeros((200, 200, 3), np.uint8)
    image[:, :] = (40, 40, 160)
    config = FollowConfig()
    state = MotionState.start(_body((100, 150)), torso_histogram(image, _body((100, 150))))
    image[:, :101] = (160, 40, 40)  # half the torso in another colour (an arm across it, another light)
    half = check_candidate(image, _body((100, 150)), 0.9, state, config)
    assert config.max_appearance < half.appearance <= config.max_appearance_unsure
    assert half.plausible and not half.matches
    for _ in range(config.reanchor_frames - 1):
        state = state.seen(_body((100, 150)), half, config)
    assert state.unlike == config.reanchor_frames - 1
    assert appearance_distance(state.appearance, half.histogram) == pytest.approx(half.appearance, abs=1e-6)
    state = state.seen(_body((100, 150)), half, config)
    assert state.unlike == 0 and appearance_distance(state.appearance, half.histogram) < 0.5 * half.appearance


def test_the_root_moves_in_depth_with_the_apparent_size():
    t = np.arange(20)
    scale = 200.0 / (4.0 - 0.1 * t)  # pixels per metre at a focal of 200 px: 4 m away, then 2.1 m
    pelvis = np.tile([160.0, 120.0], (20, 1))  # at the principal point
    path = root_path(pelvis, scale, focal=200.0, centre=np.array([160.0, 120.0]), fps=25.0)
    np.testing.assert_allclose(path[:, [0, 2]], 0.0, atol=1e-9)
    np.testing.assert_allclose(path[:, 1], 4.0 - 0.1 * t, rtol=0.02)  # the whole way, the ends too
    side = root_path(pelvis + [100.0, 0.0], np.full(20, 100.0), focal=200.0, centre=np.array([160.0, 120.0]), fps=25)
    np.testing.assert_allclose(side[:, 0], 1.0)  # 100 px right at 2 m with f = 200 px: 1 m right
    # BlazePose's world landmarks twice as far across the image plane as the pixels per metre say
    xy = np.random.default_rng(0).uniform(0, 300, (3, 33, 2))
    world = np.concatenate([(xy - 150) / 50.0, np.zeros((3, 33, 1))], axis=-1)
    np.testing.assert_allclose(pixels_per_metre(xy, world, np.ones((3, 33))), 50.0)
    assert default_focal(640, 480) == pytest.approx(320 / np.tan(np.deg2rad(30)))


# --- real video -----------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_a_passer_by_in_front_is_not_followed(passer_by, tmp_path, capsys):
    out = tmp_path / "dancer.npz"
    assert main(["pose", str(passer_by), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    with np.load(out) as data:
        pelvis, unsure, interpolated = data["joints_2d"][:, 0], data["unsure"], data["interpolated"]
    assert len(pelvis) == 60 and unsure.dtype == bool and unsure.shape == (60,)
    # the dancer stays in place (about x 250): she is followed, never the man walking across the frame
    assert np.linalg.norm(np.diff(pelvis, axis=0), axis=1).max() < 30.0
    assert np.abs(pelvis[:, 0] - pelvis[0, 0]).max() < 30.0
    # while he hides her, the frames are unsure (and interpolated), and the command says which
    hidden = np.flatnonzero(unsure)
    assert 8 <= len(hidden) <= 25 and interpolated[hidden].mean() > 0.5 and not unsure[:15].any()
    assert f"unsure of the person in {len(hidden)} frames" in printed and f"{hidden[0]}-" in printed


@pytest.mark.slow
def test_commands_that_read_a_video_say_which_frames_are_unsure(passer_by, tmp_path):
    """synthesize, transfer and sample read a video through the cached pose: its note names the unsure frames,
    estimated or read back."""
    from motion2video.stages.people import frame_ranges, video_pose

    notes: list[str] = []
    pose = video_pose(passer_by, cache=tmp_path, note=notes.append)
    again = video_pose(passer_by, cache=tmp_path, note=notes.append)
    np.testing.assert_array_equal(again.unsure, pose.unsure)
    assert pose.unsure_frames >= 8 and "estimated the pose" in notes[0] and "read from the cache" in notes[1]
    for note in notes:
        assert f"unsure of the person in {pose.unsure_frames} frames ({frame_ranges(pose.unsure)})" in note, note


@pytest.mark.slow
def test_a_person_growing_in_the_picture_comes_towards_the_camera(approach):
    from motion2video.pose.blazepose import NUM_BODY_LANDMARKS
    from motion2video.pose.estimate import estimate_video
    from motion2video.pose.track import track_video

    track = track_video(approach)
    assert track.found.all() and not track.unsure.any()
    body = slice(0, NUM_BODY_LANDMARKS)
    scale = pixels_per_metre(track.xy[:, body], track.world[:, body], track.visibility[:, body])
    growth = np.median(scale[-4:]) / np.median(scale[:4])
    expected = WINDOW_FIRST / (WINDOW_LAST + (WINDOW_FIRST - WINDOW_LAST) * 1.5 / 29)  # medians at frames 1.5, 27.5
    assert growth == pytest.approx(expected, rel=0.1)
    pose = estimate_video(approach)
    root = pose.joints3d[:, 0]
    assert root[-1, 1] - root[0, 1] < -0.8  # towards the camera (y is away from it), by most of a metre or more
    assert np.corrcoef(np.arange(30), root[:, 1])[0, 1] < -0.95  # steadily
    assert np.abs(root[:, 0] - root[0, 0]).max() < 0.15  # not sideways: the person stays in the picture's middle


def test_the_pose_cache_is_versioned(tmp_path):
    from motion2video.pose.files import POSE_VERSION, load_video_pose
    from motion2video.stages.people import cache_path, track_cache_path

    video = tmp_path / "v.avi"
    video.write_bytes(b"some bytes")
    assert cache_path(video, "largest", tmp_path).name.endswith(f".blazepose-full.v{POSE_VERSION}.npz")
    assert track_cache_path(video, "largest", tmp_path).name.endswith(f".v{POSE_VERSION}.track.npz")
    older = tmp_path / "older.npz"
    np.savez(older, joints=np.zeros((2, 17, 3)), fps=25.0)  # a pose file of the tracker before: no unsure flags
    with pytest.raises(InputError, match="older.npz"):
        load_video_pose(older)


def test_frame_ranges_name_runs_of_video_frames():
    from motion2video.stages.people import frame_ranges

    flags = np.zeros(30, bool)
    flags[[3, 10, 11, 12]] = True
    assert frame_ranges(flags) == "3, 10-12" and frame_ranges(flags, first=100) == "103, 110-112"
    assert frame_ranges(np.arange(30) % 2 == 0, most=2) == "0, 2 and 13 more runs"


def test_track_measures_find_the_jump_and_the_walk():
    from motion2video.evaluation.tracking import track_measures

    pelvis = np.stack([np.arange(10.0), np.zeros(10)], axis=1)
    pelvis[6:] += [50.0, 0.0]  # a switch to someone 50 px away at row 6
    root = np.zeros((10, 3))
    root[:, 1] = 5.0 - 0.4 * np.arange(10)  # 3.6 m towards the camera
    root[:, 0] = 0.1 * (np.arange(10) % 2)  # swaying 10 cm sideways
    m = track_measures(pelvis, root, np.arange(10) == 6)
    assert m.pelvis_max_jump_px == pytest.approx(51.0) and m.jump_frame == 6 and m.unsure_frames == 1
    assert m.depth_travel_m == pytest.approx(3.6) and m.main_direction_m == pytest.approx(3.6, abs=0.01)
    assert m.root_path_m == pytest.approx(9 * np.hypot(0.4, 0.1))
