"""How well the fitted body covers the pictured person, with its weight fitted alone and with its surface fitted to
the person's outline (generator/outline_fit.py).

One-off measurement for docs/results.md ("The body fitted to the person's outline"):

- the reference pictures as synthesize fits them (--crop-person, frames-body-mesh-256): the intersection over union
  of the fitted silhouette and BlazePose's person mask (or the picture's alpha);
- dancer.avi under evaluate-frames --video at 128: the same over its 64 target frames, each posed by its estimated
  joints, silhouettes grown as the protocol grows them (the clothes margin, or the outline margin), and the shares
  of her pixels the silhouettes miss and of theirs she does not fill.

    python scripts/measure_outline_fit.py
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")
ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
PHOTOS = ["woman_blue_tracksuit.jpg", "fashion_woman_shorts.png", "fashion_man_red_jacket.png", "skier.jpg",
          "man_by_truck.jpg", "three_walking.jpg"]


def reference_ious(fit_outline: bool) -> dict[str, float]:
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.stages import mesh_generation
    from motion2video.stages.generation import mesh_setup
    from motion2video.stages.reference import load_reference
    from motion2video.stages.sampling import Forecast
    from motion2video.stages.structure import render_structures

    walk = np.asarray(np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"], np.float64)[:4]
    forecast = Forecast(observed=walk[:2], futures=walk[None, 2:], fps=25.0, layout="body3d", model="m", seed=0)
    net = load_frame_model("frames-body-mesh-256").model
    fit = mesh_generation.outline_surface
    if not fit_outline:
        mesh_generation.outline_surface = lambda *args, **kwargs: None
    out = {}
    try:
        pictures = [(name, SHARED / "photos" / name, True) for name in PHOTOS]
        pictures.append(("demo reference_body.png", ROOT / "demo_inputs" / "reference_body.png", False))
        for name, path, crop in pictures:
            reference = load_reference(path, size=256, domain="body", crop_person=crop)
            video = mesh_setup(net, reference, render_structures(forecast, domain="body", size=256,
                                                                 reference=reference))
            body, person = video.reference.masks[0], video.person
            out[name] = float((body & person).sum() / (body | person).sum())
    finally:
        mesh_generation.outline_surface = fit
    return out


def dancer_targets(fit_outline: bool) -> tuple[float, float, float]:
    from motion2video.evaluation.reconstruction import video_frames
    from motion2video.generator.mesh_flow import grow_masks
    from motion2video.generator.mesh_reference import clothes_margin
    from motion2video.generator.outline_fit import outline_margin
    from motion2video.stages import mesh_generation

    frames = video_frames(SHARED / "video" / "dancer.avi", size=128, targets=64)
    fit = mesh_generation.outline_surface
    if not fit_outline:  # the weight alone, grown by the clothes margin, as before the outline fit
        mesh_generation.outline_surface = lambda *args, **kwargs: None
    try:
        track, _ = mesh_generation.video_mesh_track(frames.joints3d, frames.points, size=128,
                                                    person_mask=frames.masks[0])
    finally:
        mesh_generation.outline_surface = fit
    margin = outline_margin(128) if fit_outline else clothes_margin(frames.masks[0], track.masks[0])
    truth, body = frames.masks[1:], grow_masks(track.masks[1:], margin)
    iou = (truth & body).sum((1, 2)) / (truth | body).sum((1, 2))
    missed = (truth & ~body).sum((1, 2)) / truth.sum((1, 2))
    extra = (body & ~truth).sum((1, 2)) / truth.sum((1, 2))
    return float(iou.mean()), float(missed.mean()), float(extra.mean())


def main() -> int:
    before, after = reference_ious(False), reference_ious(True)
    print("| reference (256 px) | weight fitted | outline fitted |")
    print("| --- | ---: | ---: |")
    for name in before:
        print(f"| `{name}` | {before[name]:.3f} | {after[name]:.3f} |")
    print()
    print("| dancer.avi, 64 targets at 128 | IoU | her pixels missed | pixels beside her |")
    print("| --- | ---: | ---: | ---: |")
    for label, fit_outline in (("weight fitted, clothes margin", False), ("outline fitted, 1 px", True)):
        iou, missed, extra = dancer_targets(fit_outline)
        print(f"| {label} | {iou:.3f} | {missed:.3f} | {extra:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
