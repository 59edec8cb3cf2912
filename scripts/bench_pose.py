"""Pose-estimation speed: frames/s of `motion2video pose` on a 720p video, and the tracker's agreement with
per-frame detection. Writes JSON.

    python scripts/bench_pose.py --json out/bench_pose.json [--video ../shared/data/video/dancer.avi]
        [--frames 150] [--repeats 3] [--threads 2]

The 720p video is made from the first ``--frames`` frames of ``--video`` (padded to 16:9 by repeating the
border, resized to 1280x720, H.264) in a temporary folder. Timed: the whole estimate (decoding, detection,
tracking, landmarks, the mapping to H36M-17) after one warm-up run, median of ``--repeats``; and the two
models per call. Agreement: on the same frames, the tracked joints (ROI from the previous frame, before
smoothing) against the joints with the detector run on every frame, as the median over frames and joints of the distance in % of
the person's height (pelvis-relative height of the 2D head above the lowest ankle).
"""

from __future__ import annotations

import platform
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

from motion2video import __version__
from motion2video.evaluation.benchtools import bench_parser, median_ms, median_seconds, report
from motion2video.core.atomic import write_json
from motion2video.pose.blazepose import BlazePose, detection_roi
from motion2video.pose.estimate import estimate_video, iter_video_frames
from motion2video.pose.h36m import blazepose_to_h36m

SHARED = Path(__file__).resolve().parents[2] / "shared"


def make_720p(src: Path, dst: Path, frames: int) -> Path:
    """The first ``frames`` frames of ``src`` as a 1280x720 H.264 mp4 (padded to 16:9, border replicated)."""
    from motion2video.formats.video import write_video

    cap = cv2.VideoCapture(str(src))
    fps = cap.get(cv2.CAP_PROP_FPS)
    out = []
    for _ in range(frames):
        ok, frame = cap.read()
        if not ok:
            break
        h, w = frame.shape[:2]
        pad = max(0, int(round(h * 16 / 9)) - w) // 2
        wide = cv2.copyMakeBorder(frame, 0, 0, pad, pad, cv2.BORDER_REPLICATE)
        out.append(cv2.cvtColor(cv2.resize(wide, (1280, 720), interpolation=cv2.INTER_LINEAR), cv2.COLOR_BGR2RGB))
    cap.release()
    return write_video(dst, np.stack(out), fps, preset="veryfast", crf=18)


def agreement(video: Path, model: BlazePose) -> dict:
    """Tracked vs detected-every-frame 2D joints, % of the person's height."""
    tracked = estimate_video(video, model=model, smooth=False).points2d  # (T, 17, 2), the tracker alone
    detected = []
    for frame in iter_video_frames(video):
        dets = model.detect(frame)
        lm = model.landmarks(frame, detection_roi(max(dets, key=lambda d: detection_roi(d).size)))
        detected.append(blazepose_to_h36m(lm.xy[:33])[0])
    detected = np.stack(detected)[: len(tracked)]
    height = np.maximum(detected[:, [3, 6], 1].max(axis=1) - detected[:, 10, 1], 1.0)  # (T,) ankle - head, px
    err = np.linalg.norm(tracked - detected, axis=-1) / height[:, None] * 100  # (T, 17)
    return {"median_percent_of_height": round(float(np.median(err)), 3),
            "p95_percent_of_height": round(float(np.percentile(err, 95)), 3),
            "frames": int(len(tracked))}


def main(argv: list[str] | None = None) -> int:
    parser = bench_parser(__doc__)
    parser.add_argument("--video", type=Path, default=SHARED / "data" / "video" / "dancer.avi")
    parser.add_argument("--frames", type=int, default=150)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2, help="LiteRT threads per model (default 2)")
    args = parser.parse_args(argv)
    model = BlazePose(num_threads=args.threads)
    with tempfile.TemporaryDirectory() as tmp:
        video = make_720p(args.video, Path(tmp) / "video720.mp4", args.frames)
        n = sum(1 for _ in iter_video_frames(video))
        seconds = median_seconds(lambda: estimate_video(video, model=model), repeats=args.repeats, warmup=1)
        frame = next(iter_video_frames(video))
        det = model.detect(frame)[0]
        det_ms = median_ms(lambda: model.detect(frame), repeats=20, warmup=2)
        lmk_ms = median_ms(lambda: model.landmarks(frame, detection_roi(det)), repeats=20, warmup=2)
        decode_ms = median_ms(lambda: sum(1 for _ in iter_video_frames(video)), repeats=1) / n
        agree = agreement(video, model)
    fps = n / seconds
    payload = {
        "video": {"source": str(args.video), "frames": n, "size": [1280, 720]},
        "pose_frames_per_second": round(fps, 2),
        "pose_ms_per_frame": round(1000 / fps, 2),
        "target_frames_per_second": 15,
        "detector_ms": round(det_ms, 2),
        "landmark_ms": round(lmk_ms, 2),
        "decode_ms_per_frame": round(decode_ms, 2),
        "tracking_vs_detect_every_frame": agree,
        "threads": args.threads,
        "repeats": args.repeats,
        "versions": {"motion2video": __version__, "numpy": np.__version__, "opencv": cv2.__version__,
                     "python": sys.version.split()[0]},
        "machine": platform.platform(),
    }
    write_json(args.json, payload)
    report(args.json, f"pose on {n} frames of 1280x720: {fps:.1f} frames/s ({1000 / fps:.1f} ms/frame; "
                      f"detector {det_ms:.1f} ms, landmarks {lmk_ms:.1f} ms, decoding {decode_ms:.1f} ms per frame)",
           f"tracked vs detected every frame: median {agree['median_percent_of_height']}% of the person's "
           f"height (95th percentile {agree['p95_percent_of_height']}%)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
