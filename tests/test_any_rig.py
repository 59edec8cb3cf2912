"""Any humanoid BVH rig: a rig outside the known table is mapped to the body points from its joint names.

Real files only: Bandai-Namco's rig (translation on ``Hips``, six channels per joint, zero-length head end
site, ``.bvh.xz``) and a real CMU capture renamed to the common conventions (Mixamo, Unreal, 3ds Max Biped,
SMPL). Every one lands within 0.8-1.25 of Human3.6M's proportions, as every known rig does; the renamed
captures give the same limbs as the known rig; a rig whose names tell nothing is refused with one line
naming the missing body points, and reads once a rig map names them.
"""

from __future__ import annotations

import json
import lzma
import re
from pathlib import Path

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.core.skeletons import H36M_17, joint_name_parts, map_joint_names, proportion_ratios
from motion2video.formats import bvh
from motion2video.formats.io import load_motion

BANDAI_CLIPS = ("bvh/dataset-2_walk_normal_001.bvh.xz", "bvh/dataset-1_bow_active_001.bvh.xz")
LIMBS = [H36M_17.index(j) for j in ("right_hip", "right_knee", "right_ankle", "left_hip", "left_knee",
                                    "left_ankle", "left_shoulder", "left_elbow", "left_wrist", "right_shoulder",
                                    "right_elbow", "right_wrist")]

# cmu/01_01.bvh (cmu-mb names) -> each convention; joints not named here become "joint<i>" (no body part).
CONVENTIONS = {
    "mixamo": {n: f"mixamorig:{n}" for n in (
        "Hips", "Spine", "Spine1", "Neck", "Head", "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand",
        "RightShoulder", "RightArm", "RightForeArm", "RightHand", "LeftUpLeg", "LeftLeg", "LeftFoot",
        "RightUpLeg", "RightLeg", "RightFoot")},
    "unreal": {"Hips": "pelvis", "LowerBack": "spine_01", "Spine": "spine_02", "Spine1": "spine_03",
               "Neck": "neck_01", "Head": "head", "LeftShoulder": "clavicle_l", "LeftArm": "upperarm_l",
               "LeftForeArm": "lowerarm_l", "LeftHand": "hand_l", "RightShoulder": "clavicle_r",
               "RightArm": "upperarm_r", "RightForeArm": "lowerarm_r", "RightHand": "hand_r",
               "LeftUpLeg": "thigh_l", "LeftLeg": "calf_l", "LeftFoot": "foot_l", "RightUpLeg": "thigh_r",
               "RightLeg": "calf_r", "RightFoot": "foot_r"},
    "biped": {"Hips": "Bip01 Pelvis", "Spine": "Bip01 Spine", "Neck": "Bip01 Neck", "Head": "Bip01 Head",
              "LeftShoulder": "Bip01 L Clavicle", "LeftArm": "Bip01 L UpperArm", "LeftForeArm": "Bip01 L Forearm",
              "LeftHand": "Bip01 L Hand", "RightShoulder": "Bip01 R Clavicle", "RightArm": "Bip01 R UpperArm",
              "RightForeArm": "Bip01 R Forearm", "RightHand": "Bip01 R Hand", "LeftUpLeg": "Bip01 L Thigh",
              "LeftLeg": "Bip01 L Calf", "LeftFoot": "Bip01 L Foot", "RightUpLeg": "Bip01 R Thigh",
              "RightLeg": "Bip01 R Calf", "RightFoot": "Bip01 R Foot"},
    "smpl": {"Hips": "Pelvis", "Spine": "Spine1", "Neck": "Neck", "Head": "Head", "LeftShoulder": "L_Collar",
             "LeftArm": "L_Shoulder", "LeftForeArm": "L_Elbow", "LeftHand": "L_Wrist", "RightShoulder": "R_Collar",
             "RightArm": "R_Shoulder", "RightForeArm": "R_Elbow", "RightHand": "R_Wrist", "LeftUpLeg": "L_Hip",
             "LeftLeg": "L_Knee", "LeftFoot": "L_Ankle", "RightUpLeg": "R_Hip", "RightLeg": "R_Knee",
             "RightFoot": "R_Ankle"},
}


