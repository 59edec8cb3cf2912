"""Procedural body motion (FK primitives), procedural face dynamics and the committed demo inputs."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from motion2video.data.face_dynamics import FACE_MODES, FaceModeSpec, generate_face, head_pose_track
from motion2video.core.rotations import (
    axis_angle_to_matrix, head_euler_to_axis_angle, head_euler_to_matrix, matrix_to_axis_angle,
)
from motion2video.data.procedural import (
    MODES, TURN_RATE, BodyParams, ModeSpec, forward_kinematics, generate, leg_ik, mirror_euler, rest_offsets,
)
from motion2video.core.rotations import euler_to_matrix, heading_of
from motion2video.core.errors import InputError
from motion2video.formats.npz import load_face_npz, load_motion_npz
from motion2video.core.motion import ARKIT_NAMES, FaceMotion, Motion
from motion2video.core.skeletons import H36M_17

REPO = Path(__file__).resolve().parents[1]
R_HIP, R_ANKLE, L_HIP, L_ANKLE, THORAX, NOSE, HEAD = 1, 3, 4, 6, 8, 9, 10
L_SHOULDER, R_SHOULDER, L_WRIST, R_WRIST = 11, 14, 13, 16
ALL_MODES = [(m, 1.2) for m in MODES]


def _bone_lengths(joints: np.ndarray) -> np.ndarray:
    bones = np.array(H36M_17.bones)
    return np.linalg.norm(joints[:, bones[:, 1]] - joints[:, bones[:, 0]], axis=-1)  # (T, 16)


def _lowest_ankle(joints: np.ndarray) -> np.ndarray:
    return joints[:, [R_ANKLE, L_ANKLE], 2].min(axis=1)


# --- body -------------------------------------------------------------------------------------------------

def test_generate_shapes_label_and_determinism():
    motion = generate([("walk", 1.0), ("run", 1.0)], seed=3)
    assert isinstance(motion, Motion)
    assert motion.joints.shape == (50, 17, 3) and motion.joints.dtype == np.float32
    assert motion.skeleton == "h36m-17" and motion.fps == 25.0 and motion.label == "walk>run"
    assert np.all(np.isfinite(motion.joints))
    again = generate([("walk", 1.0), ("run", 1.0)], seed=3)
    np.testing.assert_array_equal(motion.joints, again.joints)
    other = generate([("walk", 1.0), ("run", 1.0)], seed=4)
    assert np.abs(other.joints - motion.joints).max() > 1e-3
    assert generate([("stand", 1.0)], fps=30.0).num_frames == 30


def test_every_mode_keeps_bone_lengths_and_stays_above_the_floor():
    motion = generate(ALL_MODES, seed=1)
    lengths = _bone_lengths(motion.joints.astype(np.float64))
    assert np.abs(lengths - lengths[0]).max() < 1e-4  # rigid bones in every mode and transition
    ankle_height = BodyParams().ankle_height
    assert 0.07 < ankle_height < 0.09
    assert _lowest_ankle(motion.joints).min() > ankle_height - 1e-4  # never through the floor


def test_body_size_scales_the_skeleton():
    small = generate([("stand", 0.4)], params=BodyParams(height=1.5)).joints
    tall = generate([("stand", 0.4)], params=BodyParams(height=1.9)).joints
    assert tall[0, HEAD, 2] / small[0, HEAD, 2] == pytest.approx(1.9 / 1.5, rel=0.02)
    assert 0.93 * 1.9 < tall[0, HEAD, 2] < 1.9  # the head joint sits just below the top of the head
    np.testing.assert_allclose(_lowest_ankle(small), BodyParams(height=1.5).ankle_height, atol=1e-5)


@pytest.mark.parametrize("mode", ["walk", "run"])
def test_walk_and_run_have_feet_on_the_floor_and_travel_forward(mode):
    joints = generate([(mode, 3.0)], seed=2).joints.astype(np.float64)
    low = _lowest_ankle(joints)
    ankle_height = BodyParams().ankle_height
    assert abs(low.min() - ankle_height) < 1e-4
    if mode == "walk":  # always one foot down
        np.testing.assert_allclose(low, ankle_height, atol=1e-4)
    else:  # short flights, a few centimetres
        assert 0.005 < low.max() - ankle_height < 0.05
    # Forward = -y at heading 0, along the facing direction, no sideways drift.
    travel = joints[-1, 0] - joints[0, 0]
    speed = -travel[1] / 3.0
    assert (0.8 < speed < 1.4) if mode == "walk" else (2.0 < speed < 3.2)
    assert abs(travel[0]) < 0.05
    # A planted foot does not slide: ankles on the floor move slowly in the world.
    ankles = joints[:, [R_ANKLE, L_ANKLE]]
    on_floor = ankles[1:, :, 2] < ankle_height + 2e-3
    on_floor &= ankles[:-1, :, 2] < ankle_height + 2e-3
    slide = np.linalg.norm(np.diff(ankles[..., :2], axis=0), axis=-1) * 25.0  # (T-1, 2) m/s
    assert slide[on_floor].max() < 0.05


def test_jump_leaves_the_ground_and_squat_goes_down():
    jump = generate([ModeSpec("jump", 2.5, phase=0.0)]).joints
    assert _lowest_ankle(jump).max() > 0.25  # feet clear the floor by > 15 cm
    assert _lowest_ankle(jump).min() == pytest.approx(BodyParams().ankle_height, abs=1e-4)
    squat = generate([ModeSpec("squat", 2.3, phase=0.0)]).joints
    pelvis = squat[:, 0, 2]
    assert pelvis.max() - pelvis.min() > 0.3
    feet = squat[:, [R_ANKLE, L_ANKLE], :2]
    np.testing.assert_allclose(feet, np.broadcast_to(feet[:1], feet.shape), atol=1e-4)  # planted


def test_turn_changes_heading_and_mirror_turns_the_other_way():
    left = generate([("turn", 1.0)], variation=0.0).joints
    right = generate([ModeSpec("turn", 1.0, mirror=True)], variation=0.0).joints
    assert heading_of(left[0]) == pytest.approx(0.0, abs=1e-6)
    expected = TURN_RATE * (left.shape[0] - 1) / 25.0
    assert heading_of(left[-1]) == pytest.approx(expected, abs=0.05)  # counter-clockwise: to its left
    assert heading_of(right[-1]) == pytest.approx(-expected, abs=0.05)
    assert np.linalg.norm(left[-1, 0, :2] - left[0, 0, :2]) < 0.02  # on the spot
    # Walking after a turn goes the new way.
    walk = generate([ModeSpec("turn", 1.0, phase=0.0), ("walk", 2.0)], variation=0.0).joints
    step = walk[-1, 0, :2] - walk[-10, 0, :2]
    heading = heading_of(walk[-1])
    facing = np.array([np.sin(heading), -np.cos(heading)])
    assert np.dot(step, facing) / np.linalg.norm(step) > 0.95


def test_chirality_and_facing_at_heading_zero():
    joints = generate([("stand", 0.4)]).joints[0]
    assert joints[L_HIP, 0] > joints[R_HIP, 0]  # the body faces -y, so its left is +x
    assert joints[L_SHOULDER, 0] > joints[R_SHOULDER, 0]
    assert joints[NOSE, 1] < joints[THORAX, 1]  # the nose is in front (-y)
    wave = generate([("wave", 2.0)]).joints
    assert wave[:, R_WRIST, 2].min() > wave[:, HEAD, 2].min() - 0.05  # the RIGHT hand waves above the head
    assert wave[:, L_WRIST, 2].max() < wave[:, 0, 2].max()  # the left arm hangs
    lefty = generate([ModeSpec("wave", 2.0, mirror=True)]).joints
    assert lefty[:, L_WRIST, 2].min() > lefty[:, HEAD, 2].min() - 0.05


def test_mirrored_angles_give_the_reflected_skeleton():
    rng = np.random.default_rng(0)
    euler = rng.uniform(-0.8, 0.8, size=(5, 17, 3))
    offsets = rest_offsets()
    pos = forward_kinematics(euler_to_matrix(euler), offsets, np.zeros((5, 3)))
    mirrored = forward_kinematics(euler_to_matrix(mirror_euler(euler)), offsets, np.zeros((5, 3)))
    reflected = pos[:, H36M_17.mirror_permutation()] * np.array([-1.0, 1.0, 1.0])
    np.testing.assert_allclose(mirrored, reflected, atol=1e-12)


def test_leg_ik_reaches_its_targets():
    thigh, shin = 0.42, 0.40
    fwd = np.array([0.0, 0.25, -0.3, 0.1])
    down = np.array([0.8, 0.7, 0.65, 0.5])
    flex, knee = leg_ik(fwd, down, thigh=thigh, shin=shin)
    assert np.all(knee >= 0)
    ankle_fwd = thigh * np.sin(flex) + shin * np.sin(flex - knee)
    ankle_down = thigh * np.cos(flex) + shin * np.cos(flex - knee)
    np.testing.assert_allclose(ankle_fwd, fwd, atol=1e-9)
    np.testing.assert_allclose(ankle_down, down, atol=1e-9)


def test_transitions_are_continuous_and_do_not_leak_backwards():
    seq = [("stand", 0.8), ("walk", 1.6), ("run", 1.6), ("turn", 1.2), ("jump", 1.6), ("squat", 1.6),
           ("punch", 1.2), ("wave", 1.2), ("idle", 1.0), ("walk", 1.0), ("stand", 0.8)]
    joints = generate(seq, seed=5).joints.astype(np.float64)
    rel = joints - joints[:, :1]
    assert np.linalg.norm(np.diff(rel, axis=0), axis=-1).max() < 0.3  # m per frame at 25 fps
    assert np.linalg.norm(np.diff(joints[:, 0], axis=0), axis=-1).max() < 0.15
    # The cross-fade is what keeps it smooth: a hard cut from waving to standing jumps.
    cut = generate([("wave", 1.0), ("stand", 1.0)], blend=0.0).joints
    assert np.linalg.norm(np.diff(cut, axis=0), axis=-1).max() > 0.4
    # Frames before a mode change do not depend on the next mode.
    a = generate([ModeSpec("walk", 1.0, phase=0.3), ModeSpec("run", 1.0)], seed=1).joints
    b = generate([ModeSpec("walk", 1.0, phase=0.3), ModeSpec("jump", 1.0)], seed=1).joints
    np.testing.assert_allclose(a[:26], b[:26], atol=1e-6)
    assert np.abs(a[30:] - b[30:]).max() > 0.1


def test_bad_inputs_raise_input_error():
    with pytest.raises(InputError, match="unknown motion mode"):
        generate([("moonwalk", 1.0)])
    with pytest.raises(InputError, match="positive"):
        generate([("walk", 0.0)])
    with pytest.raises(InputError, match="empty"):
        generate([])
    with pytest.raises(InputError):
        BodyParams(height=5.0)


# --- face -------------------------------------------------------------------------------------------------

def _channel(face: FaceMotion, name: str) -> np.ndarray:
    return face.expressions[:, ARKIT_NAMES.index(name)]


def test_face_shapes_range_and_determinism():
    modes = [(m, 1.0) for m in FACE_MODES]
    face = generate_face(modes, seed=2, identity={"gender": 0.3})
    assert isinstance(face, FaceMotion)
    assert face.params.shape == (25 * len(FACE_MODES), 58)
    assert face.identity == {"gender": 0.3} and face.label == ">".join(FACE_MODES)
    assert np.all(np.isfinite(face.params))
    assert face.expressions.min() >= 0.0 and face.expressions.max() <= 1.0
    np.testing.assert_array_equal(face.params, generate_face(modes, seed=2).params)
    assert np.abs(generate_face(modes, seed=3).params - face.params).max() > 1e-3
    assert generate_face([("neutral", 1.0)]).identity == {}
    with pytest.raises(InputError, match="unknown face mode"):
        generate_face([("wink", 1.0)])
    with pytest.raises(InputError, match="identity"):
        generate_face([("smile", 1.0)], identity={"age": 2.0})


def test_face_modes_drive_their_coefficients():
    face = generate_face([("neutral", 1.0), ("smile", 2.0)], seed=0)
    neutral, smile = slice(0, 25), slice(40, 75)  # after the 0.3 s cross-fade
    for name in ("mouthSmileLeft", "mouthSmileRight", "cheekSquintLeft", "cheekSquintRight"):
        assert _channel(face, name)[smile].mean() > _channel(face, name)[neutral].mean() + 0.25
    assert _channel(face, "mouthSmileLeft")[smile].mean() > 0.5
    blink = generate_face([("blink", 3.0)], seed=0, blink_rate=0.0)
    eyes = _channel(blink, "eyeBlinkLeft")
    closed = eyes > 0.8
    assert 2 <= np.sum(np.diff(closed.astype(int)) == 1) and eyes.min() < 0.05  # several full blinks
    talk = generate_face([("talk", 3.0)], seed=0)
    jaw = _channel(talk, "jawOpen")
    assert jaw.max() > 0.3 and np.sum(np.diff((jaw > 0.15).astype(int)) == 1) >= 4  # syllables
    surprise = generate_face([("surprise", 1.5)], seed=0)
    assert _channel(surprise, "browInnerUp")[10:].mean() > 0.6 and _channel(surprise, "eyeWideLeft")[10:].mean() > 0.5
    frown = generate_face([("frown", 1.5)], seed=0)
    assert _channel(frown, "mouthFrownLeft")[10:].mean() > 0.4 and _channel(frown, "browDownRight")[10:].mean() > 0.5


def test_head_pose_convention_nod_and_turn():
    # Positive yaw turns the face (-y at rest) towards its left (+x); positive pitch looks down.
    face_dir = np.array([0.0, -1.0, 0.0])
    assert (head_euler_to_matrix(np.array([0.3, 0.0, 0.0])) @ face_dir)[0] > 0.25
    assert (head_euler_to_matrix(np.array([0.0, 0.3, 0.0])) @ face_dir)[2] < -0.25
    assert (head_euler_to_matrix(np.array([0.0, 0.0, 0.3])) @ np.array([0.0, 0.0, 1.0]))[0] > 0.25
    nod = generate_face([("nod", 2.0)], seed=0, sway=0.0)
    pitch = nod.head_rotation[:, 0]  # about x
    assert pitch.max() > 0.2 and pitch.min() > -0.02 and np.abs(nod.head_rotation[:, 2]).max() < 0.01
    turn = generate_face([("turn", 3.4)], seed=0, sway=0.0)
    yaw = turn.head_rotation[:, 2]  # about z
    assert yaw.max() > 0.4 and yaw.min() < -0.4
    assert np.abs(turn.head_translation).max() == 0.0
    swaying = generate_face([("neutral", 3.0)], seed=0)
    assert 0 < np.abs(swaying.head_translation).max() < 0.02


def test_face_transitions_are_smooth():
    face = generate_face([("neutral", 1.0), ("smile", 1.0), ("surprise", 1.0), ("frown", 1.0), ("turn", 1.0)],
                         seed=0, blink_rate=0.0, gaze=False)
    steps = np.abs(np.diff(face.params.astype(np.float64), axis=0))
    assert steps[:, :52].max() < 0.25 and steps[:, 52:55].max() < 0.1


def test_rotation_helpers_round_trip():
    rng = np.random.default_rng(1)
    aa = rng.normal(size=(200, 3))
    aa *= rng.uniform(0, np.pi - 1e-3, size=(200, 1)) / np.linalg.norm(aa, axis=1, keepdims=True)
    np.testing.assert_allclose(matrix_to_axis_angle(axis_angle_to_matrix(aa)), aa, atol=1e-8)
    np.testing.assert_allclose(np.abs(matrix_to_axis_angle(axis_angle_to_matrix(np.array([0.0, 0.0, np.pi])))),
                               [0.0, 0.0, np.pi], atol=1e-8)
    euler = rng.uniform(-0.5, 0.5, size=(20, 3))
    np.testing.assert_allclose(axis_angle_to_matrix(head_euler_to_axis_angle(euler)), head_euler_to_matrix(euler),
                               atol=1e-10)


def test_head_pose_track_is_smooth_small_and_seeded():
    track = head_pose_track(250, 25.0, seed=4)
    assert track.shape == (250, 6) and track.dtype == np.float32
    np.testing.assert_array_equal(track, head_pose_track(250, 25.0, seed=4))
    assert not np.allclose(track, head_pose_track(250, 25.0, seed=5))
    assert 0.02 < np.abs(track[:, :3]).max() < 0.4 and np.abs(track[:, 3:]).max() < 0.01
    assert np.abs(np.diff(track, axis=0)).max() < 0.02  # slow
    with pytest.raises(InputError):
        head_pose_track(0, 25.0, seed=0)
    assert FaceModeSpec("talk", 1.0, speed=2.0).speed == 2.0


# --- demo inputs ------------------------------------------------------------------------------------------

def _load_script():
    spec = importlib.util.spec_from_file_location("make_demo_inputs", REPO / "scripts" / "make_demo_inputs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_demo_inputs_regenerate_identically(tmp_path):
    script = _load_script()
    assert script.main(["--out", str(tmp_path)]) == 0
    committed = REPO / "demo_inputs"
    names = list(script.BODY_DEMOS) + list(script.FACE_DEMOS)
    assert sum((committed / n).stat().st_size for n in names) < 2 * 1024 * 1024
    for name in script.BODY_DEMOS:
        new, old = load_motion_npz(tmp_path / name), load_motion_npz(committed / name)
        # Same formulas, but numpy's SIMD paths differ between CPUs in the last bit (measured: 2e-16 m
        # on CI against the machine that wrote the files), so compare at a nanometre, not bit for bit.
        np.testing.assert_allclose(new.joints, old.joints, rtol=0, atol=1e-9)
        assert (new.fps, new.skeleton, new.label) == (old.fps, old.skeleton, old.label)
    for name in script.FACE_DEMOS:
        new, old = load_face_npz(tmp_path / name), load_face_npz(committed / name)
        np.testing.assert_allclose(new.params, old.params, rtol=0, atol=1e-9)
        assert (new.fps, new.identity, new.label) == (old.fps, old.identity, old.label)
    assert (tmp_path / "README.md").read_text() == (committed / "README.md").read_text()
    for name in names:
        assert name in (committed / "README.md").read_text()


MOCAP = REPO.parent / "shared" / "data" / "mocap"


def test_real_demo_inputs_regenerate_identically(tmp_path):
    """The committed CMU excerpts are what ``--real-mocap`` cuts out of the mocap folder beside the repository,
    and the README names their source, the terms and CMU's credit line."""
    script = _load_script()
    assert script.main(["--out", str(tmp_path), "--real-mocap", str(MOCAP)]) == 0
    committed = REPO / "demo_inputs"
    readme = (committed / "README.md").read_text()
    for name, (clip, start, frames, _) in script.REAL_DEMOS.items():
        new, old = load_motion_npz(tmp_path / name), load_motion_npz(committed / name)
        assert old.joints.shape == (frames, 17, 3) and old.fps == 25.0 and old.skeleton == "h36m-17"
        # The BVH forward kinematics may differ in the last bits between CPUs: compare at a micrometre.
        np.testing.assert_allclose(new.joints, old.joints, rtol=0, atol=1e-6)
        assert new.label == old.label and clip in old.label and name in readme and clip in readme
        assert (committed / name).stat().st_size < 64 * 1024
    assert "mocap.cs.cmu.edu" in readme and "NSF EIA-0196217" in readme
    # A real walk moves forward; a real jump lifts the pelvis well off its standing height.
    walk = load_motion_npz(committed / "cmu_walk.npz").joints
    jump = load_motion_npz(committed / "cmu_jump.npz").joints
    assert np.linalg.norm(walk[-1, 0, :2] - walk[0, 0, :2]) > 2.0
    assert jump[:, 0, 2].max() - jump[0, 0, 2] > 0.2
    assert script.main(["--out", str(tmp_path), "--real-mocap", str(tmp_path)]) == 2  # not a mocap folder
