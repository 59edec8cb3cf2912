"""The person's own face on Anny's head (motion2video.pose.face_shape): the offsets of one fit, spread over the head's
vertices, drawn by the face renderer; the two paintings of ../shared, the bundled face mesh, Anny, OSMesa renders."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.core.motion import FACE_DIM, FaceMotion
from motion2video.core.rotations import axis_angle_to_matrix
from motion2video.pose.face_fit import FrameFit, project
from motion2video.pose.face_shape import SHAPE_SIGMA_M, fit_offsets, spread_offsets


def test_the_offsets_of_a_fit_take_its_points_onto_the_pictured_ones_without_depth():
    rng = np.random.default_rng(0)
    points = rng.normal(size=(30, 3)) * 0.05
    fit = FrameFit(np.array([0.1, -0.2, 0.3]), 900.0, np.array([120.0, 80.0]), np.zeros(52), np.zeros(30))
    xy = project(points, fit.rotation, fit.scale, fit.shift) + rng.normal(size=(30, 2)) * 3.0
    offsets = fit_offsets(points, xy, fit)
    np.testing.assert_allclose(project(points + offsets, fit.rotation, fit.scale, fit.shift), xy, atol=1e-9)
    towards_camera = axis_angle_to_matrix(fit.rotation).T @ np.array([0.0, 1.0, 0.0])  # the view axis, rest frame
    np.testing.assert_allclose(offsets @ towards_camera, 0.0, atol=1e-12)


def test_spread_offsets_follow_the_points_smoothly_and_fade_away_from_them():
    grid = np.stack(np.meshgrid(np.linspace(0, 0.1, 11), np.linspace(0, 0.1, 11), [0.0]), -1).reshape(-1, 3)
    offsets = np.tile([0.002, -0.001, 0.0], (len(grid), 1))  # the whole face 2 mm to one side, 1 mm to the other
    inside = np.array([[0.05, 0.05, 0.0], [0.055, 0.045, 0.0]])
    far = np.array([[0.05, 0.05, 8 * SHAPE_SIGMA_M], [0.3, 0.3, 0.0]])
    out = spread_offsets(grid, offsets, np.concatenate([inside, far]))
    np.testing.assert_allclose(out[:2], offsets[:2], atol=2e-4)  # within a tenth of the offset inside the face
    np.testing.assert_allclose(out[2:], 0.0, atol=1e-6)  # the skull, the neck: Anny's own


@pytest.mark.slow
def test_the_face_renderer_draws_the_person_turned_with_the_head():
    from renderers.face import FaceRenderer, FaceStyle

    params = np.zeros((2, FACE_DIM), np.float32)
    params[1, 54] = 0.5  # the second frame turns the head about the vertical axis
    face = FaceMotion(params, 25.0)
    renderer = FaceRenderer(FaceStyle(size=(96, 96)))
    plain = renderer.render_with_masks(face, vertices=True)
    shape = np.zeros((plain.vertex_uv.shape[1], 3), np.float32)
    shape[:, 0] = 0.01  # 1 cm to the head's left... of every vertex
    moved = renderer.render_with_masks(face, camera=plain.camera, vertices=True, shape=shape)
    shift = (moved.vertex_uv - plain.vertex_uv)[:, np.abs(plain.vertex_uv).sum(axis=(0, 2)) > 0]  # drawn vertices
    assert np.median(shift[0, :, 0]) > 1.0 and abs(np.median(shift[0, :, 1])) < 0.2
    assert np.median(shift[1, :, 0]) < 0.95 * np.median(shift[0, :, 0])  # turned: seen foreshortened


@pytest.mark.slow
@pytest.mark.parametrize("name", ["portrait_mona_lisa.jpg", "portrait_pearl_earring.jpg"])
def test_a_portraits_own_face_brings_the_head_onto_its_landmarks(photos_dir, name):
    from motion2video.pose.face_portrait import fit_portrait
    from motion2video.stages.reference import read_reference_image

    portrait = fit_portrait(read_reference_image(photos_dir / name)[0])
    assert portrait.shaped_error() < 0.25 * portrait.relative_error()
