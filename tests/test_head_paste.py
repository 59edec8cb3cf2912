"""The photo's own face laid over the generated heads.

Real parts: photos of ../shared/data/photos, BlazePose and MediaPipe's face detector and face mesh on them, the
demo's motion-capture walk, Anny rendered through OSMesa, the shipped mesh generator.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.generator.head_paste import (
    MATTE_FEATHER, MATTE_SHRINK, TURN_NONE_DEG, face_matte, paste_head, paste_weight,
)

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

ROOT = Path(__file__).resolve().parents[1]
SIZE = 256


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    err = np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2)
    return float(10 * np.log10(255.0 ** 2 / max(err, 1e-12)))


def walk_forecast(turn_deg: tuple[float, ...] = (0.0, 0.0, 0.0)):
    """The demo's walk, frames 0..3; target i (future frames 1..3) turned by ``turn_deg[i]`` about the vertical axis
    through its pelvis."""
    from motion2video.stages.sampling import Forecast

    walk = np.asarray(np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"], np.float64)[:4].copy()
    for i, deg in enumerate(turn_deg):
        a = np.radians(deg)
        rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        pelvis = walk[1 + i, 0].copy()
        walk[1 + i] = (walk[1 + i] - pelvis) @ rot.T + pelvis
    return Forecast(observed=walk[:1], futures=walk[None, 1:], fps=25.0, layout="body3d", model="test", seed=0)


@pytest.fixture(scope="module")
def net():
    from motion2video.generator.checkpoint import load_frame_model

    return load_frame_model("frames-body-mesh-256").model


@pytest.fixture(scope="module")
def tracksuit(photos_dir):
    from motion2video.stages.reference import load_reference

    return load_reference(photos_dir / "woman_blue_tracksuit.jpg", size=SIZE, domain="body", crop_person=True)


def mesh_video_of(net, reference, forecast):
    from motion2video.stages.generation import mesh_setup
    from motion2video.stages.structure import render_structures

    return mesh_setup(net, reference, render_structures(forecast, domain="body", size=SIZE, reference=reference))


def moved_face(image: np.ndarray, face, affine: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(SIZE, SIZE, 3) float: the reference ``image`` warped by scikit-image's piecewise-affine transform that takes
    the ``face``'s landmarks to their places moved by ``affine`` and bent by ``offsets`` (L, 2), as the face is laid
    (inside the landmarks' hull)."""
    from skimage.transform import PiecewiseAffineTransform, warp

    from motion2video.stages.pictured_face import landmarks_in_reference

    landmarks = landmarks_in_reference(face)
    to_image = PiecewiseAffineTransform.from_estimate(landmarks @ affine[:, :2].T + affine[:, 2] + offsets - 0.5,
                                                      landmarks - 0.5)
    assert to_image
    return warp(image.astype(np.float64) / 255.0, to_image, output_shape=(SIZE, SIZE), order=1) * 255.0


def face_core(face, affine: np.ndarray, offsets: np.ndarray, shown: np.ndarray | None = None) -> np.ndarray:
    """(SIZE, SIZE) bool: where the ``face``'s matte, moved by ``affine``, is over 0.99, and (with ``shown`` (L,)
    bool) the triangles of the face the target shows, bent by ``offsets``, cover the pixel fully."""
    from motion2video.generator.head_paste import compose_affine, pixel_index_affine, shown_face
    from motion2video.stages.pictured_face import landmark_triangles, landmarks_in_reference

    move = compose_affine(affine, face.to_reference)  # photo square -> frame
    core = cv2.warpAffine(face.matte, pixel_index_affine(move), (SIZE, SIZE), flags=cv2.INTER_LINEAR) > 0.99
    if shown is not None:
        where = landmarks_in_reference(face) @ affine[:, :2].T + affine[:, 2] + offsets
        core &= shown_face(where, landmark_triangles(), shown, (SIZE, SIZE)) > 0.99
    return core


