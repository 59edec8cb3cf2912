"""A person cut by the picture's edge: the picture's framing is kept, and the body is fitted to what it shows.

A half-length portrait's estimated legs lie far below its bottom edge; the picture is extended to hold the pose, and
framed around the whole pose the pictured face was some 15 px tall at 256. The frames are now generated on the
extended picture and cut to the square the picture frames. The pose estimator's guessed legs are also shorter than
the person's, and they set the fitted body's scale: only the bones the picture shows set it now.

Real parts: the painted portraits, the tracksuit and red-jersey photos of ../shared/data/photos, BlazePose and
MediaPipe's face detector on them, a CMU walk, the shipped motion model and frame generators, Anny through OSMesa.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.core.skeletons import H36M_17, HEAD, THORAX
from motion2video.generator.mesh_fit import lift_by_bones
from motion2video.stages.reference import (
    FRAMING_MAX_SIZE, PERSON_CROP_MARGIN, cut_to_view, framing_view, load_reference,
)

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

ROOT = Path(__file__).resolve().parents[1]


def test_framing_view_frames_the_shown_person_inside_the_picture():
    """A 100 x 160 picture extended to 400 x 260 (its legs below): with crop_person the view holds the shown person
    from the head down, lies inside the picture and is no larger than it; without, it is the picture's own square."""
    picture = np.zeros((400, 260), np.float32)
    picture[20:180, 80:180] = 1.0  # the file's pixels: x 80..179, y 20..179
    person = np.zeros_like(picture)
    person[50:400, 100:160] = 1.0  # the pictured person from y 50, and its guessed legs below the picture
    x0, y0, side = framing_view(picture, person, crop_person=True)
    assert side == 100.0  # the person is 130 px tall in the picture: the square is the picture's width
    assert 80 <= x0 and x0 + side <= 180 and 20 <= y0 and y0 + side <= 180  # inside the picture
    assert y0 == pytest.approx(50 - PERSON_CROP_MARGIN * side)  # from the head, with the margin above it
    assert framing_view(picture, person, crop_person=False) == (50.0, 20.0, 160.0)  # the picture's square, centred
    small = np.zeros_like(picture)
    small[100:140, 120:140] = 1.0  # a shown person small in the picture: the square around them, centred on them
    x0, y0, side = framing_view(picture, small, crop_person=True)
    assert side == pytest.approx(40 * (1 + 2 * PERSON_CROP_MARGIN))
    assert (x0 + side / 2, y0 + side / 2) == pytest.approx((130.0, 120.0))


def test_cut_to_view_cuts_and_resizes_every_frame():
    rng = np.random.default_rng(0)
    frames = rng.integers(0, 256, (2, 3, 64, 64, 3), dtype=np.uint8)
    assert cut_to_view(frames, None, 32) is frames
    out = cut_to_view(frames, (16.0, 8.0, 32.0), 32)
    assert out.shape == (2, 3, 32, 32, 3)
    np.testing.assert_array_equal(out, frames[:, :, 8:40, 16:48])  # same size: the square itself
    half = cut_to_view(frames, (0.0, 0.0, 64.0), 32)  # area-averaged: each pixel the mean of its 2 x 2 block
    block = frames[1, 2].reshape(32, 2, 32, 2, 3).astype(np.float64).mean(axis=(1, 3))
    assert np.abs(half[1, 2] - block).max() <= 1.0


@pytest.mark.slow
def test_a_half_length_portrait_keeps_its_framing(photos_dir):
    """The Mona Lisa (half length, knees and feet past the bottom edge): the reference is the extended picture at a
    larger size with the view the picture frames; in the output the head is over twice as large as when framed
    around the whole pose."""
    path = photos_dir / "portrait_mona_lisa.jpg"
    old = load_reference(path, size=256, domain="body", crop_person=True)
    new = load_reference(path, size=256, domain="body", crop_person=True, keep_framing=True)
    assert old.view is None and old.image.shape == (256, 256, 3)
    assert new.view is not None and 256 < new.image.shape[0] <= FRAMING_MAX_SIZE
    assert any("keep the picture's framing" in note for note in new.notes)
    x0, y0, side = new.view
    assert -1 <= x0 and -1 <= y0 and x0 + side <= new.image.shape[0] + 1 and y0 + side <= new.image.shape[0] + 1
    picture = new.picture_mask()[int(y0) + 1:int(y0 + side) - 1, int(x0) + 1:int(x0 + side) - 1]
    assert picture.all()  # no replicated border in view
    old_head = np.linalg.norm(np.subtract(old.pose.points[HEAD], old.pose.points[THORAX]))
    new_head = np.linalg.norm(np.subtract(new.pose.points[HEAD], new.pose.points[THORAX])) * 256 / side
    assert new_head > 2.5 * old_head


