"""Inverse kinematics of the Anny body from canonical joints (renderers/body.py).

Pure rotation helpers are checked against their definitions; the IK is checked by self-consistency
(Anny's own rest joints give back Anny's rest mesh, a similarity transform of them gives the same
transform of the mesh), by exact placement of the limb joints on synthetic targets, against Anny's own
forward, and on a real walking clip (feet on the floor).
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.body import (
    axis_angle_to_matrix,
    frame_from_axes,
    matrix_from_quaternion,
    quaternion_from_matrix,
    slerp_rotations,
    swing_rotation,
)

RNG = np.random.default_rng(0)


def _random_rotations(n: int) -> np.ndarray:
    return axis_angle_to_matrix(RNG.normal(size=(n, 3)))


def test_swing_rotation_takes_a_to_b_without_twist():
    a = RNG.normal(size=(200, 3))
    b = RNG.normal(size=(200, 3))
    b[0] = -a[0]  # opposite directions
    b[1] = a[1] * 3.0  # same direction
    rot = swing_rotation(a, b)  # (200, 3, 3)
    a_hat = a / np.linalg.norm(a, axis=1, keepdims=True)
    b_hat = b / np.linalg.norm(b, axis=1, keepdims=True)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", rot, a_hat), b_hat, atol=1e-9)
    np.testing.assert_allclose(rot @ np.swapaxes(rot, 1, 2), np.broadcast_to(np.eye(3), rot.shape), atol=1e-9)
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-9)
    np.testing.assert_allclose(rot[1], np.eye(3), atol=1e-9)
    # No twist: the axis a x b is left in place.
    axis = np.cross(a_hat[2:], b_hat[2:])
    np.testing.assert_allclose(np.einsum("nij,nj->ni", rot[2:], axis), axis, atol=1e-9)
    # A zero-length direction gives the identity.
    np.testing.assert_allclose(swing_rotation(np.zeros(3), np.ones(3)), np.eye(3))


def test_frame_from_axes_is_right_handed_and_follows_its_axes():
    x, up = RNG.normal(size=(50, 3)), RNG.normal(size=(50, 3))
    frame = frame_from_axes(x, up)  # (50, 3, 3) columns x, y, z
    np.testing.assert_allclose(np.linalg.det(frame), 1.0, atol=1e-9)
    np.testing.assert_allclose(frame[:, :, 0], x / np.linalg.norm(x, axis=1, keepdims=True), atol=1e-9)
    assert np.all(np.einsum("ni,ni->n", frame[:, :, 2], up) > 0)
    # The rest convention: left = +x, up = +z gives the identity (the body faces -y).
    np.testing.assert_allclose(frame_from_axes(np.array([1.0, 0, 0]), np.array([0.3, 0, 1.0])), np.eye(3),
                               atol=1e-12)


def test_quaternions_round_trip_and_slerp_halves_the_angle():
    rot = _random_rotations(100)
    np.testing.assert_allclose(matrix_from_quaternion(quaternion_from_matrix(rot)), rot, atol=1e-9)
    a = _random_rotations(10)
    b = axis_angle_to_matrix(np.array([0.0, 0.0, np.pi / 2])) @ a  # 90 degrees about z after a
    half = slerp_rotations(a, b, 0.5)
    np.testing.assert_allclose(half, axis_angle_to_matrix(np.array([0.0, 0.0, np.pi / 4])) @ a, atol=1e-9)
    np.testing.assert_allclose(slerp_rotations(a, b, 0.0), a, atol=1e-9)
    np.testing.assert_allclose(slerp_rotations(a, b, 1.0), b, atol=1e-9)


def test_positive_yaw_turns_the_front_towards_the_left():
    # The body faces -y and its left is +x: +90 degrees about z takes the facing direction to the left.
    np.testing.assert_allclose(axis_angle_to_matrix(np.array([0, 0, np.pi / 2])) @ [0, -1, 0], [1, 0, 0],
                               atol=1e-12)


# --- with the Anny model -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def rest():
    from renderers import anny_model

    return anny_model.anny_rest()


@pytest.mark.slow
def test_rest_joints_give_back_the_rest_mesh(rest):
    from renderers.body import pose_anny_from_joints, posed_vertices

    pose = pose_anny_from_joints(rest.joints17)
    assert pose.scale == pytest.approx(1.0)
    np.testing.assert_allclose(pose.bone_poses[0], rest.bone_poses, atol=1e-9)
    (_, verts), = list(posed_vertices(pose))
    np.testing.assert_allclose(verts[0], rest.vertices, atol=1e-5)


@pytest.mark.slow
def test_similarity_transform_of_the_joints_moves_the_mesh_the_same_way(rest):
    from renderers.body import pose_anny_from_joints, posed_vertices

    rot = axis_angle_to_matrix(np.array([0.1, -0.2, 2.5]))
    scale, shift = 1.13, np.array([0.4, -1.5, 0.2])
    pose = pose_anny_from_joints(rest.joints17 @ rot.T * scale + shift, flat_feet=False)  # a tilted body
    assert pose.scale == pytest.approx(scale)
    (_, verts), = list(posed_vertices(pose))
    np.testing.assert_allclose(verts[0], rest.vertices @ rot.T * scale + shift, atol=1e-5)


@pytest.mark.slow
def test_limb_joints_land_exactly_on_synthetic_targets(rest):
    from renderers import anny_model
    from renderers.body import pose_anny_from_joints

    joints = rest.joints17.copy()
    # Left arm raised straight forward (-y) from the shoulder, right knee bent backwards.
    shoulder = joints[11]
    upper, lower = np.linalg.norm(joints[12] - joints[11]), np.linalg.norm(joints[13] - joints[12])
    joints[12] = shoulder + upper * np.array([0.0, -1.0, 0.0])
    joints[13] = joints[12] + lower * np.array([0.0, -1.0, 0.0])
    thigh, shin = np.linalg.norm(joints[2] - joints[1]), np.linalg.norm(joints[3] - joints[2])
    joints[2] = joints[1] + thigh * np.array([0.0, -0.5, -0.866])  # thigh forward 30 degrees
    joints[3] = joints[2] + shin * np.array([0.0, 0.5, -0.866])  # shin back
    pose = pose_anny_from_joints(joints, fit_scale=False)
    heads = pose.bone_poses[0, :, :3, 3]  # (104, 3)
    for joint, bone in ((12, "lowerarm01.L"), (13, "wrist.L"), (1, "upperleg01.R"), (2, "lowerleg01.R"),
                        (3, "foot.R")):
        np.testing.assert_allclose(heads[anny_model.bone_index(bone)], joints[joint], atol=1e-9)
    # The canonical pelvis (skeleton version 2) is the midpoint of the hips, where Anny's hips land.
    hips = heads[[anny_model.bone_index("upperleg01.L"), anny_model.bone_index("upperleg01.R")]].mean(axis=0)
    np.testing.assert_allclose(hips, joints[0], atol=1e-9)
    # The upper arm bone now points forward: its rotated rest direction matches the target.
    i, child = anny_model.bone_index("upperarm01.L"), anny_model.bone_index("lowerarm01.L")
    rest_dir = rest.bone_heads[child] - rest.bone_heads[i]
    rot = pose.bone_poses[0, i, :3, :3] @ rest.bone_poses[i, :3, :3].T
    direction = rot @ rest_dir
    np.testing.assert_allclose(direction / np.linalg.norm(direction), [0.0, -1.0, 0.0], atol=1e-9)


@pytest.mark.slow
def test_skinning_shortcut_equals_annys_forward(rest):
    import torch

    from renderers import anny_model
    from renderers.body import pose_anny_from_joints, skin_vertices

    phenotype = {"gender": 0.2, "height": 0.8, "weight": 0.7}
    joints = rest.joints17 + RNG.normal(scale=0.03, size=(3, 17, 3))
    pose = pose_anny_from_joints(joints, phenotype=phenotype)
    model = anny_model.get_anny()
    with torch.no_grad():
        ref = model(torch.as_tensor(pose.bone_poses), phenotype_kwargs=phenotype,
                    pose_parameterization="world")["vertices"].double().numpy()
    ours = skin_vertices(anny_model.anny_rest(phenotype), pose.bone_poses)
    np.testing.assert_allclose(ours, ref, atol=1e-9)


@pytest.mark.slow
def test_walking_feet_stay_on_the_floor(mocap_dir):
    from motion2video.formats.bvh import load_bvh
    from renderers.body import pose_anny_from_joints, posed_vertices

    motion = load_bvh(mocap_dir / "mass" / "mass_walk.bvh", manifest=True, target_fps=25)
    joints = motion.joints[::4]
    pose = pose_anny_from_joints(joints)
    lowest = np.concatenate([v[..., 2].min(axis=1) for _, v in posed_vertices(pose)])  # (T,)
    # In a walk one foot is always down: the mesh's lowest point stays within 3 cm of the floor (z = 0).
    assert np.all(np.abs(lowest) < 0.03), (lowest.min(), lowest.max())
