"""One-off: the fitted head of a photo cut by the picture's edge against the whole photo's (the known answer).

The red jersey (``fashion_man_red_jacket.png``) and the tracksuit (``woman_blue_tracksuit.jpg``), whole and cut (at
his waist: the first 560 rows; at her thighs: the first 1150), loaded with ``--crop-person`` at 256 px and fitted as
``synthesize`` fits them (``mesh_setup``, the demo walk). For each: the fitted head's width and height, its centre's
offset right of the pictured eyes' midpoint and its crown above them, in units of the distance between the eyes;
with the body's scale from every bone, then from the bones the picture shows (``mesh_fit.MIN_SCALE_BONES``).

    python scripts/measure_cut_head.py
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import motion2video.generator.mesh_fit as mesh_fit  # noqa: E402
from motion2video.generator.checkpoint import load_frame_model  # noqa: E402
from motion2video.stages.generation import mesh_setup  # noqa: E402
from motion2video.stages.reference import load_reference  # noqa: E402
from motion2video.stages.structure import render_structures  # noqa: E402
from renderers import anny_model  # noqa: E402
from tests.test_head_paste import walk_forecast  # noqa: E402

PHOTOS = ROOT.parent / "shared" / "data" / "photos"


def head(net, path: Path) -> tuple[float, float, float, float]:
    reference = load_reference(path, size=256, domain="body", crop_person=True)
    video = mesh_setup(net, reference, render_structures(walk_forecast(), domain="body", size=256,
                                                         reference=reference))
    x0, y0, side = video.crop
    eyes = (np.asarray(reference.person.eyes) - [x0, y0]) * video.reference.masks.shape[-1] / side
    d = float(np.linalg.norm(eyes[0] - eyes[1]))
    uv = video.reference.uv[0][anny_model.head_vertices()]
    mid = eyes.mean(axis=0)
    return (np.ptp(uv[:, 0]) / d, np.ptp(uv[:, 1]) / d, (uv[:, 0].mean() - mid[0]) / d, (mid[1] - uv[:, 1].min()) / d)


def main() -> None:
    net = load_frame_model("frames-body-mesh-256").model
    folder = Path(tempfile.mkdtemp())
    cuts = {}
    for name, rows in (("fashion_man_red_jacket.png", 560), ("woman_blue_tracksuit.jpg", 1150)):
        cuts[name] = folder / f"cut_{Path(name).stem}.png"
        cv2.imwrite(str(cuts[name]), cv2.imread(str(PHOTOS / name), cv2.IMREAD_UNCHANGED)[:rows])
    print("photo | scale from | width | height | centre right of the eyes | crown above the eyes")
    for name, cut in cuts.items():
        print(name, "whole | - | %.2f | %.2f | %.2f | %.2f" % head(net, PHOTOS / name))
        for label, bones in (("every bone", 99), ("the shown bones", 4)):
            mesh_fit.MIN_SCALE_BONES = bones
            print(name, f"cut | {label} | %.2f | %.2f | %.2f | %.2f" % head(net, cut))


if __name__ == "__main__":
    main()
