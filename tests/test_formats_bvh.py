"""BVH reader, forward kinematics and the canonical conversion, on hand-written files and on all 72 real clips.

Checks on the real clips (shared/data/mocap), each with the measure it uses:

- stature: a pose-independent estimate, ankle height + shin + thigh + the most extended pelvis-to-head
  distance (95th percentile over frames) + the skull-base-to-crown distance. It needs no standing frame, so
  crawling and rolling clips are measured too. The canonical ``head`` is the skull base for every rig except
  ``deepmimic-humanoid``, where it is the neck's end site, i.e. the crown (README table) - so the crown
  offset is 0.12 m (adult skull base to vertex; Anny: 0.15 m) there and 0 for DeepMimic. For walking clips
  the standing head height (median head z + crown offset) is checked as well.
- feet on the floor: the lowest toe/foot-end node over the clip is within a few cm of z = 0 (the floor is
  placed from the ankles, so this checks it against the rig's real foot geometry), and in walking clips a
  foot is near the floor in nearly every frame.
- left/right not swapped (per clip, so per rig): the body's forward direction, up x right with up =
  thorax - pelvis and right = right_hip - left_hip, must agree with (a) the direction the knees bend (a
  bent knee lies in front of the hip-ankle line), (b) the direction the feet point (ankle -> toe), and (c)
  the direction of travel in walking clips. A mirror image flips all three (tested).
- limb bone lengths constant over time; fps per the manifest (16_01 / 16_02: 120 fps, header 30).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from motion2video.errors import InputError
from motion2video.formats import bvh
from motion2video.formats.manifest import ManifestEntry, find_manifest_entry, read_manifest
from motion2video.formats.resample import resample_linear
from motion2video.motion import Motion
from motion2video.skeletons import H36M_17

J = {name: i for i, name in enumerate(H36M_17.joints)}
CROWN_ABOVE_HEAD = {"deepmimic-humanoid": 0.0}  # others: 0.12 m, see the module docstring
DEFAULT_CROWN = 0.12
# The node just past each ankle (toe joint or foot end site), per rig: (left, right).
TOE_NODES = {
    "cmu-mb": ("LeftToeBase", "RightToeBase"),
    "cmu-3dsmax": ("LeftToe", "RightToe"),
    "cmu-amc": ("ltoes", "rtoes"),
    "cmu-daz": ("lFoot:end", "rFoot:end"),
    "deepmimic-humanoid": ("left_ankle:end", "right_ankle:end"),
    "mass-character1": ("Character1_LeftToeBase", "Character1_RightToeBase"),
}
LIMBS = [("right_hip", "right_knee"), ("right_knee", "right_ankle"), ("left_hip", "left_knee"),
         ("left_knee", "left_ankle"), ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
         ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist")]


# --- hand-written files -----------------------------------------------------------------------------------

TWO_JOINTS = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Child
  {
    OFFSET 0 10 0
    CHANNELS 2 Xrotation Zrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.04
0 0 0 0 0 0 0 0
1 2 3 90 90 0 0 0
0 0 0 0 0 0 90 90
"""


def test_parse_names_parents_channels():
    clip = bvh.parse_bvh(TWO_JOINTS, "two.bvh")
    assert clip.names == ("Hips", "Child", "Child:end")
    assert clip.parents == (-1, 0, 1)
    assert clip.channels[0] == ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    assert clip.channels[1] == ("Xrotation", "Zrotation")
    assert clip.channels[2] == ()
    assert clip.channel_start == (0, 6, 8)
    assert clip.values.shape == (3, 8)
    assert clip.header_fps == 25.0
    np.testing.assert_allclose(clip.offsets[1], [0, 10, 0])


def test_forward_kinematics_intrinsic_channel_order():
    pos = bvh.bvh_world_positions(bvh.parse_bvh(TWO_JOINTS, "two.bvh"))  # (3, 3, 3)
    # Frame 0: rest pose.
    np.testing.assert_allclose(pos[0], [[0, 0, 0], [0, 10, 0], [0, 15, 0]], atol=1e-9)
    # Frame 1: root at (1, 2, 3), rotation Rz(90) @ Rx(90) (listed order). Rx(90) takes +y to +z and Rz(90)
    # leaves +z alone, so the child sits 10 along +z. The reverse order would give -x instead.
    np.testing.assert_allclose(pos[1, 1], [1, 2, 13], atol=1e-9)
    np.testing.assert_allclose(pos[1, 2], [1, 2, 18], atol=1e-9)
    # Frame 2: the child's own Rx(90) @ Rz(90) moves only its end site: Rz(90) takes +y to -x, Rx keeps -x.
    np.testing.assert_allclose(pos[2, 1], [0, 10, 0], atol=1e-9)
    np.testing.assert_allclose(pos[2, 2], [-5, 10, 0], atol=1e-9)