@pytest.mark.slow
def test_a_whole_person_in_the_picture_keeps_the_usual_reference(photos_dir):
    """A photo with the whole person in it is loaded as before: no view, the generator's size."""
    path = photos_dir / "woman_blue_tracksuit.jpg"
    plain = load_reference(path, size=256, domain="body", crop_person=True)
    kept = load_reference(path, size=256, domain="body", crop_person=True, keep_framing=True)
    assert kept.view is None
    np.testing.assert_array_equal(kept.image, plain.image)


def face_found(frame: np.ndarray) -> bool:
    """Whether MediaPipe's face detector finds a face in an (H, W, 3) frame and its face mesh is sure of it."""
    from motion2video.pose.facemesh import MIN_PRESENCE, detection_roi
    from motion2video.stages.pictured_face import face_mesh

    frame = np.ascontiguousarray(frame)
    detections = face_mesh().detect(frame)
    return bool(detections) and face_mesh().landmarks(frame, detection_roi(detections[0])).score >= MIN_PRESENCE


@pytest.mark.slow
@pytest.mark.parametrize("frame_model, size", [("frames-body-128", 128), ("frames-body-mesh-256", 256)])
def test_a_portrait_driven_by_a_walk_shows_its_face(photos_dir, mocap_dir, frame_model, size):
    """synthesize with the Mona Lisa as the reference and a CMU walk: frames of the output size, and a face detector
    finds a face in nearly every one of them (none was found when the frames held the whole guessed body)."""
    from motion2video.apps.synthesize import SynthesisConfig, synthesize

    frames = []
    result = synthesize(motion_model="mixture-periodic", frame_model=frame_model,
                        input_path=mocap_dir / "cmu" / "08_01.bvh", reference=photos_dir / "portrait_mona_lisa.jpg",
                        output=None, config=SynthesisConfig(samples=1, horizon=4, crop_person=True),
                        on_chunk=lambda start, chunk, previews: frames.extend(chunk[:, 0]))
    assert any("keep the picture's framing" in note for note in result.notes)
    assert all(frame.shape == (size, size, 3) for frame in frames)
    assert sum(face_found(frame) for frame in frames) >= 0.8 * len(frames)


