"""The background behind the reference person and the soft matte the generated person is laid over it with.

Real parts: a real photo of ../shared/data/photos (a woman in blue on a beige wall), BlazePose's segmentation of it,
a cut-out with an alpha channel, the shipped mesh generator.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.generator.background import composite, inpaint_background, person_hole, soft_matte

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

ROOT = Path(__file__).resolve().parents[1]


def blue_share(pixels: np.ndarray) -> float:
    """The share of (N, 3) RGB pixels that are the woman's clothes' blue (blue 25 levels over red): the beige wall,
    the wooden door and the grey floor behind her are none of them."""
    c = np.asarray(pixels, np.int64)
    return float(np.mean(c[:, 2] > c[:, 0] + 25))


@pytest.fixture(scope="module")
def tracksuit(photos_dir) -> tuple[np.ndarray, np.ndarray]:
    """``woman_blue_tracksuit.jpg`` at 512 px high and BlazePose's person probability on it."""
    from motion2video.pose.estimate import default_model, estimate_image

    image = cv2.cvtColor(cv2.imread(str(photos_dir / "woman_blue_tracksuit.jpg")), cv2.COLOR_BGR2RGB)
    scale = 512 / image.shape[0]
    image = cv2.resize(image, (round(image.shape[1] * scale), 512), interpolation=cv2.INTER_AREA)
    found = estimate_image(image, model=default_model())
    return image, found.landmarks.person_mask(found.width, found.height)


def test_a_real_photos_inpainted_background_keeps_none_of_the_persons_colours(tracksuit):
    image, person = tracksuit
    region = person > 0.5
    background = inpaint_background(image, person)
    assert background.shape == image.shape and background.dtype == np.uint8
    hole = person_hole(person)
    np.testing.assert_array_equal(background[~hole], image[~hole])  # only the hole changes
    assert blue_share(image[region]) > 0.5  # she is in blue (0.78)
    assert blue_share(background[region]) < 0.01  # none of it left (0.000)
    # the filled region's colour is the background's around it, not hers
    ring = (cv2.dilate(hole.astype(np.uint8), np.ones((15, 15), np.uint8)) > 0) & ~hole
    filled, around, hers = (x.reshape(-1, 3).mean(0) for x in (background[region], image[ring], image[region]))
    assert np.linalg.norm(filled - around) < 0.5 * np.linalg.norm(filled - hers)


def test_an_image_without_a_person_comes_back_unchanged():
    image = np.random.default_rng(0).integers(0, 256, (32, 48, 3), dtype=np.uint8)
    np.testing.assert_array_equal(inpaint_background(image, np.zeros((32, 48))), image)


def test_the_soft_matte_is_in_0_1_and_feathered():
    """The generator's alpha of a disc (0.018 outside, 0.982 inside: its sigmoid around the silhouette) becomes a
    matte that is exactly 1 inside and 0 outside, with a ramp of a few pixels at the outline."""
    yy, xx = np.mgrid[:128, :128]
    r = np.hypot(xx - 63.5, yy - 63.5)
    alpha = np.where(r < 30, 0.982, 0.018).astype(np.float32)
    matte = soft_matte(alpha[None])[0]
    assert matte.min() >= 0 and matte.max() <= 1
    assert (matte[r < 28] > 0.999).all() and (matte[r > 32] < 0.001).all()
    ramp = matte[np.abs(r - 30) < 0.5]  # the pixels the outline passes through
    assert ((ramp > 0.02) & (ramp < 0.98)).mean() > 0.9  # feathered, not a hard cut
    profile = matte[64, 64:]  # from the centre outward: never rising
    assert (np.diff(profile) <= 1e-6).all()
    # laid over a background: the person's colour inside, the background's outside, a mix on the ramp
    person = np.zeros((1, 128, 128, 3), np.float32)
    person[..., 2] = 1.0
    out = composite(np.full((128, 128, 3), 200, np.uint8), person, matte[None])[0]
    assert (out[r < 28] == [0, 0, 255]).all() and (out[r > 32] == 200).all()


def test_a_cut_outs_alpha_is_the_reference_person(photos_dir, tmp_path):
    from motion2video.stages.reference import load_reference, reference_alpha

    path = photos_dir / "fashion_woman_shorts.png"
    alpha = reference_alpha(path)
    assert alpha is not None and alpha.shape == (670, 540) and 0.8 < float((alpha < 0.5).mean()) < 0.9
    reference = load_reference(path, size=256, domain="body")
    assert any("alpha channel" in note for note in reference.notes)
    mask = reference.person.mask
    soft = (mask > 0.02) & (mask < 0.98)
    assert soft.any() and float((mask > 0.5).mean()) > 0.05
    # an RGBA file opaque everywhere is no cut-out: BlazePose's segmentation stays the person
    opaque = tmp_path / "opaque.png"
    rgb = cv2.imread(str(photos_dir / "skier.jpg"))
    cv2.imwrite(str(opaque), np.dstack([rgb, np.full(rgb.shape[:2], 255, np.uint8)]))
    assert reference_alpha(opaque) is None
    assert reference_alpha(photos_dir / "skier.jpg") is None


