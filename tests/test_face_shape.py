"""A person's face shape on Anny's head (motion2video.pose.face_shape): MakeHuman's face targets fitted to landmarks,
drawn by the face renderer; the shipped targets, the two paintings of ../shared, the bundled face mesh, OSMesa."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.core.motion import FACE_DIM, FaceMotion
from motion2video.pose.face_anny import head_basis
from motion2video.pose.face_fit import FrameFit, project
from motion2video.pose.face_shape import (fit_shape, fit_shape_to_offsets, head_shape, shape_points, shape_targets,
                                          target_names)


def _some_face(seed: int) -> np.ndarray:
    """(K,) a face: a few targets at up to 0.6, the rest 0 (a pair's two sides never both)."""
    rng = np.random.default_rng(seed)
    coefficients = np.zeros(len(target_names()))
    pairs = rng.choice(len(target_names()) // 2, size=6, replace=False)
    coefficients[2 * pairs + rng.integers(0, 2, size=6)] = rng.uniform(0.2, 0.6, size=6)
    return coefficients


def test_the_targets_move_the_face_and_nothing_below_the_neck():
    from renderers import anny_model

    targets = shape_targets()
    rest = anny_model.anny_rest()
    assert targets.shapes.shape == (len(target_names()), len(rest.vertices), 3)
    moved = np.abs(targets.shapes).max(axis=(0, 2)) > 1e-3  # (V,) vertices a target moves by over a millimetre
    on_head = np.zeros(len(moved), bool)
    on_head[anny_model.head_vertices()] = True
    assert (moved & on_head).sum() > 1000
    neck = rest.bone_heads[anny_model.bone_index("neck01")]
    assert rest.vertices[moved, 2].min() > neck[2] - 0.05  # the chin's targets reach the neck, no further
    assert np.abs(targets.points).max(axis=(1, 2)).min() > 1e-4  # every target moves some tracked point


def test_a_pictured_face_shape_is_found_again_with_the_pose_held():
    """Points made from a known face, turned and projected: the fit (a tiny ridge) finds the face again."""
    basis = head_basis()
    truth = _some_face(1)
    fit = FrameFit(np.array([0.1, -0.3, 0.05]), 2500.0, np.array([250.0, 240.0]), np.zeros(52), np.zeros(470))
    xy = project(basis.neutral + shape_points(truth), fit.rotation, fit.scale, fit.shift)
    found = fit_shape(basis.neutral, xy, fit, ridge=1e-9)
    np.testing.assert_allclose(project(basis.neutral + shape_points(found), fit.rotation, fit.scale, fit.shift), xy,
                               atol=0.05)  # pixels, on a face of ~400
    assert found[truth > 0].min() > 0.5 * truth[truth > 0].min()


def test_the_ridge_keeps_an_unseen_face_at_anny_s():
    basis = head_basis()
    fit = FrameFit(np.zeros(3), 2500.0, np.array([250.0, 240.0]), np.zeros(52), np.zeros(470))
    xy = project(basis.neutral, fit.rotation, fit.scale, fit.shift)
    assert np.abs(fit_shape(basis.neutral, xy, fit)).max() < 1e-6
    assert np.abs(fit_shape_to_offsets(np.zeros((470, 3)))).max() < 1e-6


def test_a_video_s_person_offsets_give_their_face_in_the_face_s_plane():
    truth = _some_face(2)
    offsets = shape_points(truth)
    offsets[:, 1] = 0.0  # a video's offsets carry no depth
    found = fit_shape_to_offsets(offsets, ridge=1e-9)
    np.testing.assert_allclose(shape_points(found)[:, [0, 2]], offsets[:, [0, 2]], atol=2e-4)  # metres


@pytest.mark.slow
def test_the_face_renderer_draws_the_shape_turned_with_the_head():
    from renderers.face import FaceRenderer, FaceStyle

    params = np.zeros((2, FACE_DIM), np.float32)
    params[1, 54] = 0.5  # the second frame turns the head about the vertical axis
    face = FaceMotion(params, 25.0)
    renderer = FaceRenderer(FaceStyle(size=(96, 96)))
    plain = renderer.render_with_masks(face, vertices=True)
    shape = np.zeros((plain.vertex_uv.shape[1], 3), np.float32)
    shape[:, 0] = 0.01  # 1 cm to the head's left, every vertex
    moved = renderer.render_with_masks(face, camera=plain.camera, vertices=True, shape=shape)
    shift = (moved.vertex_uv - plain.vertex_uv)[:, np.abs(plain.vertex_uv).sum(axis=(0, 2)) > 0]  # drawn vertices
    assert np.median(shift[0, :, 0]) > 1.0 and abs(np.median(shift[0, :, 1])) < 0.2
    assert np.median(shift[1, :, 0]) < 0.95 * np.median(shift[0, :, 0])  # turned: seen foreshortened
    wide = renderer.render_with_masks(face, camera=plain.camera, shape=head_shape(
        np.eye(len(target_names()))[target_names().index("mouth-scale-horiz-incr")]))
    assert not np.array_equal(wide.frames[0], plain.frames[0])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["portrait_mona_lisa.jpg", "portrait_pearl_earring.jpg"])
def test_a_portraits_face_shape_brings_the_head_nearer_its_landmarks(photos_dir, name):
    from motion2video.pose.face_portrait import fit_portrait
    from motion2video.stages.reference import read_reference_image

    portrait = fit_portrait(read_reference_image(photos_dir / name)[0])
    assert portrait.relative_error() < 0.92 * portrait.plain_error()
    assert 0.0 < portrait.shape.max() < 0.6  # a face, not targets at their extremes


def test_a_reference_pose_keeps_its_face_shape(tmp_path):
    from motion2video.stages.reference import load_reference_pose, save_reference_pose

    pose = load_reference_pose(Path(__file__).resolve().parents[1] / "demo_inputs" / "reference_face.pose.npz")
    assert pose.face_shape is None
    shaped = type(pose)(**{**pose.__dict__, "face_shape": _some_face(3)})
    again = load_reference_pose(save_reference_pose(tmp_path / "f.pose.npz", shaped))
    np.testing.assert_allclose(again.face_shape, shaped.face_shape)
    bad = type(pose)(**{**pose.__dict__, "face_shape": np.full(3, 0.5)})
    with pytest.raises(InputError, match="face_shape"):
        load_reference_pose(save_reference_pose(tmp_path / "bad.pose.npz", bad))
