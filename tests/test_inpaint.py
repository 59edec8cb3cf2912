"""Patch-based inpainting (generator/inpaint.py), on pictures whose hidden part is known."""

from __future__ import annotations

import cv2
import numpy as np

from motion2video.generator.inpaint import PatchSettings, patch_inpaint
from motion2video.generator.scores import region_psnr


def disc_hole(shape: tuple[int, int], centre: tuple[int, int], radius: int) -> np.ndarray:
    yy, xx = np.mgrid[:shape[0], :shape[1]]
    return np.hypot(xx - centre[0], yy - centre[1]) <= radius


def test_a_fine_texture_keeps_its_grain_in_the_hole():
    """Diagonal stripes 6 px apart with a disc removed: the patches carry the stripes' contrast into the hole, where
    a diffusing inpainting leaves a blur."""
    yy, xx = np.mgrid[:96, :128]
    grey = 128 + 60 * np.sin(2 * np.pi * (xx + 0.5 * yy) / 6) + np.random.default_rng(1).normal(0, 4, (96, 128))
    image = np.clip(np.stack([grey, grey * 0.8, grey * 0.5], -1), 0, 255).astype(np.uint8)
    hole = disc_hole(image.shape[:2], (64, 48), 16)
    filled = patch_inpaint(image, hole)
    diffused = cv2.inpaint(image, hole.astype(np.uint8), 5, cv2.INPAINT_NS)
    assert filled.shape == image.shape and filled.dtype == np.uint8
    np.testing.assert_array_equal(filled[~hole], image[~hole])  # only the hole changes
    truth = image[hole].std()
    assert diffused[hole].std() < 0.75 * truth  # blurred (0.66)
    assert filled[hole].std() > 0.85 * truth  # the stripes' contrast (0.95)
    assert region_psnr(filled, image, hole) > region_psnr(diffused, image, hole)  # 19.5 against 17.2 dB
    assert abs(filled[hole].mean() - image[hole].mean()) < 5


def test_the_skiers_place_is_snow_not_a_smear_of_her_bindings(photos_dir):
    """``skier.jpg`` at 256 px high with her segmented person removed: between her knees and her boots the hole is
    snow. Navier-Stokes drew the black bindings and skis under her boots up into it as a dark wedge."""
    from motion2video.generator.background import inpaint_background, person_hole
    from motion2video.pose.estimate import default_model, estimate_image

    image = cv2.cvtColor(cv2.imread(str(photos_dir / "skier.jpg")), cv2.COLOR_BGR2RGB)
    scale = 256 / image.shape[0]
    image = cv2.resize(image, (round(image.shape[1] * scale), 256), interpolation=cv2.INTER_AREA)
    found = estimate_image(image, model=default_model())
    person = found.landmarks.person_mask(found.width, found.height)
    hole = person_hole(person)
    rows = np.flatnonzero(hole.any(axis=1))
    top, height = rows[0], rows[-1] - rows[0]
    yy = np.mgrid[:hole.shape[0], :hole.shape[1]][0]
    legs = hole & (yy > top + 0.6 * height) & (yy < top + 0.9 * height)

    def dark_share(picture: np.ndarray) -> float:
        return float((picture[legs].mean(axis=-1) < 150).mean())

    assert dark_share(image) > 0.5  # her black trousers
    assert dark_share(cv2.inpaint(image, hole.astype(np.uint8), 5, cv2.INPAINT_NS)) > 0.1  # the wedge (0.14)
    assert dark_share(inpaint_background(image, person)) < 0.05  # snow (0.02)


def test_the_same_seed_gives_the_same_fill_and_a_hole_over_everything_still_fills():
    rng = np.random.default_rng(3)
    image = rng.integers(0, 256, (64, 80, 3), dtype=np.uint8)
    hole = disc_hole((64, 80), (40, 32), 10)
    np.testing.assert_array_equal(patch_inpaint(image, hole), patch_inpaint(image, hole))
    other = patch_inpaint(image, hole, settings=PatchSettings(seed=1))
    assert not np.array_equal(other, patch_inpaint(image, hole))
    # no patch lies wholly outside this hole: the diffusing inpainting alone, the corner kept
    almost = np.ones((64, 80), bool)
    almost[:4, :4] = False
    out = patch_inpaint(image, almost)
    np.testing.assert_array_equal(out[:4, :4], image[:4, :4])
    assert out.shape == image.shape
