"""BVH reader and forward kinematics on hand-written files, and BVH specifics on the real clips (rigs, units,
header vs. true frame rates, trimming). The checks every real clip of every format passes are in
tests/test_mocap_clips.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.formats import bvh
from motion2video.formats.canonical import Y_UP_TO_Z_UP
from motion2video.formats.manifest import find_manifest_entry, read_manifest
from motion2video.formats.mocap import load_mocap_folder
from motion2video.formats.resample import resample_linear
from motion2video.core.skeletons import H36M_17
from tests.conftest import link_clips

J = {name: i for i, name in enumerate(H36M_17.joints)}


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
    assert np.isclose(np.linalg.det(Y_UP_TO_Z_UP), 1.0)
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


def test_unmappable_rig_raises_naming_the_missing_body_points():
    with pytest.raises(InputError, match="two.bvh: cannot map this BVH rig.*no joint found for right_hip, right_knee"):
        bvh.bvh_to_canonical(bvh.parse_bvh(TWO_JOINTS, "two.bvh"))


def test_resample_linear_hits_the_original_samples():
    x = np.arange(13, dtype=float)[:, None] * np.array([1.0, -2.0])  # (13, 2), linear in time
    y = resample_linear(x, 120.0, 30.0)
    np.testing.assert_allclose(y, x[::4])
    z = resample_linear(x, 120.0, 50.0)  # 12 frames at 120 -> 0.1 s -> 5 frames at 50 fps
    assert z.shape == (6, 2)
    np.testing.assert_allclose(z[:, 0], np.arange(6) * 2.4)


# --- real BVH clips (the checks over every file of the folder live in test_mocap_clips.py) -----------------

@pytest.mark.slow
@pytest.mark.parametrize("name", ["cmu/05_01.bvh", "cmu/16_01.bvh", "deepmimic/humanoid3d_run.bvh"])
def test_load_bvh_with_manifest_matches_the_corpus_loader(mocap_clips, mocap_dir, name):
    m = bvh.load_bvh(mocap_dir / name, manifest=True)
    c = mocap_clips[name].motion
    assert (m.fps, m.label, m.num_frames) == (c.fps, c.label, c.num_frames)
    np.testing.assert_array_equal(m.joints, c.joints)


@pytest.mark.slow
def test_true_fps_overrides_the_header(mocap_clips):
    for name in ("cmu/16_01.bvh", "cmu/16_02.bvh"):
        c = mocap_clips[name]
        assert c.canonical.fps == 30.0  # the header
        assert c.motion.fps == 120.0
    assert mocap_clips["deepmimic/humanoid3d_walk.bvh"].motion.fps == 30.0  # manifest empty: header
    for name in ("acrnn/salsa_01a.bvh", "acrnn/salsa_07b.bvh"):  # header 120, captured at 60
        c = mocap_clips[name]
        assert c.canonical.fps == 120.0 and c.motion.fps == 60.0


@pytest.mark.slow
def test_rigs_and_units_per_rig(mocap_clips):
    rigs = {name: c.canonical.rig for name, c in mocap_clips.items()}
    assert rigs["cmu/01_01.bvh"] == "cmu-mb"
    assert rigs["cmu/131_01.bvh"] == "cmu-3dsmax"
    assert rigs["cmu/05_01.bvh"] == "cmu-daz"
    assert rigs["cmu/16_01.bvh"] == "cmu-amc"  # raw amc2bvh names, although the manifest says cmu-daz
    assert rigs["deepmimic/humanoid3d_walk.bvh"] == "deepmimic-humanoid"
    assert rigs["mass/mass_walk.bvh"] == "mass-character1"
    assert {rigs[n] for n in rigs if n.startswith("acrnn/")} == {"cmu-daz"}
    # Thigh lengths from the README: ~41 cm (CMU), ~37 (DAZ), ~40 (MASS), ~42 (DeepMimic).
    for name, low, high in [("cmu/16_11.bvh", 0.38, 0.44), ("cmu/131_01.bvh", 0.38, 0.44),
                            ("cmu/05_01.bvh", 0.34, 0.40), ("mass/mass_walk.bvh", 0.37, 0.43),
                            ("deepmimic/humanoid3d_walk.bvh", 0.39, 0.45), ("cmu/16_01.bvh", 0.37, 0.43)]:
        x = mocap_clips[name].motion.joints
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
def test_load_mocap_folder_at_25_fps(mocap_dir, mocap_manifest):
    motions = load_mocap_folder(mocap_dir, target_fps=25)
    assert len(motions) == len(mocap_manifest) == 275
    assert all(m.fps == 25.0 and m.skeleton == "h36m-17" for m in motions)
    walk = [m for m in motions if m.source.endswith("cmu/07_01.bvh")][0]
    assert walk.num_frames == int((317 - 5 - 1) * 25 / 120) + 1


def test_a_folder_without_manifest_loads_its_bvh_files_with_header_rates(tmp_path, mocap_dir):
    link_clips(tmp_path, mocap_dir, ("cmu/16_01.bvh", "mass/mass_walk.bvh"))
    motions = load_mocap_folder(tmp_path, target_fps=None)
    assert [Path(m.source).name for m in motions] == ["16_01.bvh", "mass_walk.bvh"]
    assert motions[0].fps == 30.0 and motions[0].label is None  # header rate, no trim without a manifest
    assert motions[0].num_frames == 322
