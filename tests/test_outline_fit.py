"""The fitted body's surface moved onto the pictured person's outline (generator/outline_fit.py).

Known answers on discs and a small grid mesh; real parts: dancer.avi's first frame and its BlazePose segmentation,
woman_blue_tracksuit.jpg, Anny posed and rendered through OSMesa.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from motion2video.generator.outline_fit import (
    MAX_IN_M, MAX_OUT_M, outline_margin, outline_offsets, signed_distance, spread_over_mesh,
)

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")


def disc(radius: float, size: int = 64) -> np.ndarray:
    y, x = np.mgrid[:size, :size] + 0.5
    return (x - 32.0) ** 2 + (y - 32.0) ** 2 <= radius ** 2


def test_the_signed_distance_is_half_a_pixel_either_side_of_the_outline():
    mask = np.zeros((9, 9), bool)
    mask[2:7, 2:7] = True  # a 5 x 5 square
    sd = signed_distance(mask)
    assert sd[4, 4] == 2.5 and sd[2, 4] == 0.5 and sd[1, 4] == -0.5 and sd[0, 4] == -1.5


def test_points_on_the_fitted_outline_measure_how_far_the_person_reaches_past_it():
    """A body disc of radius 20 inside a person disc of radius 24: points on the body's outline measure +4 px, points
    inside it measure nothing; the person inside the body (radius 17) measures -3 px."""
    angles = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    on_outline = 32.0 + 20.0 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    inside = 32.0 + 8.0 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    offsets, measured = outline_offsets(np.concatenate([on_outline, inside]), disc(20), disc(24))
    assert measured[:24].all() and not measured[24:].any()
    np.testing.assert_allclose(offsets[:24], 4.0, atol=0.8)
    np.testing.assert_array_equal(offsets[24:], 0.0)
    offsets, _ = outline_offsets(on_outline, disc(20), disc(17))
    np.testing.assert_allclose(offsets, -3.0, atol=0.8)


def test_offsets_spread_over_the_surface_and_to_parts_no_edge_joins():
    """A strip of 2 x 11 vertices measured 0 at one end and 1 at the other takes values rising from end to end (the
    last smoothing rounds ease its ends a little); a triangle of its own (an eye) takes the value of the nearest
    vertex."""
    xs = np.arange(11, dtype=np.float64)
    strip = np.concatenate([np.stack([xs, np.zeros(11), np.zeros(11)], 1),
                            np.stack([xs, np.ones(11), np.zeros(11)], 1)])
    tris = [[i, i + 1, 11 + i] for i in range(10)] + [[i + 1, 12 + i, 11 + i] for i in range(10)]
    eye = np.array([[10.2, 0.3, 0.1], [10.4, 0.3, 0.1], [10.3, 0.5, 0.1]])
    points = np.concatenate([strip, eye])
    triangles = np.array(tris + [[22, 23, 24]])
    values = np.zeros(25)
    known = np.zeros(25, bool)
    known[[0, 11]] = True
    known[[10, 21]] = True
    values[[10, 21]] = 1.0
    spread = spread_over_mesh(values, known, triangles, points)
    row = spread[:11]
    assert (np.diff(row) > 0).all() and row[0] < 0.25 and row[-1] > 0.75 and abs(row[5] - 0.5) < 0.05
    np.testing.assert_allclose(spread[22:], spread[10], atol=1e-9)


def test_the_margin_is_a_pixel_at_128_and_scales():
    assert outline_margin(128) == 1 and outline_margin(256) == 2 and outline_margin(64) == 1


@pytest.fixture(scope="module")
def dancer_frames(dancer_video, tmp_path_factory):
    """dancer.avi's first frames at 128 and at 256 px, its track cached in a temporary folder (not the user's
    ~/.cache)."""
    from motion2video.evaluation.reconstruction import video_frames
    from tests.test_pose import _cut_video

    clip = _cut_video(dancer_video, tmp_path_factory.mktemp("clip") / "dancer30.avi", 30)
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.mktemp("cache")))
        return {size: video_frames(clip, size=size, targets=1) for size in (128, 256)}


@pytest.mark.slow
def test_the_dancer_s_fitted_body_takes_her_outline(dancer_frames):
    """dancer.avi's first frame at 128: Anny with its weight fitted to her mask covers it with IoU 0.77 (her loose
    suit reaches past it on her left); with its surface fitted to her outline, 0.9 and more."""
    from motion2video.core.camera import fit_camera, project
    from motion2video.generator.mesh_fit import fit_width, render_mesh_track
    from motion2video.stages.mesh_generation import video_mesh_track
    from motion2video.stages.structure import ALIGN_JOINTS, similarity_fit

    frames = dancer_frames[128]
    person = frames.masks[0]
    track, phenotype = video_mesh_track(frames.joints3d[:1], frames.points[:1], size=128, person_mask=person)
    fitted = track.masks[0]
    iou = (fitted & person).sum() / (fitted | person).sum()
    joints = np.asarray(frames.joints3d[:1], np.float64)
    camera = fit_camera(joints, 128, 128, elevation_deg=0.0)
    scale, shift = similarity_fit(project(joints, camera)[0, list(ALIGN_JOINTS), :2],
                                  frames.points[0][list(ALIGN_JOINTS)])
    width_only, _ = fit_width(joints[0], camera=camera, transform=(scale, shift), size=128, person_mask=person)
    before = render_mesh_track(joints, phenotype=width_only, camera=camera, transform=(scale, shift), size=128,
                               clear_arms=False).masks[0]
    iou_before = (before & person).sum() / (before | person).sum()
    assert iou_before < 0.82 and iou > 0.88 and iou > iou_before + 0.08


@pytest.mark.slow
def test_the_head_keeps_its_shape_and_no_vertex_moves_past_the_limits(photos_dir, monkeypatch):
    """woman_blue_tracksuit.jpg (long hair over one shoulder, hands in her pockets): the surface offsets of the
    reference fit move no head vertex and stay within [-MAX_IN_M, MAX_OUT_M], and the fitted body leaves her clothes
    no margin to grow by."""
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.stages import mesh_generation
    from motion2video.stages.generation import mesh_setup
    from motion2video.stages.reference import load_reference
    from motion2video.stages.structure import render_structures
    from renderers import anny_model
    from tests.test_head_paste import walk_forecast

    captured = {}
    fit = mesh_generation.outline_surface

    def keep(*args, **kwargs):
        captured["offsets"] = fit(*args, **kwargs)
        return captured["offsets"]

    monkeypatch.setattr(mesh_generation, "outline_surface", keep)
    reference = load_reference(photos_dir / "woman_blue_tracksuit.jpg", size=256, domain="body", crop_person=True)
    forecast = walk_forecast()
    net = load_frame_model("frames-body-mesh-256").model
    video = mesh_setup(net, reference, render_structures(forecast, domain="body", size=256, reference=reference))
    offsets = captured["offsets"]
    length = np.linalg.norm(offsets, axis=1)
    head = anny_model.head_vertices()
    assert length[head].max() == 0.0
    assert length.max() <= max(MAX_IN_M, MAX_OUT_M) + 1e-9
    assert video.margin == 0  # 4 px at 256 with the weight fitted alone


def test_core_sources_are_the_person_s_pixels_away_from_its_outline():
    """Known answer at 128 px: sources on the person's outline pixels are left out, sources 2 px inside kept; a
    region with too few sources inside keeps them all."""
    from motion2video.generator.mesh_flow import COLOUR_MIN_SOURCES, core_sources

    person = np.zeros((128, 128), bool)
    person[20:100, 30:90] = True
    n = COLOUR_MIN_SOURCES
    inner = np.stack([np.linspace(40, 80, n), np.full(n, 50.0)], axis=1)  # well inside
    edge = np.stack([np.full(n, 30.5), np.linspace(30, 90, n)], axis=1)  # the outline's first column
    few = np.stack([np.full(3, 30.5), [40.0, 50.0, 60.0]], axis=1)  # another region's, on the outline too
    uv = np.concatenate([inner, edge, few])
    regions = np.array([0] * (2 * n) + [1] * 3)
    kept = core_sources(uv, np.arange(len(uv)), person, regions)
    np.testing.assert_array_equal(kept, np.concatenate([np.arange(n), np.arange(2 * n, 2 * n + 3)]))


@pytest.mark.slow
def test_the_dancer_s_hidden_hair_takes_her_hair_not_the_blue_fringe(dancer_frames):
    """dancer.avi's first frame at 256: the hair vertices the reference hides (the back of her head), completed
    from shown hair on the person's outline, sampled the backdrop's blue fringe; from the person's core they do
    not."""
    from motion2video.generator.mesh_flow import complete_reference_uv
    from motion2video.generator.mesh_reference import on_person
    from motion2video.stages.mesh_generation import video_mesh_track
    from renderers import anny_model

    frames = dancer_frames[256]
    track, _ = video_mesh_track(frames.joints3d[:1], frames.points[:1], size=256, person_mask=frames.masks[0])
    seen = track.visible[0] & on_person(track.uv[0], frames.masks[0])
    hidden_hair = ~seen & (anny_model.vertex_regions() == anny_model.HAIR)
    assert hidden_hair.sum() > 100

    def blue_share(uv: np.ndarray) -> float:
        px = np.clip(np.floor(uv[hidden_hair]).astype(int), 0, 255)
        c = frames.images[0][px[:, 1], px[:, 0]].astype(int)
        return float(np.mean(c[:, 2] > c[:, 0] + 40))

    fringe = blue_share(complete_reference_uv(track.uv[0], seen, image=frames.images[0]))
    core = blue_share(complete_reference_uv(track.uv[0], seen, image=frames.images[0], person=frames.masks[0]))
    assert fringe > 0.3 and core < 0.02, (fringe, core)  # 0.45 and 0.00