def assert_face_laid_over(frame: np.ndarray, own: np.ndarray, image: np.ndarray, face, affine: np.ndarray,
                          offsets: np.ndarray, shown: np.ndarray | None = None, *, min_psnr: float = 25.0) -> None:
    """``frame`` carries the pictured ``face`` moved by ``affine`` (reference pixels -> frame pixels) and bent by
    ``offsets`` (L, 2) (head_paste.FaceBend): its pixels over the face's core (:func:`face_core`, where the target
    shows it: ``shown`` (L,) bool, None for all) are the reference ``image`` moved the same way (:func:`moved_face`,
    PSNR > ``min_psnr``), it differs from the generator's ``own`` frame only within the moved landmarks' box grown
    by a third, and a face detector finds the face in the head's square enlarged."""
    from motion2video.stages.pictured_face import face_mesh, landmarks_in_reference

    core = face_core(face, affine, offsets, shown)
    assert core.sum() > 40 and psnr(frame[core], moved_face(image, face, affine, offsets)[core]) > min_psnr
    target_lm = landmarks_in_reference(face) @ affine[:, :2].T + affine[:, 2] + offsets
    lo, hi = target_lm.min(axis=0), target_lm.max(axis=0)
    grow = (hi - lo) / 3
    changed = np.argwhere(np.any(frame != own, axis=-1))[:, ::-1] + 0.5  # (x, y)
    assert len(changed) > 40 and (changed >= lo - grow).all() and (changed <= hi + grow).all()
    x0, y0 = np.floor(lo - (hi - lo)).astype(int)
    side = int(np.ceil(3 * np.max(hi - lo)))
    square = cv2.resize(frame[max(0, y0):y0 + side, max(0, x0):x0 + side], (192, 192), interpolation=cv2.INTER_CUBIC)
    assert face_mesh().detect(np.ascontiguousarray(square)), "no face found on the head"


def test_the_face_is_found_at_the_photos_own_resolution(tracksuit):
    """On a 1080 x 1920 photo cut to its person and resized to 256, her face is some 14 px wide; the face is looked
    for in the photo as given, where the square around her head is 5.6 times larger, and mapped into the 256 px
    picture onto her eyes."""
    from motion2video.stages.pictured_face import landmarks_in_reference, reference_face

    face = reference_face(tracksuit)
    assert face is not None and face.score > 0.9
    assert tracksuit.source is not None and face.image.shape[0] > 4 * (face.to_reference[0, 0] * face.image.shape[0])
    assert np.isclose(face.to_reference[0, 0], tracksuit.source_scale)
    lm = landmarks_in_reference(face)
    width = np.ptp(lm[:, 0])
    assert 8 < width < 30  # the face in the 256 px picture (14.3 px)
    # BlazePose's eyes (found on the 256 px picture) lie on the face mesh's eyes, mapped from the photo
    eyes = tracksuit.person.eyes  # (2, 2) her left and right eye
    mesh_eyes = np.stack([lm[[362, 263]].mean(axis=0), lm[[33, 133]].mean(axis=0)])  # the mesh's left, right eye
    assert np.linalg.norm(eyes - mesh_eyes, axis=1).max() < 0.1 * width  # 0.6 px
    # the matte is the face, not the hair or the wall: its pixels are skin-coloured (red over blue), none is the wall
    inside = face.matte > 0.9
    pixels = face.image[inside].astype(np.int64)
    assert inside.sum() > 500 and np.mean(pixels[:, 0] > pixels[:, 2] + 15) > 0.8


def test_pasting_the_face_where_it_was_gives_the_photo_back_and_touches_nothing_else(tracksuit):
    """Laid over a grey frame by its own map to the reference picture, the face is the reference picture's face
    (the photo shrunk by area to 256, as the reference is): PSNR over the face's core 35.8 dB (33.2 dB warped
    bilinearly); moved by a quarter pixel it falls to 26-28 dB, so the map keeps the pixel grid. Where the warped
    matte is 0 the frame is untouched, to the bit."""
    from motion2video.stages.pictured_face import reference_face

    from motion2video.generator.head_paste import pixel_index_affine

    face = reference_face(tracksuit)
    grey = np.full((SIZE, SIZE, 3), 128, np.uint8)
    out = paste_head(grey, face.image, face.matte, face.to_reference, 1.0)

    alpha = cv2.warpAffine(face.matte, pixel_index_affine(face.to_reference), (SIZE, SIZE), flags=cv2.INTER_LINEAR)
    core = alpha > 0.99
    assert core.sum() > 60
    assert psnr(out[core], tracksuit.image[core]) > 34.5  # 35.8 dB
    untouched = cv2.dilate((alpha > 0).astype(np.uint8), np.ones((3, 3), np.uint8)) == 0
    np.testing.assert_array_equal(out[untouched], grey[untouched])
    assert untouched.mean() > 0.98  # 0.989: the face and its feather are about 1% of the frame
    np.testing.assert_array_equal(paste_head(grey, face.image, face.matte, face.to_reference, 0.0), grey)


