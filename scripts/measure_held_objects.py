"""One-off measurement behind docs/results.md's "Things the person holds" table: the share of each photo's person
area that ``background.attached_objects`` fills, with its line tests off, with the line test only, and as shipped
(line and straightness tests), from the wrists; and, with ``--ankles``, as shipped from the wrists and the ankles.

    python scripts/measure_held_objects.py ../shared/data/photos/woman_blue_tracksuit.jpg \\
        ../shared/data/photos/man_by_truck.jpg ../shared/data/photos/three_walking.jpg \\
        ../shared/data/photos/skier.jpg [MORE PHOTOS ...] [--ankles]

Each photo is loaded as ``synthesize --crop-person`` loads it for a 256 px generator. The first column repeats the
rule's first steps (thin contrasting pixels near a wrist that touch the person there), since the shipped function
has no switch for its line tests; the other two call the function itself.
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np

import motion2video.generator.background as B
from motion2video.stages.reference import load_reference

WRISTS, ANKLES = [13, 16], [3, 6]


def touching_thin_parts(image: np.ndarray, mask: np.ndarray, anchors: np.ndarray, picture: np.ndarray) -> np.ndarray:
    """The rule before its line tests: every thin contrasting part near a wrist that touches the person there."""
    h, w = mask.shape
    scale = w / 256
    rows = np.flatnonzero(mask.any(axis=1))
    height = rows[-1] - rows[0] + 1
    yy, xx = np.mgrid[:h, :w]
    near = np.min([(xx - x) ** 2 + (yy - y) ** 2 for x, y in anchors], axis=0)
    width = B.disc(B.ATTACHED_HALF_WIDTH_PX * scale)
    contrast = np.maximum(cv2.morphologyEx(image, cv2.MORPH_TOPHAT, width),
                          cv2.morphologyEx(image, cv2.MORPH_BLACKHAT, width)).max(axis=2)
    grown = B.person_hole(mask, grow_px=2 * scale)
    thin = (contrast >= B.ATTACHED_CONTRAST) & (near < (B.ATTACHED_REACH * height) ** 2) & ~grown & picture
    contact = grown & (near < (B.ATTACHED_CONTACT * height) ** 2)
    reach = cv2.dilate(contact.astype(np.uint8), B.disc(B.ATTACHED_GAP_PX * scale)) > 0
    _, parts = cv2.connectedComponents(thin.astype(np.uint8))
    touching = np.unique(parts[reach & thin])
    return np.isin(parts, touching[touching > 0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("photos", nargs="+")
    parser.add_argument("--ankles", action="store_true", help="also the shipped rule searched from the ankles")
    args = parser.parse_args()
    header = "| photo | every thin part that touches near a wrist | ... that is a line | ... and straight (kept) |"
    print(header + (" from the ankles too |" if args.ankles else ""))
    print("| --- | ---: | ---: | ---: |" + (" ---: |" if args.ankles else ""))
    for path in args.photos:
        ref = load_reference(path, size=256, domain="body", crop_person=True)
        picture = ref.picture_mask()
        mask = np.where(picture, ref.person.mask, 0) > 0.5
        image = np.ascontiguousarray(ref.image, np.uint8)
        area = mask.sum()
        shares = [touching_thin_parts(image, mask, ref.pose.points[WRISTS], picture).sum() / area]
        bend = B.ATTACHED_BEND_PX
        B.ATTACHED_BEND_PX = float("inf")  # the line test only
        shares.append(B.attached_objects(image, mask, ref.pose.points[WRISTS], picture=picture).sum() / area)
        B.ATTACHED_BEND_PX = bend
        shares.append(B.attached_objects(image, mask, ref.pose.points[WRISTS], picture=picture).sum() / area)
        if args.ankles:
            anchors = ref.pose.points[WRISTS + ANKLES]
            shares.append(B.attached_objects(image, mask, anchors, picture=picture).sum() / area)
        print(f"| `{path.split('/')[-1]}` | " + " | ".join(f"{s:.1%}" for s in shares) + " |")


if __name__ == "__main__":
    main()