def test_position_channels_subset_replace_offset_on_their_axes():
    text = """HIERARCHY
ROOT R
{
  OFFSET 7 8 9
  CHANNELS 1 Yposition
  End Site
  {
    OFFSET 0 1 0
  }
}
MOTION
Frames: 2
Frame Time: 0.5
100
-3
"""
    clip = bvh.parse_bvh(text, "sub.bvh")
    pos = bvh.bvh_world_positions(clip)
    np.testing.assert_allclose(pos[:, 0], [[7, 100, 9], [7, -3, 9]])
    np.testing.assert_allclose(pos[:, 1], [[7, 101, 9], [7, -2, 9]])


def test_axis_rotations_are_right_handed():
    rz = bvh.axis_rotations(np.array([90.0]), "Z")[0]
    np.testing.assert_allclose(rz @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    rx = bvh.axis_rotations(np.array([90.0]), "X")[0]
    np.testing.assert_allclose(rx @ [0, 1, 0], [0, 0, 1], atol=1e-12)
    ry = bvh.axis_rotations(np.array([90.0]), "Y")[0]
    np.testing.assert_allclose(ry @ [0, 0, 1], [1, 0, 0], atol=1e-12)


def test_y_up_to_z_up_is_a_rotation():
    assert np.isclose(np.linalg.det(bvh.Y_UP_TO_Z_UP), 1.0)
    np.testing.assert_allclose(bvh.to_project_frame(np.array([1.0, 2.0, 3.0]), 0.5), [0.5, -1.5, 1.0])


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("hello world\n", "no MOTION section"),
        ("HIERARCHY\nROOT A\n{\n  CHANNELS 0\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n\n", "line 4: expected OFFSET"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 x\n", "no MOTION"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Wrotation\n}\nMOTION\nFrames: 1\nFrame Time: 1\n0\n",
         "line 5: unknown channel"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n}\nMOTION\nFrames: 0\nFrame Time: 1\n",
         "empty"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n}\nMOTION\nFrames: 3\nFrame Time: 1\n1\n2\n",
         "truncated"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 2 Xrotation Yrotation\n}\nMOTION\nFrames: 1\n"
         "Frame Time: 1\n1\n", "line 10: expected 2 values, got 1"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0\n1\n",
         "Frame Time must be positive"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\nFrame Time: 1\nabc\n",
         "line 10: a motion value is not a number"),
        ("HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n  JOINT B\nMOTION\nFrames: 1\n",
         "line 6: hierarchy ends early"),
    ],
)
def test_malformed_bvh_raises_one_line_input_error(tmp_path, text, message):
    path = tmp_path / "bad.bvh"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        bvh.read_bvh(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)
    assert "\n" not in str(info.value)