def test_a_walk_carries_the_photos_face_and_changes_nothing_outside_the_head(net, tracksuit):
    """synthesize's mesh path: the photo walks. In each frame the face lies where the fitted head's face points go
    (a detector finds it there), its pixels are the photo's face moved (PSNR against the photo's face mapped by the
    same move: 27-29 dB over the face's core), and the frame differs from the generator's own frame only inside the
    head's square."""
    from dataclasses import replace

    from motion2video.stages.generation import mesh_frames
    from motion2video.stages.structure import render_structures

    forecast = walk_forecast()
    structures = render_structures(forecast, domain="body", size=SIZE, reference=tracksuit)
    video = mesh_video_of(net, tracksuit, forecast)
    assert video.face is not None
    np.testing.assert_array_less(0.99, video.head.weights)  # a walk towards the camera: the face fully laid over
    rows = np.arange(3)
    with_face = mesh_frames(net, tracksuit, structures, video, rows)
    without = mesh_frames(net, tracksuit, structures, replace(video, face=None), rows)
    for i in rows:
        assert_face_laid_over(with_face[i], without[i], tracksuit.image, video.face, video.head.affines[i],
                              video.head.offsets[i])


def test_a_head_turned_35_degrees_carries_the_photos_face_bent_to_the_turn(net, tracksuit):
    """A walk's stride swings the head by up to 40 degrees: the demo walk's futures turned by 35 degrees about the
    vertical still take the face fully (a detector finds it; where the target shows it, its pixels are the photo's
    face moved and bent by the landmarks' offsets: 23-33 dB, against 19-21 dB for the photo moved by the affine map
    alone)."""
    from dataclasses import replace

    from motion2video.stages.generation import mesh_frames
    from motion2video.stages.structure import render_structures

    forecast = walk_forecast((35.0, 35.0, 35.0))
    structures = render_structures(forecast, domain="body", size=SIZE, reference=tracksuit)
    video = mesh_video_of(net, tracksuit, forecast)
    np.testing.assert_array_equal(video.head.weights, 1.0)
    rows = np.arange(1, 4)
    with_face = mesh_frames(net, tracksuit, structures, video, rows)
    without = mesh_frames(net, tracksuit, structures, replace(video, face=None), rows)
    for i, row in enumerate(rows):
        affine, offsets, shown = video.head.affines[row], video.head.offsets[row], video.head.shown[row]
        assert_face_laid_over(with_face[i], without[i], tracksuit.image, video.face, affine, offsets, shown,
                              min_psnr=22.0)
        core = face_core(video.face, affine, offsets, shown)
        bent = psnr(with_face[i][core], moved_face(tracksuit.image, video.face, affine, offsets)[core])
        flat = psnr(with_face[i][core], moved_face(tracksuit.image, video.face, affine, 0 * offsets)[core])
        assert bent > flat + 3.0, (bent, flat)


def test_a_head_turned_away_from_the_photos_view_keeps_the_generators_head(net, tracksuit):
    """The same walk with its future frames turned by 0, 90 and 180 degrees about the vertical: the face is laid over
    the first fully (its head 18.5 degrees from the photo's view), not at all over the other two (85 and 173 degrees:
    a profile or the back of the head is not the pictured face), and those frames are the generator's own."""
    from dataclasses import replace

    from motion2video.stages.generation import mesh_frames
    from motion2video.stages.structure import render_structures

    forecast = walk_forecast((0.0, 90.0, 180.0))
    structures = render_structures(forecast, domain="body", size=SIZE, reference=tracksuit)
    video = mesh_video_of(net, tracksuit, forecast)
    # targets: the observed frame, then the futures turned by 0, 90, 180 degrees
    np.testing.assert_array_equal(video.head.weights, [1.0, 1.0, 0.0, 0.0])
    rows = np.array([2, 3])
    np.testing.assert_array_equal(mesh_frames(net, tracksuit, structures, video, rows),
                                  mesh_frames(net, tracksuit, structures, replace(video, face=None), rows))


