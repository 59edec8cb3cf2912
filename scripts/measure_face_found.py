"""One-off measurement: in how many future frames of ``synthesize`` videos a face detector finds a face on the person.

For each photo, ``motion2video synthesize`` (run from the checkout this script lies in) drives it with a motion
clip; in every future frame of every sample, BlazePose finds the person (the frame enlarged 4x), and the face
detector and face mesh look for a face around the head as ``stages.pictured_face.pictured_face`` does. Prints one
line per photo (share of frames with a face, the frames without one) and writes JSON.

    python scripts/measure_face_found.py ../shared/data/mocap/cmu/08_01.bvh PHOTO ... --out out/face_found
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import cv2
import imageio.v3 as iio
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def face_found(frame: np.ndarray, model) -> bool:
    """Whether a face lies on the head of the person BlazePose finds in ``frame`` (H, W, 3) uint8, enlarged 4x."""
    from motion2video.core.errors import InputError
    from motion2video.pose.estimate import estimate_image
    from motion2video.stages.pictured_face import pictured_face

    big = cv2.resize(frame, None, fx=4, fy=4, interpolation=cv2.INTER_CUBIC)
    try:
        pose = estimate_image(big, model=model)
    except InputError:
        return False
    return pictured_face(big, np.asarray(pose.points2d, np.float64)) is not None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("motion")
    parser.add_argument("photos", nargs="+")
    parser.add_argument("--out", required=True)
    parser.add_argument("--samples", type=int, default=2)
    parser.add_argument("--observed", type=int, default=16)
    args = parser.parse_args()
    from motion2video.pose.estimate import default_model

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    model = default_model()
    results = {}
    for photo in args.photos:
        video = out / f"{Path(photo).stem}.mp4"
        subprocess.run([sys.executable, "-m", "motion2video.cli", "synthesize", "--motion-model", "mixture-periodic",
                        "--frame-model", "frames-body-mesh-256", str(Path(args.motion).resolve()), "--reference",
                        str(Path(photo).resolve()), "--crop-person", "--samples", str(args.samples),
                        "--observed", str(args.observed), "-o", str(video.resolve())],
                       cwd=ROOT, check=True, capture_output=True)
        frames = iio.imread(video)  # (T, 256, samples x 258 - 2, 3): the samples side by side
        found = [face_found(frames[t, :, 258 * k:258 * k + 256], model)
                 for k in range(args.samples) for t in range(args.observed, len(frames))]
        missing = np.flatnonzero(~np.array(found)).tolist()
        results[Path(photo).name] = {"share": round(float(np.mean(found)), 3), "frames": len(found),
                                     "without": missing}
        print(Path(photo).name, results[Path(photo).name]["share"], missing, flush=True)
    (out / "face_found.json").write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