def assert_human36m_proportions(joints: np.ndarray, name: str) -> None:
    for key, value in proportion_ratios(joints).items():
        assert 0.8 <= value <= 1.25, f"{name}: {key} is {value:.2f} of Human3.6M's"


def renamed_bvh(source: Path, names: dict[str, str], out: Path, *, frames: int = 120) -> Path:
    """``source`` with its joints renamed by ``names`` (others to ``joint<i>``), first ``frames`` frames."""
    lines = source.read_text().splitlines()
    counter = iter(range(1000))
    head_re = re.compile(r"^(\s*)(ROOT|JOINT)\s+(.+?)\s*$")
    out_lines = []
    motion_at = next(i for i, line in enumerate(lines) if line.strip() == "MOTION")
    for line in lines[:motion_at]:
        m = head_re.match(line)
        if m:
            line = f"{m.group(1)}{m.group(2)} {names.get(m.group(3), f'joint{next(counter)}')}"
        out_lines.append(line)
    dt = lines[motion_at + 2]
    out_lines += ["MOTION", f"Frames: {frames}", dt] + lines[motion_at + 3:motion_at + 3 + frames]
    out.write_text("\n".join(out_lines) + "\n")
    return out


@pytest.fixture(scope="module")
def bandai_dir(shared_dir: Path) -> Path:
    path = shared_dir / "data" / "bandai"
    assert path.is_dir(), f"missing {path}"
    return path


def test_joint_names_split_into_side_and_part():
    assert joint_name_parts("mixamorig:LeftUpLeg") == ("left", "upleg")
    assert joint_name_parts("UpperLeg_L") == ("left", "upperleg")
    assert joint_name_parts("thigh_r") == ("right", "thigh")
    assert joint_name_parts("L_Hip") == ("left", "hip")
    assert joint_name_parts("LeftHip") == ("left", "hip")
    assert joint_name_parts("Bip01 R Forearm") == ("right", "forearm")
    assert joint_name_parts("lThigh") == ("left", "thigh")
    assert joint_name_parts("Spine1") == ("", "spine1")
    assert joint_name_parts("Hips") == ("", "hips")


@pytest.mark.parametrize("name", BANDAI_CLIPS)
def test_bandai_rig_reads_with_human36m_proportions(bandai_dir, name):
    clip = bvh.read_bvh(bandai_dir / name)  # through lzma
    assert clip.names[:2] == ("joint_Root", "Hips") and all(len(c) == 6 for c in clip.channels if c)
    assert bvh.detect_rig(clip.names) is None
    motion = load_motion(bandai_dir / name)
    assert motion.fps == 30 and motion.label == name.split("_")[1]  # from the manifest above bvh/
    joints = motion.joints.astype(np.float64)
    assert_human36m_proportions(joints, name)
    # centimetres found: an adult's head point (Human3.6M's, below the crown; CMU 01_01 and 08_01: 1.50, 1.52 m)
    # over feet on the floor
    head = np.median(joints[:, H36M_17.index("head"), 2])
    assert 1.35 < head < 1.75, head
    ankles = joints[:, [H36M_17.index("right_ankle"), H36M_17.index("left_ankle")], 2].min(axis=1)
    assert np.percentile(ankles, 1) == pytest.approx(0.07, abs=1e-3)
    # the head-top point follows the head: above the neck/nose point, 11.5 cm of Human3.6M's leg scaled
    up = joints[:, H36M_17.index("head")] - joints[:, H36M_17.index("neck")]
    assert np.median(up[:, 2] / np.linalg.norm(up, axis=-1)) > 0.8


def test_bandai_walk_translation_is_on_hips(bandai_dir):
    joints = load_motion(bandai_dir / BANDAI_CLIPS[0]).joints
    pelvis = joints[:, 0, :2]
    assert np.linalg.norm(pelvis[-1] - pelvis[0]) > 1.5  # metres walked: the root joint alone stays at 0


def test_bandai_zero_head_end_site_points_along_the_head(bandai_dir):
    clip = bvh.read_bvh(bandai_dir / BANDAI_CLIPS[1])
    mapping, missing = map_joint_names(clip.names, clip.parents)
    assert not missing and mapping["head"] == "Head:end" and mapping["neck"] == "Head"
    assert np.linalg.norm(clip.offsets[clip.index("Head:end")]) == 0
    fixed = bvh.with_head_top(clip, mapping)
    np.testing.assert_allclose(fixed.offsets[fixed.index("Head:end")], clip.offsets[clip.index("Head")])


