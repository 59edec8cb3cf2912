"""npz, OpenPose JSON, VideoPose3D, Live Link Face CSV and the load_motion / save_motion dispatcher."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from motion2video.core import atomic
from motion2video.core.errors import InputError
from motion2video.formats import face_csv, npz, openpose, videopose3d
from motion2video.formats.io import load_motion, save_motion
from motion2video.core.motion import ARKIT_NAMES, FACE_DIM, FaceMotion, Motion
from motion2video.core.skeletons import BODY_25, H36M_32_TO_17, OPENPOSE_18, convert_openpose_to_h36m

FACE_FILES = ["livelinkface/S07-001.csv", "livelinkface/S88-001.csv", "livelinkface/alex_rom_3.csv",
              "livelinkface/alex_rom_4.csv", "livelinkface/apfel.csv", "llv/dao.csv"]


def _one_line(err: pytest.ExceptionInfo, path) -> None:
    text = str(err.value)
    assert "\n" not in text and str(path) in text


def _motion(frames: int = 6, dim: int = 3) -> Motion:
    joints = np.random.default_rng(1).normal(size=(frames, 17, dim)).astype(np.float32)
    return Motion(joints, 30.0, "h36m-17", None, "walk")


# --- npz --------------------------------------------------------------------------------------------------

def test_body_npz_round_trip(tmp_path):
    m = _motion()
    path = save_motion(m, tmp_path / "sub" / "clip.npz")
    assert sorted(os.listdir(path.parent)) == ["clip.npz"]  # no temporary file left behind
    back = load_motion(path)
    assert isinstance(back, Motion)
    np.testing.assert_array_equal(back.joints, m.joints)
    assert (back.fps, back.skeleton, back.label, back.source) == (30.0, "h36m-17", "walk", str(path))
    m2 = Motion(m.joints[..., :2], 25.0, "h36m-17")  # 2D, no label
    back2 = load_motion(save_motion(m2, tmp_path / "clip2d.npz"))
    assert back2.dim == 2 and back2.label is None and back2.fps == 25.0


def test_face_npz_round_trip(tmp_path):
    params = np.random.default_rng(2).uniform(size=(5, FACE_DIM)).astype(np.float32)
    f = FaceMotion(params, 60.0, {"age": 0.3, "gender": 0.9}, None, "talk")
    back = load_motion(save_motion(f, tmp_path / "face.npz"))
    assert isinstance(back, FaceMotion)
    np.testing.assert_array_equal(back.params, f.params)
    assert back.identity == {"age": 0.3, "gender": 0.9} and back.fps == 60.0 and back.label == "talk"


def test_overwrite_is_atomic_and_keeps_the_old_file_on_failure(tmp_path):
    path = save_motion(_motion(), tmp_path / "clip.npz")
    before = path.read_bytes()
    unpicklable = np.array([lambda: None], dtype=object)  # np.savez fails while writing it
    with pytest.raises(Exception, match="pickle|lambda"):
        atomic.save_npz(path, {"joints": unpicklable})
    assert path.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["clip.npz"]  # the temporary file was removed


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        ({"joints": np.full((4, 17, 3), np.nan, np.float32), "fps": 30.0, "skeleton": "h36m-17"}, "NaN"),
        ({"joints": np.zeros((4, 17, 4), np.float32), "fps": 30.0, "skeleton": "h36m-17"}, "shape"),
        ({"joints": np.zeros((4, 12, 3), np.float32), "fps": 30.0, "skeleton": "h36m-17"}, "17 joints"),
        ({"joints": np.zeros((0, 17, 3), np.float32), "fps": 30.0, "skeleton": "h36m-17"}, "empty"),
        ({"joints": np.zeros((4, 17, 3), np.float32), "fps": 0.0, "skeleton": "h36m-17"}, "fps must be"),
        ({"joints": np.zeros((4, 17, 3), np.float32), "fps": -25.0, "skeleton": "h36m-17"}, "fps must be"),
        ({"joints": np.zeros((4, 17, 3), np.float32), "skeleton": "h36m-17"}, "lacks key(s) fps"),
        ({"joints": np.zeros((4, 17, 3), np.float32), "fps": 30.0, "skeleton": "smpl"}, "unknown skeleton"),
        ({"joints": np.array(["a"]), "fps": 30.0, "skeleton": "h36m-17"}, "numeric"),
        ({"face": np.zeros((4, 57), np.float32), "fps": 30.0, "identity": "{}"}, "shape (T, 58)"),
        ({"face": np.zeros((4, 58), np.float32), "fps": 30.0, "identity": "[1"}, "not valid JSON"),
        ({"face": np.full((4, 58), np.inf, np.float32), "fps": 30.0, "identity": "{}"}, "NaN or Inf"),
        ({"something": np.zeros(3)}, "expected joints of shape (T, J, 3)"),  # one array: a joint array
        ({"something": np.zeros(3), "else": np.zeros(3)}, "unknown .npz layout"),
    ],
)
def test_bad_npz_raises_input_error(tmp_path, arrays, message):
    path = tmp_path / "bad.npz"
    np.savez(path, **arrays)
    with pytest.raises(InputError) as err:
        load_motion(path)
    assert message in str(err.value)
    _one_line(err, path)


def test_pickled_npz_and_non_archives_are_refused(tmp_path):
    path = tmp_path / "obj.npz"
    np.savez(path, joints=np.array([{"a": 1}], dtype=object), fps=30.0, skeleton="h36m-17")
    with pytest.raises(InputError, match="without pickles"):
        npz.load_motion_npz(path)
    text = tmp_path / "text.npz"
    text.write_text("not a zip")
    with pytest.raises(InputError, match="not an .npz archive"):
        load_motion(text)


# --- load_motion dispatch ---------------------------------------------------------------------------------

def test_missing_file_unknown_extension_and_bad_rates(tmp_path):
    with pytest.raises(InputError, match="no such file") as err:
        load_motion(tmp_path / "nope.bvh")
    _one_line(err, tmp_path / "nope.bvh")
    other = tmp_path / "clip.xyz"
    other.write_text("1 2 3")
    with pytest.raises(InputError, match="unknown motion file extension") as err:
        load_motion(other)
    _one_line(err, other)
    text = tmp_path / "clip.txt"  # a .txt that is not DeepMimic JSON is read as exp-map text, which needs a layout
    text.write_text("1 2 3")
    with pytest.raises(InputError, match="no exp-map layout file") as err:
        load_motion(text)
    _one_line(err, text)
    path = save_motion(_motion(), tmp_path / "m.npz")
    for kwargs in ({"fps": 0}, {"fps": -1}, {"target_fps": 0}, {"fps": float("nan")}):
        with pytest.raises(InputError, match="must be a positive number"):
            load_motion(path, **kwargs)
    with pytest.raises(InputError, match=r"written as \.npz"):
        save_motion(_motion(), tmp_path / "m.bvh")


def test_load_motion_fps_override_and_resampling(tmp_path):
    m = Motion(np.linspace(0, 1, 31)[:, None, None] * np.ones((1, 17, 3)), 30.0)  # linear ramp, 1 s
    path = save_motion(m, tmp_path / "ramp.npz")
    assert load_motion(path, fps=60).fps == 60.0
    r = load_motion(path, target_fps=10)
    assert r.fps == 10.0 and r.num_frames == 11
    np.testing.assert_allclose(r.joints[:, 0, 0], np.linspace(0, 1, 11), atol=1e-6)


def test_load_motion_bvh_uses_the_manifest(mocap_dir):
    m = load_motion(mocap_dir / "cmu/16_02.bvh")
    assert m.fps == 120.0 and m.label.startswith("jump") and m.num_frames == 466
    daz = load_motion(mocap_dir / "cmu/07_01.bvh", target_fps=30)
    assert daz.fps == 30.0 and daz.num_frames == (317 - 5 - 1) // 4 + 1


# --- OpenPose ---------------------------------------------------------------------------------------------

def _write_openpose(folder, frames: list[np.ndarray | None]) -> None:
    folder.mkdir()
    for t, kp in enumerate(frames):
        people = [] if kp is None else [{"person_id": [-1], "pose_keypoints_2d": kp.reshape(-1).tolist()}]
        (folder / f"clip_{t:012d}_keypoints.json").write_text(json.dumps({"version": 1.3, "people": people}))


def _keypoints(skeleton, t: int) -> np.ndarray:
    """(K, 3) keypoints moving right by 10 px per frame; confidence 0.9."""
    k = skeleton.num_joints
    xy = np.stack([np.arange(k) * 5.0 + 10.0 * t, np.arange(k) * 7.0 + 100.0], axis=1)
    return np.concatenate([xy, np.full((k, 1), 0.9)], axis=1)


@pytest.mark.parametrize("skeleton", [OPENPOSE_18, BODY_25])
def test_openpose_folder_with_gaps(tmp_path, skeleton):
    frames = [_keypoints(skeleton, t) for t in range(5)]
    frames[2] = None  # nobody detected
    lost = skeleton.index("left_wrist")
    frames[3][lost] = 0.0  # undetected keypoint: 0, 0, 0
    folder = tmp_path / "op"
    _write_openpose(folder, frames)
    m = load_motion(folder)
    assert m.dim == 2 and m.num_frames == 5 and m.fps == 25.0 and m.skeleton == "h36m-17"
    full = [_keypoints(skeleton, t) for t in range(5)]
    expected = convert_openpose_to_h36m(np.stack(full)[..., :2], skeleton)
    np.testing.assert_allclose(m.joints, expected, atol=1e-4)  # linear motion: interpolation is exact
    assert openpose.load_openpose_folder(folder, fps=12.5).fps == 12.5


def test_openpose_errors(tmp_path):
    never = [_keypoints(OPENPOSE_18, t) for t in range(3)]
    for f in never:
        f[OPENPOSE_18.index("right_knee")] = 0.0
    _write_openpose(tmp_path / "never", never)
    with pytest.raises(InputError, match="never detected: right_knee"):
        load_motion(tmp_path / "never")
    _write_openpose(tmp_path / "empty", [None, None])
    with pytest.raises(InputError, match="no person detected"):
        load_motion(tmp_path / "empty")
    (tmp_path / "nothing").mkdir()
    with pytest.raises(InputError, match="no OpenPose"):
        load_motion(tmp_path / "nothing")
    odd = tmp_path / "odd"
    odd.mkdir()
    (odd / "a_keypoints.json").write_text(json.dumps({"people": [{"pose_keypoints_2d": [1.0] * 30}]}))
    with pytest.raises(InputError, match="30 values"):
        load_motion(odd)


# --- VideoPose3D ------------------------------------------------------------------------------------------

def test_videopose3d_layout(tmp_path):
    rng = np.random.default_rng(3)
    positions = {
        "S1": {"Walking 1": rng.normal(size=(8, 32, 3)), "Eating": rng.normal(size=(4, 32, 3))},
        "S9": {"Walking 1": rng.normal(size=(6, 32, 3)).astype(np.float32)},
    }
    path = tmp_path / "data_3d_h36m.npz"
    np.savez_compressed(path, positions_3d=positions)  # the layout VideoPose3D writes (a pickled dict)
    clips = videopose3d.load_videopose3d(path)
    assert [(c.source.split("#")[1], c.num_frames) for c in clips] == [
        ("S1/Eating", 4), ("S1/Walking 1", 8), ("S9/Walking 1", 6)]
    assert all(c.fps == 50.0 and c.skeleton == "h36m-17" for c in clips)
    np.testing.assert_allclose(clips[1].joints, positions["S1"]["Walking 1"][:, list(H36M_32_TO_17)], atol=1e-6)
    walking = videopose3d.load_videopose3d(path, action="Walking 1")
    assert len(walking) == 2 and all(c.label == "Walking 1" for c in walking)
    assert len(videopose3d.load_videopose3d(path, subject="S9")) == 1
    with pytest.raises(InputError, match="no clip matches"):
        videopose3d.load_videopose3d(path, subject="S5")
    with pytest.raises(InputError, match="holds 3 clips"):
        load_motion(path)
    single = tmp_path / "single.npz"
    np.savez(single, positions_3d={"S11": {"Sitting": positions["S1"]["Eating"]}})
    assert load_motion(single).label == "Sitting"


def test_videopose3d_bad_shapes(tmp_path):
    path = tmp_path / "bad.npz"
    np.savez(path, positions_3d={"S1": {"Walk": np.zeros((5, 17, 3))}})
    with pytest.raises(InputError, match=r"S1/Walk: expected a \(T, 32, 3\)"):
        videopose3d.load_videopose3d(path)
    np.savez(path, other=np.zeros(3))
    with pytest.raises(InputError, match="no 'positions_3d' key"):
        videopose3d.load_videopose3d(path)


# --- Live Link Face CSV -----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def faces(face_dir) -> dict[str, tuple[face_csv.FaceCsv, FaceMotion]]:
    return {name: (face_csv.read_face_csv(face_dir / name), face_csv.load_face_csv(face_dir / name))
            for name in FACE_FILES}


@pytest.mark.parametrize("name", FACE_FILES)
def test_real_face_captures_load(faces, name):
    raw, face = faces[name]
    assert face.params.shape[1] == FACE_DIM
    assert 0.0 <= face.expressions.min() and face.expressions.max() <= 1.0
    assert np.all(face.head_translation == 0)
    # Uniform grid over the capture: one frame per row plus the frames the capture dropped.
    assert face.num_frames >= raw.num_rows
    assert face.num_frames == pytest.approx(raw.times[-1] * face.fps + 1, abs=0.51)
    expected_fps = 60.0 if name.startswith("llv/") else 30.0
    assert face.fps == expected_fps and raw.fps == expected_fps
    assert face.label  # from the face manifest's "content"
    assert face.expressions.std(axis=0).max() > 0.05  # it moves


def test_tracking_lost_rows_are_interpolated(faces):
    raw, face = faces["livelinkface/S88-001.csv"]
    assert raw.num_lost == 277
    assert faces["livelinkface/apfel.csv"][0].num_lost == 35
    lost = ~raw.valid
    assert np.all(np.isnan(raw.blendshapes[lost]))
    # Lost rows become the straight line between the valid rows around them (not a neutral face).
    first = int(np.argmax(lost))
    end = first + int(np.argmax(~lost[first:]))  # first valid row after the gap
    before, after = raw.blendshapes[first - 1], raw.blendshapes[end]
    t0, t1 = raw.times[first - 1], raw.times[end]
    mid = first + (end - first) // 2
    k = int(round(raw.times[mid] * face.fps))
    w = (raw.times[mid] - t0) / (t1 - t0)
    expected = np.clip(before + w * (after - before), 0, 1)
    np.testing.assert_allclose(face.expressions[k], expected, atol=0.02)
    assert face.expressions[k].sum() > 0.5


def test_head_rotation_only_in_dao(faces):
    _, dao = faces["llv/dao.csv"]
    assert np.abs(dao.head_rotation).max() > 0.2  # radians, a real head turn
    assert np.abs(dao.head_rotation).max() < 1.0
    _, s07 = faces["livelinkface/S07-001.csv"]
    assert np.all(s07.head_rotation == 0)


def test_blendshape_columns_matched_case_insensitively(faces, face_dir):
    raw, _ = faces["llv/dao.csv"]
    header = (face_dir / "llv/dao.csv").read_text().splitlines()[0].split(",")
    first = (face_dir / "llv/dao.csv").read_text().splitlines()[1].split(",")
    column = {h.lower(): i for i, h in enumerate(header)}
    for k in (0, 24, 51):  # browDownLeft, jawOpen, tongueOut
        assert raw.blendshapes[0, k] == pytest.approx(float(first[column[ARKIT_NAMES[k].lower()]]))


def test_head_ypr_mapping():
    small = np.array([[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]])
    aa = face_csv.head_ypr_to_axis_angle(small)
    np.testing.assert_allclose(aa, [[0, 0, 0.01], [0.01, 0, 0], [0, -0.01, 0]], atol=1e-9)
    # Composition: Rz(90) @ Rx(90) maps x -> y -> z -> x, a 120 deg rotation about (1, 1, 1) / sqrt(3).
    aa = face_csv.head_ypr_to_axis_angle(np.array([[np.pi / 2, np.pi / 2, 0.0]]))[0]
    np.testing.assert_allclose(aa, 2 * np.pi / 3 * np.array([1, 1, 1]) / np.sqrt(3), atol=1e-9)
    assert np.all(face_csv.head_ypr_to_axis_angle(np.zeros((2, 3))) == 0)


def test_bad_face_csv(tmp_path):
    path = tmp_path / "face.csv"
    path.write_text("Timecode,BlendShapeCount,EyeBlinkLeft\n00:00:00:00.000,1,0.5\n")
    with pytest.raises(InputError, match="missing blendshape column"):
        load_motion(path)
    header = "Timecode,BlendShapeCount," + ",".join(n[0].upper() + n[1:] for n in ARKIT_NAMES)
    path.write_text(header + "\n00:00:00:00.000,0\n00:00:00:02.000,0\n")
    with pytest.raises(InputError, match="tracking is lost on every row"):
        load_motion(path)
    path.write_text(header + "\n")
    with pytest.raises(InputError, match="no data rows"):
        load_motion(path)
    row = ",".join(["0.5"] * 52)
    path.write_text(header + f"\n00:00:00:00.000,52,{row}\n00:00:00:02.000,52,{row.replace('0.5', 'x', 1)}\n")
    with pytest.raises(InputError, match="line 3"):
        load_motion(path)
    # Without timecodes and without a manifest the rate is unknown unless given.
    path.write_text("BlendShapeCount," + header.split(",", 2)[2] + f"\n52,{row}\n52,{row}\n")
    with pytest.raises(InputError, match="pass fps"):
        load_motion(path)
    assert load_motion(path, fps=30).num_frames == 2
