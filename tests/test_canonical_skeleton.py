"""Skeleton version 2: "h36m-17" means Human3.6M's body points, whatever the source.

Known answers: Human3.6M's own skeleton is a fixed point of :func:`h36m_body_points`; a rig whose chest
joint sits mid-chest and whose head joint sits at the neck comes out with Human3.6M's proportions; every
source (real files of each rig, the procedural generator, the demo inputs, Anny) measures within 0.8-1.25 of
Human3.6M's four proportions; the bones the function builds keep their length; and a checkpoint trained on
the old definition is refused with one line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.core.skeletons import (H36M_BONES_MM, HEAD, L_SHOULDER, NECK, PELVIS, R_SHOULDER, SKELETON_VERSION,
                                         SPINE, THORAX, bone_lengths, check_skeleton_version, h36m_body_points,
                                         proportion_ratios)
from motion2video.formats.io import load_motion

DEMO = Path(__file__).resolve().parents[1] / "demo_inputs"
# One or two real files of every rig of ../shared/data/mocap (the per-file check of all 275 rows is in
# test_mocap_clips.py).
RIG_FILES = {
    "cmu-daz": ["cmu/08_01.bvh", "acrnn/salsa_01a.bvh"],
    "cmu-3dsmax": ["cmu/131_01.bvh"],
    "cmu-mb": ["cmu/01_01.bvh"],
    "cmu-amc": ["cmu/16_01.bvh"],
    "deepmimic-humanoid": ["deepmimic/humanoid3d_walk.bvh"],
    "deepmimic-humanoid-txt": ["deepmimic/txt/humanoid3d_walk.txt", "deepmimic-cmu/02_01.txt"],
    "mass-character1": ["mass/mass_walk.bvh"],
    "cmu-bench-expmap": ["cmu-bench/test/walking/walking_1.txt"],
    # a rig outside the known table, mapped from its joint names: Bandai-Namco's (../shared/data/bandai)
    "named-joints": ["../bandai/bvh/dataset-2_walk_normal_001.bvh.xz", "../bandai/bvh/dataset-1_bow_active_001.bvh.xz"],
}


def h36m_rest(scale: float = 0.001) -> np.ndarray:
    """(1, 17, 3) Human3.6M's skeleton (subject S1 bone lengths) standing straight, z up, in metres."""
    b = {k: v * scale for k, v in H36M_BONES_MM.items()}
    j = np.zeros((17, 3))
    j[1] = (-b["hip"], 0, 0)
    j[2] = j[1] - (0, 0, b["thigh"])
    j[3] = j[2] - (0, 0, b["shin"])
    j[4] = (b["hip"], 0, 0)
    j[5] = j[4] - (0, 0, b["thigh"])
    j[6] = j[5] - (0, 0, b["shin"])
    j[7] = (0, 0, b["pelvis_spine"])
    j[8] = j[7] + (0, 0, b["spine_thorax"])
    j[9] = j[8] + (0, 0, b["thorax_nose"])
    j[10] = j[9] + (0, 0, b["nose_head"])
    j[11] = j[8] + (b["thorax_shoulder"], 0, 0)
    j[12] = j[11] + (b["upper_arm"], 0, 0)
    j[13] = j[12] + (b["forearm"], 0, 0)
    j[14] = j[8] - (b["thorax_shoulder"], 0, 0)
    j[15] = j[14] - (b["upper_arm"], 0, 0)
    j[16] = j[15] - (b["forearm"], 0, 0)
    return j[None]


def test_human36m_itself_is_a_fixed_point():
    rest = h36m_rest()
    np.testing.assert_allclose(h36m_body_points(rest), rest, atol=1e-7)  # sqrt of a rounding-level residual
    assert proportion_ratios(rest) == pytest.approx(
        {"pelvis_thorax": 1.0, "thorax_nose": 1.0, "nose_head": 1.0, "thorax_shoulder": 1.0})


