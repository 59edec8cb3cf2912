"""One-off: the background behind the person filled by Navier-Stokes and by patches, where the truth is known.

    python scripts/measure_inpaint.py ../shared/data/photos/skier.jpg ... [--json out/inpaint.json]

For each photo, `synthesize --crop-person --frame-model frames-body-mesh-256` is run for two frames, and the hole its
background fills (the segmented person joined with the fitted silhouette, the pad) is taken. That hole is moved 30% of
the picture's width left and right onto the background; both holes are filled, and the moved one, less the person
grown by 6 px, is compared with the picture: PSNR, SSIM (scikit-image, grey) and grain (the mean absolute Laplacian
there over the picture's: 1 keeps the grain, 0 is a blur).

With --time, the seconds each inpainting takes to fill the reference's own hole: Navier-Stokes and the patches at the
picture's size and at twice it, and OpenCV contrib's ``xphoto`` frequency-selective reconstruction (FSR_FAST) and
shift-map at the picture's size.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import cv2
import numpy as np
from skimage.metrics import structural_similarity

import motion2video.apps.synthesize as synth
import motion2video.stages.mesh_generation as mesh_generation
from motion2video.generator.background import person_hole
from motion2video.generator.inpaint import patch_inpaint

CLIP = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap" / "cmu" / "08_01.bvh"


def reference_hole(photo: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(image (H, W, 3) uint8, hole (H, W) bool, from_file (H, W) bool) as synthesize fills the background."""
    seen = {}
    original = mesh_generation.reference_background

    def spy(image, video, person, points, *, from_file=None):
        seen.update(image=image, video=video, person=person, from_file=from_file)
        return original(image, video, person, points, from_file=from_file)

    mesh_generation.reference_background = spy
    try:
        synth.synthesize(motion_model="mixture-periodic", frame_model="frames-body-mesh-256", input_path=str(CLIP),
                         reference=str(photo), output=None, on_chunk=lambda *a: None,
                         config=synth.SynthesisConfig(samples=1, horizon=2, observed=2, crop_person=True))
    finally:
        mesh_generation.reference_background = original
    image, video = seen["image"], seen["video"]
    x0, y0, side = video.crop
    hole = np.zeros(image.shape[:2], np.float32)
    hole[y0:y0 + side, x0:x0 + side] = cv2.resize(video.reference.masks[0].astype(np.float32), (side, side))
    if seen["person"] is not None:
        hole = np.maximum(hole, np.asarray(seen["person"], np.float32))
    from_file = np.ones(image.shape[:2], bool) if seen["from_file"] is None else np.asarray(seen["from_file"], bool)
    hole = np.where(from_file, hole, 1.0)
    return image, person_hole(hole), from_file


def scores(filled: np.ndarray, image: np.ndarray, truth: np.ndarray) -> dict:
    err = np.mean((filled[truth].astype(np.float64) - image[truth]) ** 2)
    grey, grey_filled = (cv2.cvtColor(x, cv2.COLOR_RGB2GRAY) for x in (image, filled))
    _, ssim = structural_similarity(grey, grey_filled, full=True)
    lap = [np.abs(cv2.Laplacian(g.astype(np.float32), cv2.CV_32F))[truth].mean() for g in (grey_filled, grey)]
    return {"psnr": round(float(10 * np.log10(255 ** 2 / err)), 2), "ssim": round(float(ssim[truth].mean()), 3),
            "grain": round(float(lap[0] / lap[1]), 2)}


def seconds(fill, *args) -> float:
    start = time.perf_counter()
    fill(*args)
    return round(time.perf_counter() - start, 2)


def timings(image: np.ndarray, hole: np.ndarray) -> dict:
    """Seconds to fill ``hole`` in ``image`` by each inpainting (see the module's docstring)."""
    def navier_stokes(picture, mask):
        return cv2.inpaint(picture, mask.astype(np.uint8), 5, cv2.INPAINT_NS)

    def xphoto(flag):
        def fill(picture, mask):
            bgr = cv2.cvtColor(picture, cv2.COLOR_RGB2BGR)
            bgr[mask] = 0
            cv2.xphoto.inpaint(bgr, (~mask).astype(np.uint8), np.zeros_like(bgr), flag)
        return fill

    double = (cv2.resize(image, None, fx=2, fy=2, interpolation=cv2.INTER_CUBIC),
              cv2.resize(hole.astype(np.uint8), None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST) > 0)
    return {"size": image.shape[1], "navier_stokes": seconds(navier_stokes, image, hole),
            "patches": seconds(patch_inpaint, image, hole),
            "navier_stokes_double": seconds(navier_stokes, *double), "patches_double": seconds(patch_inpaint, *double),
            "fsr_fast": seconds(xphoto(cv2.xphoto.INPAINT_FSR_FAST), image, hole),
            "shift_map": seconds(xphoto(cv2.xphoto.INPAINT_SHIFTMAP), image, hole)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("photos", nargs="+", type=Path)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--time", action="store_true", help="also time each inpainting on the reference's hole")
    args = parser.parse_args()
    results = {}
    for photo in args.photos:
        image, hole, from_file = reference_hole(photo)
        if args.time:
            results[f"{photo.name} seconds"] = timings(image, hole)
            print(photo.name, results[f"{photo.name} seconds"], flush=True)
        width = image.shape[1]
        for shift in (-int(0.3 * width), int(0.3 * width)):
            moved = np.roll(hole & from_file, shift, axis=1)
            if shift > 0:
                moved[:, :shift] = False  # no wrapping round the picture
            else:
                moved[:, shift:] = False
            truth = moved & ~person_hole(hole, grow_px=6) & from_file
            if truth.sum() < 500:
                continue
            both = hole | moved
            row = {"pixels": int(truth.sum()),
                   "navier_stokes": scores(cv2.inpaint(image, both.astype(np.uint8), 5, cv2.INPAINT_NS), image, truth),
                   "patches": scores(patch_inpaint(image, both), image, truth)}
            results[f"{photo.name} {shift:+d}"] = row
            print(photo.name, shift, row, flush=True)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