def test_a_photo_without_a_face_keeps_the_generators_head(photos_dir, tracksuit):
    """The photo with her head painted over by its background (no face left where the body puts the head): nothing
    is found, and the mesh video carries no face."""
    from dataclasses import replace

    from motion2video.generator.background import inpaint_background
    from motion2video.stages.pictured_face import head_square, reference_face

    source = tracksuit.source.copy()
    size = tracksuit.image.shape[0]
    points = (np.asarray(tracksuit.pose.points) * size / tracksuit.pose.width - tracksuit.source_offset) \
        / tracksuit.source_scale
    x0, y0, side = head_square(points)
    hole = np.zeros(source.shape[:2], np.float32)
    cx, cy = x0 + side / 2, y0 + side / 2
    cv2.circle(hole, (int(cx), int(cy)), int(side * 0.3), 1.0, -1)
    faceless = inpaint_background(source, hole, grow_px=2)
    assert reference_face(replace(tracksuit, source=faceless)) is None


def test_the_paste_weight_falls_with_the_turn_and_the_hidden_face():
    assert paste_weight(0.0, 1.0) == 1.0
    assert paste_weight(TURN_NONE_DEG, 1.0) == 0.0 and paste_weight(0.0, 0.3) == 0.0 and paste_weight(0.0, 0.6) == 1.0
    turns = np.linspace(0, 60, 13)
    weights = [paste_weight(t, 1.0) for t in turns]
    assert (np.diff(weights) <= 0).all() and 0 < paste_weight(45.0, 1.0) < 1


def test_the_face_matte_is_the_hull_feathered(tracksuit):
    from motion2video.stages.pictured_face import reference_face

    face = reference_face(tracksuit)
    matte = face_matte(face.landmarks, face.image.shape[:2])
    hull = np.zeros(face.image.shape[:2], np.uint8)
    cv2.fillConvexPoly(hull, cv2.convexHull(np.round(face.landmarks - 0.5).astype(np.int32)), 1)
    assert matte.min() >= 0 and matte.max() <= 1
    assert matte[hull == 0].max() < 0.5  # outside the hull it fades out
    size = np.ptp(face.landmarks, axis=0).max()
    reach = int(np.ceil((MATTE_SHRINK + 3 * MATTE_FEATHER) * size))  # the shrink and three feather widths
    deep = cv2.erode(hull, np.ones((2 * reach + 1, 2 * reach + 1), np.uint8)) > 0
    assert deep.sum() > 1000 and matte[deep].min() > 0.99  # deep inside it is 1


def test_a_reframed_reference_keeps_its_face_on_its_eyes(tracksuit):
    """--fit-view re-frames the reference (zoomed out to 1.5 times, panned): the face found in the photo still lands on
    the eyes BlazePose found, moved with the picture."""
    from motion2video.stages.pictured_face import landmarks_in_reference, reference_face
    from motion2video.stages.reference import zoom_to_view

    zoomed = zoom_to_view(tracksuit, (-64.0, -40.0, 384.0))
    face = reference_face(zoomed)
    assert face is not None
    lm = landmarks_in_reference(face)
    mesh_eyes = np.stack([lm[[362, 263]].mean(axis=0), lm[[33, 133]].mean(axis=0)])
    width = np.ptp(lm[:, 0])
    assert 5 < width < 14  # two thirds of the 14 px face
    assert np.linalg.norm(zoomed.person.eyes - mesh_eyes, axis=1).max() < 0.1 * width


# --- the keypoint warp (frames-body-128): the face moved as the warp moves the head ------------------------------

def test_the_head_s_affine_is_the_inverse_of_the_warp_s_head_field():
    """A reference pixel moved by segment_affine is the target pixel whose head field (part_maps) samples it."""
    import torch

    from motion2video.generator.warp import SEGMENT_PARTS, part_maps, segment_affine

    rng = np.random.default_rng(0)
    ref = rng.uniform(20, 100, size=(3, 17, 2))
    tgt = ref + rng.normal(scale=6.0, size=ref.shape)
    maps = part_maps(torch.as_tensor(ref, dtype=torch.float64), torch.as_tensor(tgt, dtype=torch.float64), 120, 120)
    head = 1 + [name for name, _, _ in SEGMENT_PARTS].index("head")
    affine = segment_affine(ref, tgt, "head")  # (3, 2, 3)
    for b in range(3):
        for y, x in [(10, 15), (60, 70), (100, 30)]:
            sampled = maps[b, head, y, x].numpy()  # the reference pixel the target pixel (x + .5, y + .5) samples
            np.testing.assert_allclose(affine[b, :, :2] @ sampled + affine[b, :, 2], [x + 0.5, y + 0.5], atol=1e-6)