def walked_reference(path: Path):
    """``path`` as ``synthesize --crop-person`` loads it at 256 px, the shipped mesh generator, and the
    :class:`~motion2video.stages.mesh_generation.MeshVideo` it fits for two frames of the demo's CMU walk observed and
    two predicted: (reference, net, video)."""
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.stages.generation import mesh_setup
    from motion2video.stages.reference import load_reference
    from motion2video.stages.sampling import Forecast
    from motion2video.stages.structure import render_structures

    walk = np.asarray(np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"], np.float64)
    forecast = Forecast(observed=walk[:2], futures=walk[None, 2:4], fps=25.0, layout="body3d", model="test", seed=0)
    reference = load_reference(path, size=256, domain="body", crop_person=True)
    net = load_frame_model("frames-body-mesh-256").model
    video = mesh_setup(net, reference, render_structures(forecast, domain="body", size=256, reference=reference))
    return reference, net, video


def test_no_ghost_where_the_photos_person_stood(photos_dir):
    """synthesize's mesh path on the cut-out (a runner on white) driven by a walk: where she stood and no generated
    person now covers (her new silhouette grown by 6 px) is white. Pasting the generated person over the reference
    with the old feathered paste mask left 11.5% of those pixels hers (a hand and a shoe's shadow beside the new
    body); over the inpainted background, none."""
    from motion2video.generator.mesh_flow import grow_masks
    from motion2video.stages.mesh_generation import generate_mesh_frames

    def not_white(pixels: np.ndarray) -> float:
        return float(np.mean(np.asarray(pixels).min(axis=1) < 230))

    reference, net, video = walked_reference(photos_dir / "fashion_woman_shorts.png")
    assert video.background is not None and not_white(video.background.reshape(-1, 3)) < 0.01
    frame = generate_mesh_frames(net, reference.image, video, np.array([3]))[0]
    stood = reference.person.mask > 0.5
    x0, y0, side = video.crop
    now = np.zeros((256, 256), bool)
    grown = grow_masks(video.targets.masks[3:4, None], video.margin + 6)[0, 0]
    now[y0:y0 + side, x0:x0 + side] = cv2.resize(grown.astype(np.uint8), (side, side),
                                                  interpolation=cv2.INTER_NEAREST) > 0
    left = stood & ~now
    assert left.sum() > 300  # where she stood is uncovered: 667 pixels
    assert not_white(reference.image[left]) > 0.9  # it was her
    assert not_white(frame[left]) < 0.01  # now it is the background (0.0)


def test_ski_poles_leave_the_background_with_the_skier(photos_dir):
    """What the person holds is not the person to BlazePose's segmentation: the skier's poles stayed in the
    background where they were pictured, while she walked away from them. The poles (the dark pixels on the snow
    above her feet, outside her grown silhouette: 227 at 256 px) are filled with snow: all of them stayed dark
    without :func:`~motion2video.generator.background.attached_objects`, none does with it."""
    reference, _, video = walked_reference(photos_dir / "skier.jpg")
    ankles = reference.pose.points[[3, 6], 1]
    poles = (reference.image.max(axis=2) < 90) & ~person_hole(reference.person.mask, grow_px=4)
    poles[int(ankles.min()) - 10:] = False  # the skis under her boots are not asked about
    assert poles.sum() > 150
    assert float(np.mean(video.background[poles].max(axis=1) < 90)) < 0.05


def test_nothing_held_leaves_the_background_as_it_was(tracksuit):
    """On a photo of a woman with her hands in her pockets against a wall and a door, the thin lines the rule takes
    for held things (the door's edge beside her hand) are under 3% of her area. A stick planted in her hand (a dark
    bar 3 px wide on the 288 x 512 photo, from her wrist out over the wall) is found, 90% of it or more; the same
    line bent into a half circle (the edge of something her hand rests on) is not."""
    from motion2video.generator.background import attached_objects
    from motion2video.pose.blazepose import LANDMARK_NAMES
    from motion2video.pose.estimate import default_model, estimate_image

    image, person = tracksuit
    found = estimate_image(image, model=default_model())
    joints = np.asarray(found.landmarks.xy, np.float64)[:, :2]
    anchors = joints[[LANDMARK_NAMES.index("left_wrist"), LANDMARK_NAMES.index("right_wrist")]]
    held = attached_objects(image, person, anchors)
    assert held.sum() < 0.03 * (person > 0.5).sum()
    planted = image.copy()
    wrist = anchors[1]
    outward = np.sign(wrist[0] - np.median(np.flatnonzero((person > 0.5).any(axis=0))))
    tip = wrist + (70.0 * outward, 40.0)  # away from her, down onto the wall
    ends = [tuple(int(round(v)) for v in p) for p in (wrist, tip)]
    cv2.line(planted, *ends, (20, 20, 20), 3)
    stick = np.zeros(image.shape[:2], np.uint8)
    cv2.line(stick, *ends, 1, 3)
    stick = (stick > 0) & ~person_hole(person)
    assert stick.sum() > 150
    found_stick = attached_objects(planted, person, anchors)
    assert float(found_stick[stick].mean()) > 0.9
    bent = image.copy()
    centre = (int(round(wrist[0] + 30 * outward)), int(round(wrist[1])))
    cv2.ellipse(bent, centre, (30, 30), 0, 0, 180, (20, 20, 20), 3)  # from her wrist round below to 60 px out
    arc = np.zeros(image.shape[:2], np.uint8)
    cv2.ellipse(arc, centre, (30, 30), 0, 0, 180, 1, 3)
    arc = (arc > 0) & ~person_hole(person)
    assert arc.sum() > 150
    assert float(attached_objects(bent, person, anchors)[arc].mean()) < 0.1
