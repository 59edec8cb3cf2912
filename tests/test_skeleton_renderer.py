"""Skeleton maps, limb maps and heatmaps: real renderer, synthetic human-like motion, tiny images."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.core.motion import Motion
from motion2video.core.skeletons import COCO_17, H36M_17, H36M_32, OPENPOSE_18
from motion2video.testing.golden import synthetic_walk
from motion2video.core.camera import ImageFraming, fit_camera
from renderers.skeleton import (
    CENTRE_COLOUR,
    LEFT_COLOUR,
    OPENPOSE_COLOURS,
    RIGHT_COLOUR,
    HeatmapRenderer,
    HeatmapStyle,
    SkeletonRenderer,
    SkeletonStyle,
    colourise_heatmaps,
    draw_skeleton,
    gaussian_heatmaps,
    place_joints,
    render_limb_maps,
    to_openpose18,
)

SIZE = (128, 128)


@pytest.fixture(scope="module")
def walk() -> Motion:
    return synthetic_walk(12, fps=30.0, seed=3)


def _pixel(image: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """The pixel whose area contains continuous point xy."""
    return image[int(np.floor(xy[1])), int(np.floor(xy[0]))].astype(int)


def test_style_validation():
    with pytest.raises(InputError, match="palette"):
        SkeletonStyle(palette="rainbow")
    with pytest.raises(InputError, match="thickness"):
        SkeletonStyle(thickness=0)
    with pytest.raises(InputError, match="sigma"):
        HeatmapStyle(sigma=0.0)


def test_render_shape_and_determinism(walk):
    renderer = SkeletonRenderer(style=SkeletonStyle(size=(160, 120)))
    a = renderer.render(walk)
    b = renderer.render(walk.joints)  # raw array, default skeleton h36m-17
    assert a.shape == (12, 120, 160, 3) and a.dtype == np.uint8
    np.testing.assert_array_equal(a, b)
    assert a[0].any() and not a[0, 0, 0].any()  # something drawn on a black background


def test_left_right_colours_front_view(walk):
    """Front view: the body's right appears on the image's left and is drawn orange-red; left is green."""
    style = SkeletonStyle(size=SIZE, joint_radius=0)
    renderer = SkeletonRenderer(style=style)
    frames = renderer.render(walk)
    placed, _ = renderer.place(walk)
    for t in (0, 6):
        xy = placed.xy[t]
        assert xy[H36M_17.index("right_knee"), 0] < SIZE[0] / 2 < xy[H36M_17.index("left_knee"), 0]
        # Midpoint of the shin: pure limb colour (no joint discs drawn).
        right_mid = 0.5 * (xy[2] + xy[3])
        left_mid = 0.5 * (xy[5] + xy[6])
        spine_mid = 0.5 * (xy[0] + xy[7])
        assert np.abs(_pixel(frames[t], right_mid) - RIGHT_COLOUR).max() <= 2
        assert np.abs(_pixel(frames[t], left_mid) - LEFT_COLOUR).max() <= 2
        assert np.abs(_pixel(frames[t], spine_mid) - CENTRE_COLOUR).max() <= 2


def test_one_camera_per_sequence(walk):
    """The camera is fitted once to the whole clip: frame t alone, with that camera, matches frame t."""
    renderer = SkeletonRenderer(style=SkeletonStyle(size=SIZE))
    whole = renderer.render(walk)
    camera = fit_camera(walk.joints, *SIZE)
    np.testing.assert_array_equal(renderer.render(walk, camera=camera), whole)
    np.testing.assert_array_equal(renderer.render(walk.slice(5, 1), camera=camera)[0], whole[5])
    with pytest.raises(ValueError, match="camera is"):
        renderer.render(walk, camera=fit_camera(walk.joints, 64, 64))


def test_2d_input_framing_and_subpixel():
    """2D joints go through ImageFraming; coordinates keep sub-pixel precision; AA gives soft edges."""
    joints = np.zeros((1, 17, 2))
    joints[0, :, 0] = np.linspace(20, 100, 17)
    joints[0, :, 1] = 64.5
    style = SkeletonStyle(size=SIZE, thickness=1, joint_radius=0)
    renderer = SkeletonRenderer(style=style)
    identity = ImageFraming(1.0, (0.0, 0.0))
    base = renderer.render(joints, framing=identity)[0]
    assert base[64].any() and not base[60].any()  # the line lies on row 64
    shifted = joints.copy()
    shifted[..., 1] += 0.25
    moved = renderer.render(shifted, framing=identity)[0]
    assert not np.array_equal(base, moved)  # a quarter pixel changes the drawing
    values = np.unique(moved[:, 50].max(axis=-1))
    assert len(values) > 2  # anti-aliased: intermediate grey levels, not just 0 / colour
    fitted = renderer.place(joints * 3.0)[0]  # fit_image_framing once: centred in the image
    centre = 0.5 * (fitted.xy[0].min(axis=0) + fitted.xy[0].max(axis=0))
    np.testing.assert_allclose(centre, [64.0, 64.0], atol=1e-6)


def test_hidden_joints_are_not_drawn():
    joints = np.array([[[30.0, 30.0]] * 17])
    joints[0, 13] = [100.0, 100.0]  # left wrist far away
    style = SkeletonStyle(size=SIZE, joint_radius=2)
    full = draw_skeleton(np.zeros((128, 128, 3), np.uint8), joints[0], H36M_17, style)
    assert full[100, 100].any()
    depth = np.ones(17)
    depth[13] = -1.0  # behind the camera
    hidden = draw_skeleton(np.zeros((128, 128, 3), np.uint8), joints[0], H36M_17, style, depth=depth)
    nan = joints[0].copy()
    nan[13] = np.nan
    missing = draw_skeleton(np.zeros((128, 128, 3), np.uint8), nan, H36M_17, style)
    np.testing.assert_array_equal(hidden, missing)
    assert not hidden[70:, 70:].any()


def test_openpose_conversion(walk):
    op = to_openpose18(walk.joints, H36M_17)  # (T, 18, 3)
    assert op.shape == (12, 18, 3)
    j = walk.joints.astype(np.float64)
    np.testing.assert_allclose(op[:, OPENPOSE_18.index("neck")], 0.5 * (j[:, 11] + j[:, 14]))
    np.testing.assert_allclose(op[:, OPENPOSE_18.index("right_wrist")], j[:, 16])
    np.testing.assert_allclose(op[:, OPENPOSE_18.index("left_hip")], j[:, 4])
    # Eyes and ears are symmetric about the nose-head line; the left eye is on the left shoulder's side.
    nose = op[:, 0]
    lateral = j[:, 11] - j[:, 14]
    left_eye, right_eye = op[:, OPENPOSE_18.index("left_eye")], op[:, OPENPOSE_18.index("right_eye")]
    assert np.all(np.einsum("td,td->t", left_eye - nose, lateral) > 0)
    np.testing.assert_allclose(0.5 * (left_eye + right_eye), nose + 0.35 * (j[:, 10] - j[:, 9]), atol=1e-6)
    ear_gap = np.linalg.norm(op[:, 17] - op[:, 16], axis=-1)
    assert np.all((0.10 < ear_gap) & (ear_gap < 0.20))  # metres
    coco = np.random.default_rng(0).normal(size=(2, 17, 2))
    coco_op = to_openpose18(coco, COCO_17)
    np.testing.assert_allclose(coco_op[:, 1], 0.5 * (coco[:, 5] + coco[:, 6]))
    with pytest.raises(InputError, match="h36m-32"):
        to_openpose18(np.zeros((1, 32, 3)), H36M_32)


def test_openpose_palette_colours(walk):
    style = SkeletonStyle(size=(256, 256), palette="openpose", thickness=4, joint_radius=4)
    renderer = SkeletonRenderer(style=style)
    frames = renderer.render(walk)
    placed, skel = renderer.place(walk)
    assert skel is OPENPOSE_18
    xy = placed.xy[0]
    assert frames[0, 0, 0].tolist() == [0, 0, 0]
    # Keypoint k in full colour k; limb i at 60 % of colour i (right hip-knee is limb 7, colour (0,255,85)).
    assert np.abs(_pixel(frames[0], xy[4]) - OPENPOSE_COLOURS[4]).max() <= 2  # right wrist, yellow
    knee_mid = 0.5 * (xy[8] + xy[9])
    assert np.abs(_pixel(frames[0], knee_mid) - np.array([0, 153, 51])).max() <= 2
    # Same framing for both palettes: the right wrist lands on the same pixel.
    lr, _ = SkeletonRenderer(style=SkeletonStyle(size=(256, 256))).place(walk)
    np.testing.assert_allclose(lr.xy[:, 16], placed.xy[:, 4], atol=1e-9)


def test_gaussian_heatmaps():
    pts = np.array([[10.5, 20.5], [40.2, 7.9], [np.nan, 3.0]])
    h = gaussian_heatmaps(pts, (64, 32), 2.0)
    assert h.shape == (3, 32, 64) and h.dtype == np.float32
    assert h[0, 20, 10] == 1.0 and h[0].max() == 1.0
    ys, xs = np.mgrid[0:32, 0:64] + 0.5
    direct = np.exp(-((xs - 40.2) ** 2 + (ys - 7.9) ** 2) / (2 * 2.0**2))
    np.testing.assert_allclose(h[1], direct, atol=1e-6)
    assert not h[2].any()


def test_heatmap_renderer(walk):
    renderer = HeatmapRenderer(style=HeatmapStyle(size=(96, 80), sigma=2.0))
    maps = renderer.heatmaps(walk)
    assert maps.shape == (12, 17, 80, 96) and maps.dtype == np.float32
    placed = place_joints(walk.joints, (96, 80))
    t, j = 4, H36M_17.index("left_wrist")
    row, col = np.unravel_index(np.argmax(maps[t, j]), maps[t, j].shape)
    assert abs(col + 0.5 - placed.xy[t, j, 0]) <= 0.5 and abs(row + 0.5 - placed.xy[t, j, 1]) <= 0.5
    vis = renderer.render(walk)
    assert vis.shape == (12, 80, 96, 3) and vis.dtype == np.uint8
    np.testing.assert_array_equal(vis, colourise_heatmaps(maps))
    assert vis[0, 0, 0].max() < 10  # zero -> (almost) black
    assert vis[t, row, col].sum() > 500  # peak -> pale yellow


def test_limb_maps(walk):
    placed = place_joints(walk.joints, SIZE)
    maps = render_limb_maps(placed.xy, H36M_17, SIZE, thickness=3)
    assert maps.shape == (12, 16, 128, 128) and maps.dtype == np.float32
    assert 0.0 <= maps.min() and maps.max() == 1.0
    # Channel for bone (knee -> ankle) of the right leg is lit at its midpoint and nowhere near the left arm.
    bone = H36M_17.bones.index((2, 3))
    mid = 0.5 * (placed.xy[0, 2] + placed.xy[0, 3])
    assert maps[0, bone, int(mid[1]), int(mid[0])] > 0.5
    wrist = placed.xy[0, 13]
    assert maps[0, bone, int(wrist[1]), int(wrist[0])] == 0.0


def test_bench_render_smoke(tmp_path, monkeypatch):
    """scripts/bench.py render runs end to end (skeleton, heatmaps, mp4) and writes its keys."""
    import importlib
    import json
    from pathlib import Path

    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[1] / "scripts"))
    bench = importlib.import_module("bench")
    out = tmp_path / "bench.json"
    assert bench.main(["render", "--json", str(out), "--frames", "4", "--repeats", "1", "--warmup", "0", "--no-mesh",
                       "--no-long"]) == 0
    record = json.loads(out.read_text())
    for key in ("skeleton_vs_matplotlib", "mesh_reuse_vs_recreate", "mesh_fps", "mp4_fps", "machine", "versions"):
        assert key in record
    assert record["skeleton_vs_matplotlib"] > 0 and record["mp4_fps"] > 0
    assert record["details"]["skeleton"]["shared_pixels"] > 0.5  # both draw the same skeleton
    assert record["mesh_fps"] is None and record["mesh_reuse_vs_recreate"] is None  # --no-mesh