def test_truncated_real_file_raises(tmp_path, mocap_dir):
    lines = (mocap_dir / "cmu/16_11.bvh").read_text().splitlines(keepends=True)
    cut = tmp_path / "cut.bvh"
    cut.write_text("".join(lines[: len(lines) // 2]))
    with pytest.raises(InputError, match="truncated"):
        bvh.load_bvh(cut)
    # Cut inside the hierarchy: no MOTION section at all.
    cut.write_text("".join(lines[:40]))
    with pytest.raises(InputError, match="no MOTION"):
        bvh.load_bvh(cut)


def test_binary_garbage_and_missing_file(tmp_path):
    garbage = tmp_path / "garbage.bvh"
    garbage.write_bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    with pytest.raises(InputError, match="garbage.bvh"):
        bvh.read_bvh(garbage)
    with pytest.raises(InputError, match="no such file"):
        bvh.load_bvh(tmp_path / "missing.bvh")


def test_unknown_rig_raises():
    with pytest.raises(InputError, match="unknown BVH rig"):
        bvh.bvh_to_canonical(bvh.parse_bvh(TWO_JOINTS, "two.bvh"))


def test_resample_linear_hits_the_original_samples():
    x = np.arange(13, dtype=float)[:, None] * np.array([1.0, -2.0])  # (13, 2), linear in time
    y = resample_linear(x, 120.0, 30.0)
    np.testing.assert_allclose(y, x[::4])
    z = resample_linear(x, 120.0, 50.0)  # 12 frames at 120 -> 0.1 s -> 5 frames at 50 fps
    assert z.shape == (6, 2)
    np.testing.assert_allclose(z[:, 0], np.arange(6) * 2.4)


# --- the 72 real clips ------------------------------------------------------------------------------------

@dataclass
class LoadedClip:
    entry: ManifestEntry
    clip: bvh.BvhClip
    rig: str
    motion: Motion  # via load_bvh with the manifest (trim, true fps)
    nodes: np.ndarray  # (T, N, 3) all nodes, same frames and floor as motion.joints


@pytest.fixture(scope="module")
def manifest(mocap_dir) -> dict[str, ManifestEntry]:
    return read_manifest(mocap_dir / "manifest.csv")


@pytest.fixture(scope="module")
def clips(mocap_dir, manifest) -> dict[str, LoadedClip]:
    """Every clip of the manifest, loaded once per module (a few seconds), as load_bvh(manifest=) does
    (test_load_bvh_with_manifest_matches_the_fixture checks that on a few clips)."""
    out = {}
    for name, entry in manifest.items():
        clip = bvh.read_bvh(mocap_dir / name)
        canon = bvh.canonical_positions(clip)
        trim = bvh.default_trim(canon.rig)
        motion = bvh.bvh_to_canonical(clip, fps=entry.fps, start=trim, label=entry.label, canonical=canon)
        nodes = canon.nodes[trim:].copy()
        nodes[..., 2] -= bvh.floor_height(canon.joints[trim:])
        out[name] = LoadedClip(entry, clip, canon.rig, motion, nodes)
    return out


def _manifest_at_collection() -> dict[str, ManifestEntry]:
    """The manifest, read when the module is collected (parametrisation); empty without the shared data
    (the fixtures then fail with a clear message)."""
    path = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "manifest.csv"
    return read_manifest(path) if path.is_file() else {}


CLIP_NAMES = sorted(_manifest_at_collection())
WALK_NAMES = sorted(n for n, e in _manifest_at_collection().items() if e.label.startswith("walk"))


def test_every_clip_of_the_folder_is_in_the_manifest(mocap_dir, manifest):
    files = sorted(p.relative_to(mocap_dir).as_posix() for p in mocap_dir.rglob("*.bvh"))
    assert len(files) == 72
    assert files == sorted(manifest)


def stature(joints: np.ndarray, rig: str) -> float:
    """Pose-independent standing-height estimate (see the module docstring), metres."""
    def length(a: str, b: str) -> float:
        return float(np.median(np.linalg.norm(joints[:, J[a]] - joints[:, J[b]], axis=-1)))

    legs = (length("right_hip", "right_knee") + length("right_knee", "right_ankle")
            + length("left_hip", "left_knee") + length("left_knee", "left_ankle")) / 2
    hip_mid = (joints[:, J["right_hip"]] + joints[:, J["left_hip"]]) / 2
    trunk = float(np.percentile(np.linalg.norm(joints[:, J["head"]] - hip_mid, axis=-1), 95))
    return bvh.ANKLE_HEIGHT + legs + trunk + CROWN_ABOVE_HEAD.get(rig, DEFAULT_CROWN)


def body_forward(joints: np.ndarray) -> np.ndarray:
    """(T, 3) unit forward direction: up x right, up = thorax - pelvis, right = right_hip - left_hip."""
    up = joints[:, J["thorax"]] - joints[:, J["pelvis"]]
    right = joints[:, J["right_hip"]] - joints[:, J["left_hip"]]
    forward = np.cross(up, right)
    return forward / np.linalg.norm(forward, axis=-1, keepdims=True)


def knee_agreement(joints: np.ndarray, side: str, forward: np.ndarray) -> tuple[float, int]:
    """Fraction of clearly bent frames (knee angle < 150 deg) whose knee lies in front of hip-ankle."""
    hip, knee, ankle = (joints[:, J[f"{side}_{n}"]] for n in ("hip", "knee", "ankle"))
    u, v = hip - knee, ankle - knee
    cos = np.sum(u * v, -1) / (np.linalg.norm(u, axis=-1) * np.linalg.norm(v, axis=-1))
    bent = np.degrees(np.arccos(np.clip(cos, -1, 1))) < 150
    ahead = np.sum((knee - (hip + ankle) / 2) * forward, axis=-1) > 0
    return (float(ahead[bent].mean()) if bent.any() else float("nan")), int(bent.sum())


@pytest.mark.parametrize("name", CLIP_NAMES)
def test_real_clip_is_a_plausible_body(clips, name):
    c = clips[name]
    m = c.motion
    x = m.joints.astype(np.float64)
    assert m.skeleton == "h36m-17" and x.shape[1:] == (17, 3)
    assert m.label == c.entry.label
    # Frames: the manifest's trim for cmu-daz, none otherwise.
    assert m.num_frames == c.clip.num_frames - bvh.default_trim(c.rig)
    # fps per the manifest; the header where the manifest has none.
    assert m.fps == (c.entry.fps if c.entry.fps is not None else c.clip.header_fps)

    h = stature(x, c.rig)
    assert 1.4 < h < 2.0, f"stature {h:.2f} m"

    # Limbs are rigid: every canonical limb maps to one BVH bone (no joint in between).
    for a, b in LIMBS:
        length = np.linalg.norm(x[:, J[a]] - x[:, J[b]], axis=-1)
        assert length.std() < 1e-3, f"{a}-{b} length varies by {length.std() * 1000:.2f} mm"
        assert 0.15 < length.mean() < 0.6

    # Feet: the rig's toe / foot-end nodes reach the floor the ankles define, within a few cm.
    toe_ids = [c.clip.index(n) for n in TOE_NODES[c.rig]]
    lowest_toe = float(c.nodes[:, toe_ids, 2].min())
    assert abs(lowest_toe) < 0.08, f"lowest toe at {lowest_toe:.3f} m"
    assert bvh.ANKLE_HEIGHT - 0.06 < x[:, [J["right_ankle"], J["left_ankle"]], 2].min() <= bvh.ANKLE_HEIGHT + 1e-5

    # Chirality (a): knees bend forward.
    forward = body_forward(x)
    for side in ("left", "right"):
        agree, bent = knee_agreement(x, side, forward)
        if bent >= 5:
            assert agree > 0.75, f"{side} knee bends forward in only {agree:.0%} of {bent} bent frames"
    # Chirality (b): feet point forward (median over frames of ankle -> toe along forward).
    for side, toe_id in zip(("left", "right"), toe_ids):
        foot = c.nodes[:, toe_id] - x[:, J[f"{side}_ankle"]]
        assert np.median(np.sum(foot * forward, axis=-1)) > 0, f"{side} foot points backwards"


@pytest.mark.parametrize("name", WALK_NAMES)
def test_walking_clips_stand_travel_forward_and_touch_the_floor(clips, name):
    c = clips[name]
    x = c.motion.joints.astype(np.float64)
    head = float(np.median(x[:, J["head"], 2])) + CROWN_ABOVE_HEAD.get(c.rig, DEFAULT_CROWN)
    assert 1.4 < head < 2.0, f"standing head height {head:.2f} m"
    # Chirality (c): the pelvis travels the way the body faces.
    step = np.diff(x[:, J["pelvis"], :2], axis=0)  # (T-1, 2)
    along = np.sum(step * body_forward(x)[1:, :2], axis=-1).sum() / np.linalg.norm(step, axis=-1).sum()
    assert along > 0.5, f"only {along:.0%} of the path goes forward"
    if "uneven" not in c.entry.label:
        lower_ankle = x[:, [J["right_ankle"], J["left_ankle"]], 2].min(axis=1)
        assert np.mean(lower_ankle < bvh.ANKLE_HEIGHT + 0.10) > 0.9


def test_chirality_checks_detect_a_mirror_image(clips):
    c = clips["cmu/16_11.bvh"]  # cmu-mb walk
    mirrored = c.motion.joints.astype(np.float64) * np.array([-1.0, 1.0, 1.0])  # reflect, keep names
    forward = body_forward(mirrored)
    for side in ("left", "right"):
        agree, bent = knee_agreement(mirrored, side, forward)
        assert bent > 50 and agree < 0.1


@pytest.mark.parametrize("name", ["cmu/05_01.bvh", "cmu/16_01.bvh", "deepmimic/humanoid3d_run.bvh"])
def test_load_bvh_with_manifest_matches_the_fixture(clips, mocap_dir, name):
    m = bvh.load_bvh(mocap_dir / name, manifest=True)
    c = clips[name].motion
    assert (m.fps, m.label, m.num_frames) == (c.fps, c.label, c.num_frames)
    np.testing.assert_array_equal(m.joints, c.joints)


def test_true_fps_overrides_the_header(clips):
    for name in ("cmu/16_01.bvh", "cmu/16_02.bvh"):
        c = clips[name]
        assert c.clip.header_fps == 30.0
        assert c.motion.fps == 120.0
    assert clips["deepmimic/humanoid3d_walk.bvh"].motion.fps == 30.0  # manifest empty: header


def test_rigs_and_units_per_rig(clips):
    rigs = {name: c.rig for name, c in clips.items()}
    assert rigs["cmu/01_01.bvh"] == "cmu-mb"
    assert rigs["cmu/131_01.bvh"] == "cmu-3dsmax"
    assert rigs["cmu/05_01.bvh"] == "cmu-daz"
    assert rigs["cmu/16_01.bvh"] == "cmu-amc"  # raw amc2bvh names, although the manifest says cmu-daz
    assert rigs["deepmimic/humanoid3d_walk.bvh"] == "deepmimic-humanoid"
    assert rigs["mass/mass_walk.bvh"] == "mass-character1"
    # Thigh lengths from the README: ~41 cm (CMU), ~37 (DAZ), ~40 (MASS), ~42 (DeepMimic).
    for name, low, high in [("cmu/16_11.bvh", 0.38, 0.44), ("cmu/131_01.bvh", 0.38, 0.44),
                            ("cmu/05_01.bvh", 0.34, 0.40), ("mass/mass_walk.bvh", 0.37, 0.43),
                            ("deepmimic/humanoid3d_walk.bvh", 0.39, 0.45), ("cmu/16_01.bvh", 0.37, 0.43)]:
        x = clips[name].motion.joints
        thigh = np.linalg.norm(x[0, J["left_hip"]] - x[0, J["left_knee"]])
        assert low < thigh < high, name


def test_trim_frames_fps_and_resampling_arguments(mocap_dir):
    path = mocap_dir / "cmu/05_01.bvh"
    full = bvh.load_bvh(path, trim_start=0)
    assert full.num_frames == 599 and full.fps == 120.0 and full.label is None
    via_manifest = bvh.load_bvh(path, manifest=True)
    assert via_manifest.num_frames == 594 and via_manifest.label.startswith("walk")
    part = bvh.load_bvh(path, trim_start=10, frames=100, fps=60)
    assert part.num_frames == 100 and part.fps == 60.0
    at30 = bvh.load_bvh(path, manifest=True, target_fps=30)
    assert at30.fps == 30.0 and at30.num_frames == (594 - 1) // 4 + 1
    # Every 4th frame of the 120 fps clip is an original sample (same floor: same kept frames).
    np.testing.assert_allclose(at30.joints, via_manifest.joints[::4], atol=1e-5)
    with pytest.raises(InputError, match="fps must be a positive"):
        bvh.load_bvh(path, fps=0)
    with pytest.raises(InputError, match="target fps"):
        bvh.load_bvh(path, target_fps=-5)
    with pytest.raises(InputError, match="outside the clip"):
        bvh.load_bvh(path, trim_start=599)


def test_manifest_lookup(mocap_dir, tmp_path):
    entry = find_manifest_entry(mocap_dir / "cmu/16_01.bvh")
    assert entry is not None and entry.fps == 120.0 and entry.label.startswith("jump")
    assert find_manifest_entry(mocap_dir / "deepmimic/humanoid3d_walk.bvh").fps is None
    assert find_manifest_entry(tmp_path / "x.bvh") is None
    bad = tmp_path / "manifest.csv"
    bad.write_text("file,action,fps\na.bvh,walk,fast\n")
    with pytest.raises(InputError, match="line 2: fps is not a number"):
        read_manifest(bad)


@pytest.mark.slow
def test_load_mocap_folder_at_25_fps(mocap_dir):
    motions = bvh.load_mocap_folder(mocap_dir, target_fps=25)
    assert len(motions) == 72
    assert all(m.fps == 25.0 and m.skeleton == "h36m-17" for m in motions)
    walk = [m for m in motions if m.source.endswith("cmu/07_01.bvh")][0]
    assert walk.num_frames == int((317 - 5 - 1) * 25 / 120) + 1
