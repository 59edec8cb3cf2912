"""The fitted head of a reference picture moved onto the pictured eyes: a body fitted to a picture puts
its joints on the picture's joints, not its face on the pictured face.

Real parts: Anny's rest mesh and regions, its inverse kinematics and renders, BlazePose on the demo's reference.
"""

from __future__ import annotations

import os

import numpy as np

from motion2video.generator import mesh_reference
from motion2video.generator.mesh_reference import (FACE_HAIRLINE_M, MAX_FACE_SHIFT, align_face, crown_offset,
                                                face_weights, head_weights)

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")


def frontal_picture():
    """Anny's rest mesh seen from the front in pixels (x right, y down; 200 px a metre), every vertex shown; the
    centres of its two irises."""
    from renderers import anny_model

    rest = anny_model.anny_rest({})
    v = rest.vertices
    uv = np.stack([128.0 + 200.0 * v[:, 0], 400.0 - 200.0 * v[:, 2]], axis=1)
    iris = anny_model.vertex_regions(rest) == anny_model.IRIS
    centres = np.stack([uv[iris & (v[:, 0] > 0)].mean(axis=0), uv[iris & (v[:, 0] < 0)].mean(axis=0)])
    return rest, uv, np.ones(len(uv), bool), centres


def test_the_head_moves_onto_the_pictured_eyes_and_the_body_stays():
    from renderers import anny_model

    rest, uv, shown, irises = frontal_picture()
    moved, shift = align_face(uv, shown, irises + [3.0, -4.0], np.array([0.9, 0.9]), rest=rest)
    np.testing.assert_allclose(shift, [3.0, -4.0], atol=1e-6)
    head = anny_model.head_vertices()
    np.testing.assert_allclose(moved[head] - uv[head], np.broadcast_to([3.0, -4.0], (head.sum(), 2)), atol=1e-4)
    below_neck = rest.vertices[:, 2] < rest.bone_heads[anny_model.bone_index("neck01"), 2]
    np.testing.assert_array_equal(moved[below_neck], uv[below_neck])
    weights = head_weights(rest)
    neck = (weights > 0.05) & (weights < 0.95)  # the neck follows part of the way
    assert neck.sum() > 50
    np.testing.assert_allclose(moved[neck] - uv[neck], weights[neck, None] * [3.0, -4.0], atol=1e-4)


def test_the_face_follows_the_eyes_and_the_crown_the_pictured_head_top():
    """A fitted face too high under a crown in the right place (the demo's reference): the face moves, the hair
    stays."""
    from renderers import anny_model

    rest, uv, shown, irises = frontal_picture()
    moved, shift = align_face(uv, shown, irises + [2.0, 5.0], np.array([0.9, 0.9]), rest=rest, crown_dy=0.0)
    np.testing.assert_allclose(shift, [2.0, 5.0], atol=1e-6)
    head = anny_model.head_vertices()
    z = rest.vertices[:, 2]
    eyes = float(np.mean(z[anny_model.vertex_regions(rest) == anny_model.IRIS]))
    face, crown = head & (z <= eyes), head & (z >= eyes + FACE_HAIRLINE_M)
    assert face.sum() > 1000 and crown.sum() > 100
    np.testing.assert_allclose(moved[face] - uv[face], np.broadcast_to([2.0, 5.0], (face.sum(), 2)), atol=1e-4)
    np.testing.assert_allclose(moved[crown] - uv[crown], np.broadcast_to([2.0, 0.0], (crown.sum(), 2)), atol=1e-4)
    w = face_weights(rest)
    assert np.all(w[~head] == 0) and np.all((w >= 0) & (w <= 1))


def fitted_head_columns_40_to_60() -> tuple[np.ndarray, np.ndarray]:
    """(V, 2) vertex pixels whose head spans columns 40..60, and a (128, 128) fitted silhouette whose top is row 30
    over columns 38..62."""
    from renderers import anny_model

    head = anny_model.head_vertices()
    uv = np.zeros((len(head), 2))
    uv[head, 0] = np.linspace(40.0, 60.0, head.sum())
    silhouette = np.zeros((128, 128), bool)
    silhouette[30:100, 38:63] = True
    return uv, silhouette


