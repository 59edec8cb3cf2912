"""renderers.collision: elbows and wrists moved out of Anny's torso before posing, on Anny's real rest mesh and real
CMU mocap."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.core.skeletons import L_ELBOW, L_WRIST, R_ELBOW, R_WRIST
from renderers import anny_model
from renderers.body import fitted_scale, pose_anny_from_joints, posed_vertices
from renderers.collision import ARM_RADIUS_M, arms_clear_of_torso, body_axes, push_out_of_torso, torso_shape

ARMS = [L_ELBOW, L_WRIST, R_ELBOW, R_WRIST]


@pytest.fixture(scope="module")
def rest():
    return anny_model.anny_rest({})


def test_the_torso_shape_is_annys_waist_and_chest(rest):
    """The cross-sections measured on the rest mesh: 26-32 cm wide and 16-22 cm deep for the default phenotype."""
    torso = torso_shape(rest)
    assert torso.s.shape == (10,) and np.all(np.diff(torso.s) > 0)
    assert np.all((2 * torso.half_width > 0.24) & (2 * torso.half_width < 0.34))
    assert np.all((2 * torso.half_depth > 0.15) & (2 * torso.half_depth < 0.23))


def test_a_wrist_inside_the_belly_lands_on_the_outline_and_one_outside_stays(rest):
    """A wrist at the middle of the waist moves sideways out to the grown ellipse; one beside the body, or above the
    thorax, does not move."""
    joints = rest.joints17[None].copy()
    torso = torso_shape(rest)
    pelvis, spine, lateral, front = body_axes(joints)
    inside = pelvis + 0.5 * spine + 0.02 * lateral + torso.centre[5] * front
    outside = pelvis + 0.5 * spine + 0.30 * lateral
    above = pelvis + 1.2 * spine
    points = np.concatenate([inside, outside, above])
    frames = np.repeat(joints, 3, axis=0)
    moved = push_out_of_torso(points, frames, torso, scale=1.0, radius=ARM_RADIUS_M)
    np.testing.assert_array_equal(moved[1:], points[1:])
    d = moved[0] - pelvis[0]
    x, z = d @ lateral[0], d @ front[0]
    a = np.interp(0.5, torso.s, torso.half_width) + ARM_RADIUS_M
    b = np.interp(0.5, torso.s, torso.half_depth) + ARM_RADIUS_M
    c = np.interp(0.5, torso.s, torso.centre)
    assert np.hypot(x / a, (z - c) / b) == pytest.approx(1.0)
    assert x > 0.1 and abs(d @ spine[0] / (spine[0] @ spine[0]) - 0.5) < 1e-9  # out to the side, at its height


def test_real_walks_move_the_arms_little_and_nothing_else(rest, mocap_dir):
    """CMU 02_01 (a walk, the hands brushing the hips of Anny's wider body): only elbows and wrists move, by a few
    centimetres (median 2.7 cm, at most 12 cm, 2026-11-26), and afterwards none of them is inside the grown torso."""
    from motion2video.formats.io import load_motion

    joints = np.asarray(load_motion(mocap_dir / "cmu" / "02_01.bvh").joints, np.float64)
    scale = fitted_scale(joints, rest)
    out = arms_clear_of_torso(joints, rest, scale=scale)
    others = [i for i in range(17) if i not in ARMS]
    np.testing.assert_array_equal(out[:, others], joints[:, others])
    move = np.linalg.norm(out - joints, axis=-1)[:, ARMS]
    assert 0.5 < (move > 0).any(axis=1).mean() and np.median(move[move > 0]) < 0.05 and move.max() < 0.16
    torso = torso_shape(rest)
    for i in ARMS:
        again = push_out_of_torso(out[:, i], out, torso, scale=scale, radius=ARM_RADIUS_M * scale * 0.999)
        np.testing.assert_allclose(again, out[:, i])


def test_a_forearm_across_the_belly_no_longer_sinks_into_the_posed_mesh(rest):
    """The posed mesh itself (Anny's pose solver and skinning, not the joint model): an elbow at the waist and a
    forearm of Anny's length pointing into the belly, as a narrower mocap actor's can. Counted against Anny's
    torso cross-sections without the arm's radius: most forearm and hand vertices are inside before, and after the
    correction neither is."""
    joints = rest.joints17[None].copy()
    torso = torso_shape(rest)
    pelvis, spine, lateral, front = body_axes(joints)
    elbow = pelvis[0] + 0.55 * spine[0] - 0.17 * lateral[0] + torso.centre[5] * front[0]
    belly = pelvis[0] + 0.35 * spine[0] + torso.centre[3] * front[0]
    forearm = np.linalg.norm(rest.joints17[R_WRIST] - rest.joints17[R_ELBOW])
    joints[0, R_ELBOW] = elbow
    joints[0, R_WRIST] = elbow + forearm * (belly - elbow) / np.linalg.norm(belly - elbow)
    names, dominant = anny_model.bone_names(), anny_model.dominant_bones()
    fore = np.isin(dominant, [names.index("lowerarm01.R"), names.index("lowerarm02.R")])
    hand = np.isin(dominant, [i for i, n in enumerate(names) if n == "wrist.R" or n.startswith("finger")
                              and n.endswith(".R")])

    def inside(j: np.ndarray, part: np.ndarray) -> int:
        (_, verts), = list(posed_vertices(pose_anny_from_joints(j, fit_scale=False)))
        d = verts[0][part] - pelvis[0]
        s = d @ spine[0] / (spine[0] @ spine[0])
        r = np.hypot(d @ lateral[0] / np.interp(s, torso.s, torso.half_width),
                     (d @ front[0] - np.interp(s, torso.s, torso.centre)) / np.interp(s, torso.s, torso.half_depth))
        return int(((s >= 0) & (s <= 1) & (r < 1)).sum())

    cleared = arms_clear_of_torso(joints, rest, scale=1.0)
    # 170 of 241 forearm and 470 of 1,438 hand vertices inside before, none after (2026-11-26)
    assert inside(joints, fore) > 0.5 * fore.sum() and inside(joints, hand) > 0.25 * hand.sum()
    assert inside(cleared, fore) < 0.05 * fore.sum() and inside(cleared, hand) < 0.05 * hand.sum()


@pytest.mark.slow
def test_render_mesh_track_moves_the_arms_only_in_the_frames_it_is_told(rest):
    """synthesize poses the reference picture's own pose and the motion together: the picture's arms are where
    they are pictured (frame 0 left alone), the motion's are moved out of the torso."""
    from motion2video.core.camera import fit_camera
    from motion2video.generator.mesh_fit import render_mesh_track

    joints = rest.joints17[None].copy()
    pelvis, spine, lateral, front = body_axes(joints)
    joints[0, R_WRIST] = pelvis[0] + 0.45 * spine[0] - 0.03 * lateral[0]  # a wrist in the belly
    both = np.concatenate([joints, joints])
    camera = fit_camera(both.reshape(-1, 3), 96, 96, margin=0.3)
    track = render_mesh_track(both, phenotype={}, camera=camera, transform=(1.0, np.zeros(2)), size=96,
                              clear_arms=np.array([False, True]))
    alone = render_mesh_track(joints, phenotype={}, camera=camera, transform=(1.0, np.zeros(2)), size=96,
                              clear_arms=False)
    np.testing.assert_array_equal(track.uv[0], alone.uv[0])
    hand = anny_model.hand_vertices("R")
    assert np.median(np.linalg.norm(track.uv[1][hand] - track.uv[0][hand], axis=1)) > 1.0  # pixels at 96