def test_the_head_s_axes_turn_with_the_body_and_carry_its_points_rigidly():
    from motion2video.core.rotations import axis_angle_to_matrix
    from motion2video.generator.head_paste import joint_head_axes, rigid_head

    rng = np.random.default_rng(1)
    rest = np.asarray(np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"], np.float64)[0]
    turn = axis_angle_to_matrix(np.array([0.1, -0.2, 1.3]))
    moved = rest @ turn.T + [0.3, -1.0, 0.2]
    axes, origin = joint_head_axes(np.stack([rest, moved]))
    np.testing.assert_allclose(axes[1], turn @ axes[0], atol=1e-9)
    np.testing.assert_allclose(axes[0].T @ axes[0], np.eye(3), atol=1e-9)
    points, normals = rng.normal(size=(20, 3)) * 0.1 + rest[10], rng.normal(size=(20, 3))
    out, out_normals = rigid_head(points, normals, rest, np.stack([rest, moved]))
    np.testing.assert_allclose(out[0], points, atol=1e-9)
    np.testing.assert_allclose(out[1], (points - rest[10]) @ turn.T + moved[10], atol=1e-9)
    np.testing.assert_allclose(out_normals[1], normals @ turn.T, atol=1e-9)


@pytest.fixture(scope="module")
def warp_net():
    from motion2video.generator.checkpoint import load_frame_model

    return load_frame_model("frames-body-128")


def test_the_keypoint_warp_carries_the_photos_face_on_its_head(warp_net, tracksuit, monkeypatch):
    """frames-body-128 makes the photo walk: its frames carry the photo's face moved as the warp moves the head (PSNR
    against the photo's face moved the same way, over the face's core), a face detector finds it there, and outside
    the head's square the frames are the warp's own."""
    import motion2video.stages.generation as generation
    from motion2video.stages.structure import render_structures

    forecast = walk_forecast()
    structures = render_structures(forecast, domain="body", size=SIZE, reference=tracksuit)
    pasted = generation.warp_face(tracksuit, structures)
    assert pasted is not None
    face, affines, head = pasted
    np.testing.assert_array_less(0.99, head.weights)  # walking towards the camera: the face fully laid over
    out = generation.generate_video_frames(warp_net, tracksuit, structures)
    frames = np.concatenate([out.observed, out.futures[0]])
    monkeypatch.setattr(generation, "warp_face", lambda reference, structures: None)  # the warp's own frames
    own = generation.generate_video_frames(warp_net, tracksuit, structures)
    own = np.concatenate([own.observed, own.futures[0]])
    for i in range(len(frames)):
        assert_face_laid_over(frames[i], own[i], tracksuit.image, face, affines[i], head.offsets[i])


def test_the_keypoint_warp_keeps_its_own_head_turned_away_from_the_photos_view(warp_net, tracksuit):
    """The walk's futures turned by 0, 90 and 180 degrees: the face is laid over the first (about 18 degrees from the
    photo's view), not over the others (a profile, the back of the head)."""
    import motion2video.stages.generation as generation
    from motion2video.stages.structure import render_structures

    structures = render_structures(walk_forecast((0.0, 90.0, 180.0)), domain="body", size=SIZE, reference=tracksuit)
    _, _, head = generation.warp_face(tracksuit, structures)
    np.testing.assert_array_equal(head.weights, [1.0, 1.0, 0.0, 0.0])


def test_a_2d_motion_gives_the_keypoint_warp_no_face(tracksuit):
    """2D joints do not say where the head is turned: no face is laid over."""
    import motion2video.stages.generation as generation
    from motion2video.stages.sampling import Forecast
    from motion2video.stages.structure import render_structures

    walk = walk_forecast()
    flat = Forecast(observed=walk.observed[..., :2] * 100 + 128, futures=walk.futures[..., :2] * 100 + 128, fps=25.0,
                    layout="body2d", model="test", seed=0)
    structures = render_structures(flat, domain="body", size=SIZE, reference=tracksuit)
    assert generation.warp_face(tracksuit, structures) is None


def test_the_head_cut_is_the_person_in_the_head_zone_only():
    """head_cut: 1 away from the head; inside the head zone, the segmented person. cut_alpha samples it along the
    flow: a target pixel whose colour comes from the cut's 0 is background."""
    import torch

    from motion2video.generator.mesh_flow import identity_flow
    from motion2video.generator.mesh_warp import HEAD_ZONE, cut_alpha, head_cut

    points = np.zeros((17, 2))
    points[8], points[9], points[10] = (32.0, 40.0), (32.0, 30.0), (32.0, 20.0)  # thorax, neck, head: 20 px apart
    person = np.zeros((64, 64), np.float32)
    person[18:40, 26:38] = 1.0
    cut = head_cut(person, points)
    half = HEAD_ZONE * 20 / 2  # the zone's half side around (32, 25)
    assert cut[25, 32] == 1.0 and cut[25, 20] == 0.0  # her head; beside it, in the zone
    assert cut[25, int(32 + half + 2)] == 1.0 and cut[60, 5] == 1.0  # outside the zone: never cut
    alpha = torch.ones(1, 1, 64, 64)
    flow = torch.from_numpy(identity_flow(64, 64))[None].float()
    out = cut_alpha(alpha, torch.from_numpy(cut)[None, None], flow)[0, 0].numpy()
    np.testing.assert_allclose(out, cut, atol=1e-6)


def test_the_shown_face_is_its_triangles_the_target_shows():
    """Known answer on a 5 x 5 grid of landmarks 4 px apart: all shown, the whole face may be laid; two neighbouring
    landmarks hidden, the triangles around them are left out (0 there, 1 away from them); one hidden among shown ones
    (the depth test's noise, head_paste.lone_hidden) is drawn over; triangles folded over (a mirrored grid's faces
    against the others) are not drawn."""
    from motion2video.generator.head_paste import face_triangles, shown_face

    gx, gy = np.meshgrid(np.arange(5), np.arange(5))
    rest = np.stack([gx.ravel(), gy.ravel(), 0.02 * (gx.ravel() - 2.0) ** 2], axis=1).astype(np.float64)
    triangles = face_triangles(rest)
    assert len(triangles) == 32  # two per grid square, no sliver on a square grid
    points = rest[:, :2] * 4.0 + 10.0  # pixels: the grid from (10, 10) to (26, 26)
    shown = np.ones(25, bool)
    np.testing.assert_array_equal(shown_face(points, triangles, shown, (40, 40)), 1.0)
    shown[12] = False  # the middle landmark, at pixel (18, 18): alone, it is drawn over
    np.testing.assert_array_equal(shown_face(points, triangles, shown, (40, 40)), 1.0)
    shown[13] = False  # and its neighbour at (22, 18): both are hidden
    cover = shown_face(points, triangles, shown, (40, 40))
    assert cover[18, 18] == 0.0 and cover[17:20, 17:20].max() < 0.5 and cover[18, 22] == 0.0
    assert cover[11, 11] > 0.9 and cover[25, 11] > 0.9  # the left corners' squares, away from the hidden landmarks
    assert cover[2, 2] == 0.0  # outside the face nothing is drawn
    folded = points.copy()
    folded[gx.ravel() >= 3, 0] = 2 * points[12, 0] - folded[gx.ravel() >= 3, 0]  # the right columns mirrored over
    cover = shown_face(folded, triangles, np.ones(25, bool), (40, 40))
    assert cover[18, 12] > 0.9  # the left squares, facing as most do
    assert cover[20, 19] < 0.5  # the folded squares' area (x 18-22) is only drawn by the unfolded ones beside it


def test_a_hand_in_front_of_the_face_stays_in_front(net, tracksuit):
    """A target whose right hand is held a hand's width in front of her face: the landmarks behind the hand are not
    shown, the face is laid over the rest of the face only, and the frame around the hand is the generator's own."""
    from dataclasses import replace

    from motion2video.core.skeletons import HEAD, R_ELBOW, R_WRIST
    from motion2video.generator.head_paste import joint_head_axes
    from motion2video.stages.generation import mesh_frames
    from motion2video.stages.structure import render_structures

    forecast = walk_forecast()
    futures = forecast.futures.copy()
    axes, _ = joint_head_axes(futures[0, 0])
    front = -axes[:, 1]  # the way the body faces (up x left points to its back)
    head = futures[0, 0, HEAD]
    futures[0, 0, R_WRIST] = head - 0.06 * axes[:, 2] + 0.15 * front - 0.03 * axes[:, 0]  # a little to her right
    futures[0, 0, R_ELBOW] = head - 0.30 * axes[:, 2] + 0.10 * front - 0.15 * axes[:, 0]
    forecast = replace(forecast, futures=futures)
    structures = render_structures(forecast, domain="body", size=SIZE, reference=tracksuit)
    video = mesh_video_of(net, tracksuit, forecast)
    hidden = ~video.head.shown[1]  # target 1: the first future
    assert 0.3 < hidden.mean() < 0.5 and (~video.head.shown[2]).mean() < 0.05  # 0.37; the next target's hand is down
    assert video.head.weights[1] == 1.0  # the rest of the face is laid over fully
    with_face = mesh_frames(net, tracksuit, structures, video, np.array([1]))[0]
    without = mesh_frames(net, tracksuit, structures, replace(video, face=None), np.array([1]))[0]
    from motion2video.stages.pictured_face import landmarks_in_reference

    affine = video.head.affines[1]
    where = landmarks_in_reference(video.face) @ affine[:, :2].T + affine[:, 2]
    behind = np.round(where[hidden] - 0.5).astype(int)
    changed = np.any(with_face != without, axis=-1)
    shown_at = np.round(where[~hidden] - 0.5).astype(int)
    assert changed[shown_at[:, 1], shown_at[:, 0]].mean() > 0.5  # the face the hand leaves free is the photo's
    assert changed[behind[:, 1], behind[:, 0]].mean() < 0.2  # behind the hand the generator's frame stays


def bent_landmarks(landmarks: np.ndarray, affine: np.ndarray, strength: float) -> tuple[np.ndarray, np.ndarray]:
    """The landmarks ``landmarks`` (L, 2) moved by ``affine`` and bent as a head turned about its vertical axis bends
    them: each is pushed sideways by ``strength`` times the face's width times a bump that is 1 at the face's middle
    and 0 at its sides (the nose moves farther than the ears). Returns (target points (L, 2), offsets (L, 2))."""
    moved = landmarks @ affine[:, :2].T + affine[:, 2]
    lo, hi = moved[:, 0].min(), moved[:, 0].max()
    u = (moved[:, 0] - lo) / (hi - lo)
    offsets = np.zeros_like(moved)
    offsets[:, 0] = strength * (hi - lo) * np.sin(np.pi * u)
    return moved + offsets, offsets


def test_a_bent_face_is_the_piecewise_affine_warp_of_its_landmarks(tracksuit):
    """The face laid with a bend (head_paste.FaceBend: each landmark offset from its affine place) is the photo warped
    piecewise-affinely from its landmarks onto the bent ones, as scikit-image's PiecewiseAffineTransform warps it:
    1.2 levels apart on average over the face's core (the two triangulate the landmarks differently and interpolate
    differently), where the affine map alone is 29.9 levels off. With no offsets the bend leaves the affine paste as
    it was (within a level: OpenCV's remap and warpAffine round the maps alike)."""
    from skimage.transform import PiecewiseAffineTransform, warp

    from motion2video.generator.head_paste import FaceBend, pixel_index_affine
    from motion2video.stages.pictured_face import reference_face

    face = reference_face(tracksuit)
    size = 192
    scale = 0.6 * size / np.ptp(face.landmarks[:, 0])  # the face enlarged to 60% of the frame: no shrinking first
    centre = face.landmarks.mean(axis=0)
    affine = np.array([[scale, 0.0, size / 2 - scale * centre[0]], [0.0, scale, size / 2 - scale * centre[1]]])
    grey = np.full((size, size, 3), 128, np.uint8)
    points, offsets = bent_landmarks(face.landmarks, affine, 0.08)
    bent = paste_head(grey, face.image, face.matte, affine, 1.0, bend=FaceBend(points, offsets))
    flat = paste_head(grey, face.image, face.matte, affine, 1.0)

    # scikit-image's warp: output pixel (index coordinates) -> source pixel, estimated from the landmarks' pairs
    to_source = PiecewiseAffineTransform.from_estimate(points - 0.5, face.landmarks - 0.5)
    assert to_source
    expected = warp(face.image.astype(np.float64) / 255.0, to_source, output_shape=(size, size), order=3) * 255.0
    hull = np.zeros((size, size), np.uint8)
    cv2.fillConvexPoly(hull, cv2.convexHull(np.round(points - 0.5).astype(np.int32)), 1)
    alpha = cv2.warpAffine(face.matte, pixel_index_affine(affine), (size, size), flags=cv2.INTER_LINEAR)
    core = (cv2.erode(hull, np.ones((9, 9), np.uint8)) > 0) & (alpha > 0.99)
    assert core.sum() > 2000
    error_bent = np.abs(bent[core].astype(np.float64) - expected[core]).mean()
    error_flat = np.abs(flat[core].astype(np.float64) - expected[core]).mean()
    assert error_bent < 2.0 and error_flat > 10 * error_bent, (error_bent, error_flat)  # 1.2 and 29.9

    still = FaceBend(face.landmarks @ affine[:, :2].T + affine[:, 2], np.zeros_like(offsets))
    same = paste_head(grey, face.image, face.matte, affine, 1.0, bend=still)
    assert np.abs(same.astype(np.int64) - flat).max() <= 1


def test_the_bend_is_the_offsets_spread_between_the_landmarks():
    """Known answer on a 3 x 3 grid of landmarks 8 px apart, their offsets growing linearly across it: inside the grid
    the bend is that linear field exactly, outside it the nearest pixel's, and with no landmark near the box zero."""
    from motion2video.generator.head_paste import FaceBend, bend_field

    gx, gy = np.meshgrid(np.arange(3), np.arange(3))
    points = np.stack([gx.ravel(), gy.ravel()], axis=1) * 8.0 + 4.0  # pixels: the grid from (4, 4) to (20, 20)
    offsets = np.stack([0.5 * points[:, 0], -0.25 * points[:, 1]], axis=1)
    field = bend_field(FaceBend(points, offsets), (0, 0, 24, 24))
    centres = np.arange(24) + 0.5
    inside = (centres > 4) & (centres < 20)
    x, y = np.meshgrid(centres[inside], centres[inside])
    np.testing.assert_allclose(field[np.ix_(inside, inside)], np.stack([0.5 * x, -0.25 * y], axis=-1), atol=1e-9)
    np.testing.assert_allclose(field[0, 0], field[4, 4], atol=1e-9)  # the corner outside takes the nearest inside
    np.testing.assert_allclose(field[23, 10], field[19, 10], atol=1e-9)
    np.testing.assert_array_equal(bend_field(FaceBend(points + 100, offsets), (0, 0, 24, 24)), 0.0)


def test_the_moved_landmarks_are_where_the_turned_head_has_them():
    """Known answer: a rigid face-like surface (a 9 x 9 grid of points whose depth falls off from the nose) seen by an
    orthographic camera turned 10 degrees about the vertical in the photo and 50 in the target. head_moves' affine map
    plus its offsets (head_paste.FaceBend) put every landmark where the target camera sees it, to 1e-6 px; the affine
    map alone misses by up to 66 px (the face is 152 px wide, its corners 8 cm behind its nose)."""
    from motion2video.generator.head_paste import head_moves

    g = np.linspace(-0.07, 0.07, 9)
    x, y = (a.ravel() for a in np.meshgrid(g, g))
    points = np.stack([x, y, -0.08 * (x ** 2 + y ** 2) / 0.07 ** 2], axis=1)  # metres: x right, y up, z to the camera

    def seen(deg: float) -> np.ndarray:  # (P, 2) pixels: 1000 px per metre, y down
        a = np.radians(deg)
        turned = points @ np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]]).T
        return np.stack([1000 * turned[:, 0] + 128, -1000 * turned[:, 1] + 128], axis=1)

    photo, target = seen(10.0), seen(50.0)
    n = len(points)
    one = np.stack([np.arange(n)] * 3, axis=1)  # each landmark on its own vertex
    weights = np.tile([1.0, 0.0, 0.0], (n, 1))
    moves = head_moves(photo, points, one, weights, photo, target[None], np.ones((1, n), bool), head_points=points,
                       head_vertices=np.arange(n))
    affine = moves.affines[0]
    flat = photo @ affine[:, :2].T + affine[:, 2]
    np.testing.assert_allclose(flat + moves.offsets[0], target, atol=1e-6)
    assert np.abs(flat - target).max() > 30.0
