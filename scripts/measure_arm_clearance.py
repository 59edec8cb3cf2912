"""How far ``renderers.collision`` moves the arms of real mocap clips before Anny is posed on them.

    python scripts/measure_arm_clearance.py [CLIP ...] [--data ../shared/data/mocap]

For each clip (default: the demo walk and five CMU clips), Anny at the default phenotype, sized to the clip as the
pose solver sizes it (``renderers.body.fitted_scale``): the share of frames where an elbow or a wrist moves, and the
median and largest move of a moved joint, in centimetres. A few seconds on one thread.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from motion2video.core.skeletons import L_ELBOW, L_WRIST, R_ELBOW, R_WRIST
from motion2video.formats.io import load_motion
from renderers import anny_model
from renderers.body import fitted_scale
from renderers.collision import arms_clear_of_torso

REPO = Path(__file__).resolve().parents[1]
CLIPS = ("cmu/02_01.bvh", "cmu/08_01.bvh", "cmu/13_42.bvh", "cmu/05_14.bvh", "cmu/16_02.bvh")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clips", nargs="*", help=f"clips under --data (default: the demo walk and {', '.join(CLIPS)})")
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data" / "mocap")
    args = parser.parse_args()
    paths = [args.data / c for c in args.clips] if args.clips else \
        [REPO / "demo_inputs" / "cmu_walk.npz", *(args.data / c for c in CLIPS)]
    rest = anny_model.anny_rest({})
    print("| clip | frames | frames with a moved arm joint | median move (cm) | largest move (cm) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for path in paths:
        joints = np.asarray(load_motion(path).joints, np.float64)
        cleared = arms_clear_of_torso(joints, rest, scale=fitted_scale(joints, rest))
        move = np.linalg.norm(cleared - joints, axis=-1)[:, [L_ELBOW, L_WRIST, R_ELBOW, R_WRIST]]
        moved = move > 0
        median = float(np.median(move[moved])) if moved.any() else 0.0
        print(f"| `{path.name}` | {len(joints)} | {moved.any(axis=1).mean():.0%} | {100 * median:.1f} | "
              f"{100 * move.max():.1f} |")


if __name__ == "__main__":
    main()