def test_the_bones_the_picture_shows_set_the_lifted_body_s_scale():
    """A standing pose 4 m from the camera, its legs 30% shorter in the pictured 3D pose than where its 2D joints put
    them (as a pose estimator guesses legs below a picture's edge). Scaled by every bone, the guessed legs bring the
    body nearer; scaled by the shown bones only, the pelvis is at its depth."""
    walk = np.asarray(np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"], np.float64)[0]
    cam = np.stack([walk[:, 0], walk[:, 2], walk[:, 1] - walk[0, 1] + 4.0], axis=1)  # x right, y up, z away
    focal, centre = 500.0, 128.0
    pixels = np.stack([centre + focal * cam[:, 0] / cam[:, 2], centre - focal * cam[:, 1] / cam[:, 2]], axis=1)
    rays = np.stack([(pixels[:, 0] - centre) / focal, (centre - pixels[:, 1]) / focal, np.ones(17)], axis=1)
    legs = [H36M_17.index(f"{side}_{part}") for side in ("left", "right") for part in ("knee", "ankle")]
    guessed = cam.copy()
    for side in ("left", "right"):
        hip, knee, ankle = (H36M_17.index(f"{side}_{part}") for part in ("hip", "knee", "ankle"))
        guessed[knee] = cam[hip] + 0.7 * (cam[knee] - cam[hip])
        guessed[ankle] = guessed[knee] + 0.7 * (cam[ankle] - cam[knee])
    shown = np.ones(17, bool)
    shown[legs] = False
    exact = lift_by_bones(rays, cam, focal, pixels)
    assert exact[0, 2] == pytest.approx(cam[0, 2], rel=0.05)  # the nearest bones set it: within 5%
    assert lift_by_bones(rays, guessed, focal, pixels)[0, 2] < 0.8 * cam[0, 2]  # every bone: far too near
    assert lift_by_bones(rays, guessed, focal, pixels, shown=shown)[0, 2] == pytest.approx(exact[0, 2], rel=0.02)


@pytest.mark.slow
def test_a_person_cut_at_the_waist_gets_the_head_of_the_whole_photo(photos_dir, tmp_path):
    """The red-jersey photo cut at his waist: the fitted head's width, over the distance between the pictured eyes,
    is within 5% of the whole photo's (13% wider when the guessed legs set the body's scale)."""
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.stages.generation import mesh_setup
    from motion2video.stages.structure import render_structures
    from renderers import anny_model
    from tests.test_head_paste import walk_forecast

    net = load_frame_model("frames-body-mesh-256").model
    whole = photos_dir / "fashion_man_red_jacket.png"
    cut = tmp_path / "red_jersey_to_the_waist.png"
    cv2.imwrite(str(cut), cv2.imread(str(whole), cv2.IMREAD_UNCHANGED)[:560])

    def head_width(path) -> float:
        reference = load_reference(path, size=256, domain="body", crop_person=True)
        video = mesh_setup(net, reference, render_structures(walk_forecast(), domain="body", size=256,
                                                             reference=reference))
        x0, y0, side = video.crop
        eyes = (np.asarray(reference.person.eyes) - [x0, y0]) * video.reference.masks.shape[-1] / side
        return float(np.ptp(video.reference.uv[0][anny_model.head_vertices(), 0]) / np.linalg.norm(eyes[0] - eyes[1]))

    assert head_width(cut) == pytest.approx(head_width(whole), rel=0.05)


@pytest.mark.slow
def test_a_portrait_re_enacting_a_behaviour_shows_its_face(photos_dir, mocap_dir, tmp_path):
    """transfer --style frames with the Mona Lisa: the video read back shows her face in every re-enacted frame."""
    import imageio.v3 as iio

    from motion2video.cli import main

    out = tmp_path / "mona.mp4"
    assert main(["transfer", "--model", "behavior", "--sample", "1", "--target", str(mocap_dir / "cmu" / "08_01.bvh"),
                 "--style", "frames", "--frame-model", "frames-body-128", "--reference",
                 str(photos_dir / "portrait_mona_lisa.jpg"), "--crop-person", "--horizon", "4", "-o", str(out)]) == 0
    assert all(face_found(frame) for frame in iio.imread(out))


def test_view_crop_is_the_integer_square_inside_the_picture():
    from motion2video.stages.mesh_generation import view_crop

    assert view_crop((271.4, 16.0, 256.1), 794) == (271, 16, 256)
    assert view_crop((-3.0, 700.0, 120.0), 794) == (0, 674, 120)  # moved inside
    assert view_crop((0.0, 0.0, 900.0), 794) == (0, 0, 794)  # no larger than the picture


@pytest.mark.slow
def test_the_mesh_generator_makes_a_portrait_in_its_view_at_its_own_size(photos_dir):
    """The Mona Lisa's mesh video is generated in the view's square (at the model's 256 px), not in the square
    around every pose, whose legs lie out of view."""
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.stages.generation import mesh_setup
    from motion2video.stages.mesh_generation import view_crop
    from motion2video.stages.structure import render_structures
    from tests.test_head_paste import walk_forecast

    net = load_frame_model("frames-body-mesh-256").model
    portrait = load_reference(photos_dir / "portrait_mona_lisa.jpg", size=256, domain="body", crop_person=True,
                              keep_framing=True)
    canvas = portrait.image.shape[0]
    video = mesh_setup(net, portrait, render_structures(walk_forecast(), domain="body", size=canvas,
                                                        reference=portrait))
    assert video.crop == view_crop(portrait.view, canvas)
    assert video.crop[2] == 256 and video.reference.masks.shape[-1] == 256