@pytest.mark.parametrize("convention", sorted(CONVENTIONS))
def test_renamed_capture_reads_like_the_known_rig(mocap_dir, tmp_path, convention):
    source = mocap_dir / "cmu" / "01_01.bvh"
    path = renamed_bvh(source, CONVENTIONS[convention], tmp_path / f"{convention}.bvh")
    clip = bvh.read_bvh(path)
    assert bvh.detect_rig(clip.names) is None
    named = bvh.canonical_positions(clip)
    assert named.rig == bvh.NAMED_JOINTS_RIG and named.unit == pytest.approx(0.0254 / 0.45)
    assert_human36m_proportions(named.joints, convention)
    ref = bvh.canonical_positions(bvh.read_bvh(source)).joints[:120]
    np.testing.assert_allclose(named.joints[:, LIMBS], ref[:, LIMBS], atol=1e-9)
    # thorax and spine from the shoulders and hips alike; neck/head along the head's own direction: within 10 cm
    assert np.abs(named.joints - ref).max() < 0.10


def test_unmappable_rig_is_one_line_then_a_rig_map_reads_it(mocap_dir, tmp_path):
    source = mocap_dir / "cmu" / "01_01.bvh"
    path = renamed_bvh(source, {}, tmp_path / "opaque.bvh")  # joint0, joint1, ...
    with pytest.raises(InputError) as err:
        load_motion(path)
    text = str(err.value)
    assert "\n" not in text and "opaque.bvh" in text
    assert "no joint found for pelvis, right_hip, right_knee" in text and "--rig-map" in text
    # the joints as the cmu-mb rig names them, by their index in the renamed file
    plain = bvh.read_bvh(source)
    renamed = bvh.read_bvh(path)
    rig_map = {point: renamed.names[plain.index(joint)] for point, joint in bvh.rig_joint_maps()["cmu-mb"].items()}
    map_file = tmp_path / "map.json"
    map_file.write_text(json.dumps(rig_map))
    motion = load_motion(path, rig_map=map_file)
    assert_human36m_proportions(motion.joints, "opaque with rig map")
    reference = load_motion(source).joints[:120]  # its floor from all frames: compare about the pelvis
    np.testing.assert_allclose(motion.joints[:, LIMBS] - motion.joints[:, :1],
                               reference[:, LIMBS] - reference[:, :1], atol=1e-5)


def test_rig_map_errors_are_one_line(mocap_dir, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"left_toe": "LeftToeBase"}')
    with pytest.raises(InputError, match="bad.json.*unknown body point.*left_toe"):
        bvh.read_rig_map(bad)
    absent = tmp_path / "absent.json"
    absent.write_text('{"left_hip": "Thigh.L"}')
    with pytest.raises(InputError, match="lacks: Thigh.L"):
        load_motion(mocap_dir / "cmu" / "01_01.bvh", rig_map=absent)
    broken = tmp_path / "clip.bvh.xz"
    broken.write_bytes(lzma.compress(b"HIERARCHY\n")[:20])
    with pytest.raises(InputError, match="clip.bvh.xz"):
        load_motion(broken)


def test_cli_rig_map_option(mocap_dir, tmp_path, capsys):
    source = mocap_dir / "cmu" / "01_01.bvh"
    path = renamed_bvh(source, {}, tmp_path / "opaque.bvh", frames=30)
    out = tmp_path / "out.gif"
    code = main(["render", str(path), "-o", str(out), "--size", "64", "--frames", "3", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "no joint found for" in err and not out.exists()
    plain, renamed = bvh.read_bvh(source), bvh.read_bvh(path)
    map_file = tmp_path / "map.json"
    map_file.write_text(json.dumps({p: renamed.names[plain.index(j)]
                                    for p, j in bvh.rig_joint_maps()["cmu-mb"].items()}))
    code = main(["render", str(path), "-o", str(out), "--size", "64", "--frames", "3", "--no-progress",
                 "--rig-map", str(map_file)])
    assert code == 0 and out.stat().st_size > 0
