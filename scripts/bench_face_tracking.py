"""Face tracking: speed (frames/s of the face mesh tracker, and of the Anny fit) and accuracy (landmarks
re-projected from the fitted Anny head against the tracked ones, in face sizes) on real face videos. Writes
JSON, and a contact sheet per video (video frame | the tracked face motion drawn by the face renderer |
the tracked landmarks in green and the re-projected ones in red).

    PYOPENGL_PLATFORM=osmesa python scripts/bench_face_tracking.py --json out/bench_face_tracking.json \
        [--videos ../shared/data/video/face_talking_woman.mp4 ...] [--size 512] [--threads 2] \
        [--sheets out/face_sheets] [--frames 0]

Tracking is timed on frames already decoded and resized so that their long side is ``--size`` pixels
(detector, landmark model, ROI geometry); the fit (smoothing, gap filling, pose and 52 coefficients per frame,
and the error measurement) is timed on its own, after Anny's one-off construction. The error is measured
through Anny's full forward (the head as the face renderer poses it). Face size: the long side of the
landmarks' bounding box. The machine's load average is recorded beside the times (the cores may be shared).
"""

from __future__ import annotations

import itertools
import os
import platform
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from motion2video import __version__
from motion2video.core.atomic import write_json
from motion2video.evaluation.benchtools import bench_parser, report
from motion2video.pose.estimate import iter_video_frames, open_video
from motion2video.pose.face_track import face_track_from_landmarks, track_faces
from motion2video.pose.facemesh import FaceMesh

SHARED = Path(__file__).resolve().parents[2] / "shared"
VIDEOS = ("face_talking_woman.mp4", "face_talking_man_glasses.mp4")
SHEET_FRAMES = 6


def resized_frames(path: Path, size: int, limit: int) -> tuple[list[np.ndarray], float]:
    """Frames of ``path`` (RGB) with the long side scaled to ``size`` pixels, and the scale applied."""
    frames = []
    scale = 1.0
    source = iter_video_frames(path)
    for frame in (itertools.islice(source, limit) if limit > 0 else source):
        h, w = frame.shape[:2]
        scale = size / max(h, w)
        if scale != 1.0:
            frame = cv2.resize(frame, (round(w * scale), round(h * scale)), interpolation=cv2.INTER_AREA)
        frames.append(frame)
    return frames, scale


def sheet(frames: list[np.ndarray], track, out: Path) -> Path:
    """Video | face render | landmarks, for SHEET_FRAMES frames spread over the clip."""
    from motion2video.formats.video import contact_sheet, write_image
    from renderers.face import FaceRenderer, FaceStyle

    picks = np.linspace(0, track.num_frames - 1, SHEET_FRAMES).round().astype(int)
    side = 256
    renderer = FaceRenderer(FaceStyle(size=(side, side)))
    drawn = renderer.render(track.motion)
    renderer.close()
    from motion2video.pose.face_track import fitted_landmarks2d

    reproj = fitted_landmarks2d(track)[picks]
    rows = []
    for k, t in enumerate(picks):
        frame = frames[track.first_frame + t]
        h, w = frame.shape[:2]
        s = side / max(h, w)
        def fit_square(img):
            img = cv2.resize(img, (round(w * s), round(h * s)), interpolation=cv2.INTER_AREA)
            pad = np.full((side, side, 3), 255, np.uint8)
            y0, x0 = (side - img.shape[0]) // 2, (side - img.shape[1]) // 2
            pad[y0:y0 + img.shape[0], x0:x0 + img.shape[1]] = img
            return pad, np.array([x0, y0])
        video, off = fit_square(frame)
        marks = video.copy()
        for p in track.landmarks2d[t] * s + off:
            cv2.circle(marks, (int(p[0]), int(p[1])), 1, (0, 200, 0), -1)
        for p in reproj[k] * s + off:
            cv2.circle(marks, (int(p[0]), int(p[1])), 1, (230, 0, 0), -1)
        rows.append(np.concatenate([video, drawn[t], marks], axis=1))
    return write_image(out, contact_sheet(np.stack(rows), columns=2))


def main(argv: list[str] | None = None) -> int:
    parser = bench_parser(__doc__)
    parser.add_argument("--videos", nargs="+", type=Path, default=[SHARED / "data" / "video" / v for v in VIDEOS])
    parser.add_argument("--size", type=int, default=512, help="long side of the tracked frames, pixels")
    parser.add_argument("--threads", type=int, default=2, help="LiteRT threads per model")
    parser.add_argument("--frames", type=int, default=0, help="first N frames only (0: all)")
    parser.add_argument("--sheets", type=Path, default=None, help="folder for the contact sheets")
    args = parser.parse_args(argv)

    model = FaceMesh(num_threads=args.threads)
    from motion2video.pose.face_anny import head_basis, posed_landmarks

    head_basis()  # Anny's construction and the basis at the landmarks: once per process, not timed
    posed_landmarks(np.zeros((1, 52)), np.zeros((1, 3)), np.zeros((1, 3)))
    record: dict = {"version": __version__, "python": sys.version.split()[0], "machine": platform.machine(),
                    "cpu_count": os.cpu_count(), "size": args.size, "threads": args.threads, "videos": {}}
    lines = []
    for path in args.videos:
        _, info = open_video(path)
        frames, scale = resized_frames(path, args.size, args.frames)
        list(track_faces(frames[:5], model=model))  # warm-up
        load_before = os.getloadavg()[0]
        start = time.perf_counter()
        results = list(track_faces(frames, model=model))
        track_s = time.perf_counter() - start
        start = time.perf_counter()
        track = face_track_from_landmarks(results, fps=info.fps, width=frames[0].shape[1],
                                          height=frames[0].shape[0], source=path)
        fit_s = time.perf_counter() - start
        load_after = os.getloadavg()[0]
        rel = track.relative_error()  # (T, 468)
        per_frame = np.median(rel, axis=1)
        entry = {
            "frames": len(frames), "tracked_frames": track.num_frames,
            "found": int(sum(r is not None for r in results)),
            "gaps": track.gaps, "frame_size": [int(frames[0].shape[1]), int(frames[0].shape[0])],
            "scale_from_video": scale,
            "tracking_fps": len(frames) / track_s, "fit_and_measure_fps": track.num_frames / fit_s,
            "load_average_1min": [load_before, load_after],
            "reprojection_median_face_size": float(np.median(rel)),
            "reprojection_p90_face_size": float(np.percentile(rel, 90)),
            "worst_frame_median_face_size": float(per_frame.max()),
            "reprojection_median_px": float(np.median(track.reprojection)),
            "face_size_median_px": float(np.median(track.face_size())),
        }
        if args.sheets is not None:
            entry["sheet"] = str(sheet(frames, track, args.sheets / f"{path.stem}_sheet.png"))
        record["videos"][path.name] = entry
        lines.append(f"{path.name}: tracking {entry['tracking_fps']:.1f} frames/s at {entry['frame_size']}, fit "
                     f"{entry['fit_and_measure_fps']:.1f} frames/s; re-projection median "
                     f"{100 * entry['reprojection_median_face_size']:.2f}% of the face size (p90 "
                     f"{100 * entry['reprojection_p90_face_size']:.2f}%), load {load_before:.1f}-{load_after:.1f}")
    write_json(args.json, record)
    report(args.json, *lines)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