def test_a_cmu_like_rig_lands_on_human36m_points():
    """Thorax 17 cm below the shoulders, nose/head at the neck (as the CMU Daz rig had them)."""
    rest = h36m_rest()
    rig = rest.copy()
    rig[:, THORAX] -= (0, 0, 0.17)
    rig[:, NECK] = rest[:, THORAX] + (0, 0, 0.02)
    rig[:, HEAD] = rest[:, THORAX] + (0, 0.01, 0.09)  # the head joint at the top of the neck, tilted back
    out = h36m_body_points(rig)
    np.testing.assert_allclose(out[:, THORAX], rest[:, THORAX], atol=1e-9)
    for key, value in proportion_ratios(out).items():
        assert value == pytest.approx(1.0, abs=1e-9), key
    # the head keeps the rig's head direction
    d = out[0, HEAD] - out[0, NECK]
    raw = rig[0, HEAD] - rig[0, NECK]
    np.testing.assert_allclose(d / np.linalg.norm(d), raw / np.linalg.norm(raw), atol=1e-9)


def test_wide_shoulders_move_whole_arms_and_keep_them_rigid():
    rest = h36m_rest()
    wide = rest.copy()
    wide[:, [11, 12, 13]] += (0.06, 0, 0)
    wide[:, [14, 15, 16]] -= (0.06, 0, 0)
    out = h36m_body_points(wide)
    assert proportion_ratios(out)["thorax_shoulder"] == pytest.approx(1.2)
    np.testing.assert_allclose(bone_lengths(out)[:, [12, 13, 15, 16]], bone_lengths(wide)[:, [12, 13, 15, 16]], atol=1e-9)
    kept = h36m_body_points(wide, shoulder_band=None)
    np.testing.assert_allclose(kept[:, [L_SHOULDER, R_SHOULDER]], wide[:, [L_SHOULDER, R_SHOULDER]])


@pytest.mark.parametrize("rig", sorted(RIG_FILES))
def test_every_rig_has_human36m_proportions(mocap_dir, rig):
    for name in RIG_FILES[rig]:
        joints = load_motion(mocap_dir / name).joints
        ratios = proportion_ratios(joints)
        for key, value in ratios.items():
            assert 0.8 <= value <= 1.25, f"{name}: {key} is {value:.2f} of Human3.6M's"
        # The built bones keep their length over the clip (spine chain, neck, head, thorax-shoulder within
        # what the rig's own clavicles move).
        lengths = bone_lengths(joints)  # (T, 17)
        for joint in (SPINE, THORAX, NECK, HEAD):
            assert lengths[:, joint].std() < 2e-3, f"{name}: bone to joint {joint} varies"
        # The pelvis is the midpoint of the hips.
        np.testing.assert_allclose(joints[:, PELVIS], joints[:, [1, 4]].mean(axis=1), atol=1e-5)


@pytest.mark.parametrize("name", ["walk_to_run.npz", "jump.npz", "wave.npz", "squat_punch_turn.npz"])
def test_procedural_demo_inputs_have_human36m_proportions(name):
    for key, value in proportion_ratios(load_motion(DEMO / name).joints).items():
        assert 0.8 <= value <= 1.25, f"{name}: {key} is {value:.2f} of Human3.6M's"


@pytest.mark.slow
def test_anny_joints_have_human36m_proportions():
    from renderers import anny_model

    rest = anny_model.anny_rest()
    for key, value in proportion_ratios(rest.joints17[None]).items():
        assert 0.8 <= value <= 1.25, f"Anny: {key} is {value:.2f} of Human3.6M's"


def test_old_checkpoints_are_refused_with_one_line():
    check_skeleton_version("h36m-17", SKELETON_VERSION, "m.safetensors")  # the current one passes
    check_skeleton_version(None, None, "face.safetensors")  # no body skeleton: nothing to check
    with pytest.raises(InputError) as err:
        check_skeleton_version("h36m-17", None, "old.safetensors")
    message = str(err.value)
    assert "\n" not in message and "old.safetensors" in message and "version 1" in message


def test_shipped_body_checkpoints_record_the_current_version():
    from motion2video.models.checkpoint import load_model, read_meta, resolve_checkpoint
    from motion2video.generator.checkpoint import load_frame_model

    for name in ("mtvae-add", "mtvae-add-dlow", "lcpvae", "behavior", "mtvae-add-2d"):
        assert read_meta(resolve_checkpoint(name)).skeleton_version == SKELETON_VERSION, name
        load_model(name)
    load_frame_model("frames-body-128")
