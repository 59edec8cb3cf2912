"""The pose check: the project's pose estimator against MediaPipe's own BlazePose full pipeline.

    python scripts/compare_pose_mediapipe.py --mediapipe-python /tmp/mpvenv/bin/python PHOTO [PHOTO ...] \
        [--json out/pose_vs_mediapipe.json]

The project runs the same two BlazePose networks as MediaPipe (`pose_detection.tflite`, `pose_landmark_full.tflite`)
with its own pre- and post-processing (anchors, ROI, landmark decoding: ``motion2video.pose``), because the
``mediapipe`` wheel cannot share the project's environment (it pins numpy<2 and protobuf<5). This script measures
how far that re-implementation lands from MediaPipe's: MediaPipe runs in another Python environment given by
``--mediapipe-python`` (make one with ``python3 -m venv /tmp/mpvenv && /tmp/mpvenv/bin/pip install
mediapipe==0.10.21``; ``Pose(static_image_mode=True, model_complexity=1)``, the full model), prints its 33
landmarks per photo as JSON, and both sets are mapped to the canonical H36M-17 joints.

Per photo: the error of each of the 17 joints in pixels and as a fraction of the person's height (MediaPipe's
head-top-to-lowest-ankle extent), the median over joints (the target: <= 5% of the height) and the limb
error (each of the 16 bones' two end points, averaged). Writes JSON; prints one line per photo.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# Run by --mediapipe-python: argv = photos; prints {photo: [[x, y], ...33] or null}.
SNIPPET = r"""
import json, sys
import cv2
import mediapipe as mp
out = {}
with mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1) as pose:
    for path in sys.argv[1:]:
        image = cv2.cvtColor(cv2.imread(path), cv2.COLOR_BGR2RGB)
        h, w = image.shape[:2]
        res = pose.process(image)
        out[path] = None if res.pose_landmarks is None else [[p.x * w, p.y * h] for p in res.pose_landmarks.landmark]
print(json.dumps(out))
"""


def mediapipe_landmarks(python: str, photos: list[Path]) -> dict[str, np.ndarray | None]:
    run = subprocess.run([python, "-c", SNIPPET, *map(str, photos)], capture_output=True, text=True, check=True)
    data = json.loads(run.stdout.strip().splitlines()[-1])
    return {k: None if v is None else np.asarray(v, np.float64) for k, v in data.items()}


def compare(ours: np.ndarray, theirs: np.ndarray) -> dict:
    """Joint and limb errors between two (33, 2) landmark sets, as pixels and fractions of the person's height."""
    from motion2video.core.skeletons import H36M_17
    from motion2video.pose.h36m import blazepose_to_h36m

    a, _ = blazepose_to_h36m(ours)
    b, _ = blazepose_to_h36m(theirs)
    height = float(theirs[:, 1].max() - theirs[:, 1].min())
    joint = np.linalg.norm(a - b, axis=1)  # (17,)
    bones = [(int(p), c) for c, p in enumerate(H36M_17.parents) if p >= 0]
    limb = np.array([(joint[p] + joint[c]) / 2 for p, c in bones])
    return {"height_px": round(height, 1), "median_joint_px": round(float(np.median(joint)), 2),
            "median_joint_of_height": round(float(np.median(joint) / height), 4),
            "median_limb_of_height": round(float(np.median(limb) / height), 4),
            "max_joint_of_height": round(float(joint.max() / height), 4),
            "joint_px": [round(float(v), 2) for v in joint]}


def main(argv: list[str] | None = None) -> int:
    import cv2

    from motion2video.pose.estimate import default_model, estimate_image

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("photos", nargs="+", type=Path)
    parser.add_argument("--mediapipe-python", required=True, help="a Python with mediapipe==0.10.21 installed")
    parser.add_argument("--json", type=Path, default=ROOT / "out" / "pose_vs_mediapipe.json")
    args = parser.parse_args(argv)
    theirs = mediapipe_landmarks(args.mediapipe_python, args.photos)
    model = default_model()
    report = {}
    for photo in args.photos:
        image = cv2.cvtColor(cv2.imread(str(photo)), cv2.COLOR_BGR2RGB)
        ours = estimate_image(image, model=model, source=photo).landmarks.xy[:33]
        ref = theirs.get(str(photo))
        if ref is None:
            report[photo.name] = {"mediapipe": "no person found"}
        else:
            report[photo.name] = compare(np.asarray(ours, np.float64), ref)
        print(photo.name, json.dumps({k: v for k, v in report[photo.name].items() if k != "joint_px"}))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=1) + "\n")
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
