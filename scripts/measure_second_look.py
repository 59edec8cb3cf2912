"""One-off: how often BlazePose's second look (pose.estimate.second_chance) takes a person-less picture for a person.

    python scripts/measure_second_look.py [--photos ../shared/data/photos] [--per-photo 20]

From every photo, squares of 20-60% of its shorter side that miss its person (BlazePose's segmentation of the
largest person, grown by 7 px) are cut at random (seed 1). For each square, where the detector finds no one at its
threshold: is a person found by presence alone (a detection from 0.3, or 0.35, whose landmarks have presence 0.9),
and by the second look (``second_chance``: presence on two regions, visibility, inside the picture). Also: does the
detector with presence 0.5 find a person (the rule without the second look). Then plain-colour pictures. Prints a
JSON object.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import numpy as np

from motion2video.core.errors import InputError
from motion2video.pose.blazepose import detection_roi
from motion2video.pose.estimate import (SECOND_CHANCE_PRESENCE, default_model, estimate_image, read_image_rgb,
                                        second_chance)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--photos", type=Path, default=Path("../shared/data/photos"))
    parser.add_argument("--per-photo", type=int, default=20)
    args = parser.parse_args()
    model = default_model()
    rng = np.random.default_rng(1)
    rows = []
    for path in sorted(p for p in args.photos.iterdir() if p.suffix.lower() in (".jpg", ".jpeg", ".png")):
        image = read_image_rgb(path)
        h, w = image.shape[:2]
        pose = estimate_image(image, model=model)
        person = cv2.dilate((pose.landmarks.person_mask(w, h) > 0.2).astype(np.uint8), np.ones((15, 15), np.uint8))
        cut = 0
        for _ in range(400):
            side = int(rng.uniform(0.2, 0.6) * min(h, w))
            x, y = int(rng.integers(0, w - side)), int(rng.integers(0, h - side))
            if person[y:y + side, x:x + side].any():
                continue
            square = np.ascontiguousarray(image[y:y + side, x:x + side])
            try:
                estimate_image(square, model=model, second_look=False)
                today = True
            except InputError:
                today = False
            found = {}
            for score in (0.3, 0.35):
                found[score] = (not model.detect(square)) and any(
                    model.landmarks(square, detection_roi(d)).score >= SECOND_CHANCE_PRESENCE
                    for d in model.detect(square, min_score=score))
            rows.append({"photo": path.name, "square": [x, y, side], "detector": today,
                         "presence_alone_0.3": found[0.3], "presence_alone_0.35": found[0.35],
                         "second_look": (not model.detect(square)) and bool(second_chance(model, square))})
            cut += 1
            if cut >= args.per_photo:
                break
    plain = [np.full((300, 300, 3), c, np.uint8) for c in ((128, 128, 128), (200, 30, 30), (10, 10, 10))]
    result = {
        "squares": len(rows), "photos": sorted({r["photo"] for r in rows}),
        "person_found_by_the_detector": sum(r["detector"] for r in rows),
        "presence_alone_from_0.3": sum(r["presence_alone_0.3"] for r in rows),
        "presence_alone_from_0.35": sum(r["presence_alone_0.35"] for r in rows),
        "second_look": sum(r["second_look"] for r in rows),
        "plain_colour_detections_from_0.2": sum(len(model.detect(p, min_score=0.2)) for p in plain),
        "found": [r for r in rows if r["detector"] or r["presence_alone_0.3"] or r["second_look"]],
    }
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