def test_crown_offset_is_how_far_the_pictured_head_top_lies_below_the_fitted_one():
    from renderers import anny_model

    head = anny_model.head_vertices()
    uv, silhouette = fitted_head_columns_40_to_60()
    person = np.zeros((128, 128), bool)
    person[34:100, 36:65] = True
    assert crown_offset(uv, silhouette, person) == 4.0
    person[:, 50] = False  # a column without the person: no measure
    assert crown_offset(uv, silhouette, person) is None
    uv[head, 0] = 50.0  # a head one column wide: no measure
    assert crown_offset(uv, silhouette, silhouette) is None


def test_crown_offset_is_measured_where_the_face_moves_sideways():
    """A fitted head 20 px beside the pictured one: in its own columns it sees the person's shoulder, 44 px below its
    crown; in the columns its face moves to (dx) it sees the pictured head top, 4 px below."""
    uv, silhouette = fitted_head_columns_40_to_60()
    person = np.zeros((128, 128), bool)
    person[34:100, 56:85] = True  # the pictured head, 20 px to the right, its top 4 px lower
    person[74:100, 20:110] = True  # the shoulders
    assert crown_offset(uv, silhouette, person) == 44.0
    assert crown_offset(uv, silhouette, person, dx=20.0) == 4.0


def test_the_head_stays_where_the_eyes_are_unsure_unseen_or_too_far():
    rest, uv, shown, irises = frontal_picture()
    # BlazePose unsure of one eye
    assert align_face(uv, shown, irises + 2.0, np.array([0.9, 0.3]), rest=rest)[1] is None
    # the fitted mesh shows neither iris (a head turned away)
    from renderers import anny_model

    no_iris = shown & (anny_model.vertex_regions(rest) != anny_model.IRIS)
    same, shift = align_face(uv, no_iris, irises + 2.0, np.array([0.9, 0.9]), rest=rest)
    assert shift is None and same is uv
    # a shift longer than MAX_FACE_SHIFT eye distances is a wrong detection, not a fit error
    far = (MAX_FACE_SHIFT + 0.5) * np.linalg.norm(irises[0] - irises[1])
    assert align_face(uv, shown, irises + [0.0, far], np.array([0.9, 0.9]), rest=rest)[1] is None


def test_the_demo_references_fitted_irises_land_on_its_eyes(monkeypatch):
    """End to end on the demo's reference and its pose file, fitted as synthesize fits it."""
    from pathlib import Path

    from renderers import anny_model

    from motion2video.stages.generation import reference_person
    from tests.test_mesh_sampling_edges import fitted_reference

    root = Path(__file__).resolve().parents[1]

    def iris_offset(video, eyes):  # the iris discs' centres, shown or not (the fit alone hides one of them)
        iris = anny_model.vertex_regions() == anny_model.IRIS
        x = anny_model.anny_rest({}).vertices[:, 0]
        uv = video.reference.uv[0]
        centres = np.stack([uv[iris & (x > 0)].mean(axis=0), uv[iris & (x < 0)].mean(axis=0)])
        return float(np.linalg.norm(centres - eyes, axis=1).max())

    reference, video = fitted_reference(root / "demo_inputs" / "reference_body.png")
    found = reference_person(reference.image)
    eyes, visibility = found.eyes, found.eye_visibility
    assert (visibility > 0.5).all()
    x0, y0, side = video.crop
    eyes = (eyes - [x0, y0]) * 256 / side
    monkeypatch.setattr(mesh_reference, "move_face", lambda uv, *args, **kwargs: uv)  # the face left where fitted
    _, fitted = fitted_reference(root / "demo_inputs" / "reference_body.png")
    before, after = iris_offset(fitted, eyes), iris_offset(video, eyes)
    assert before > 3.0  # where the fit alone puts them
    assert after < 2.0
