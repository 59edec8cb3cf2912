"""One-off: half-length portraits driven by a real video, framed around the whole guessed body against the picture's
own framing (``load_reference(keep_framing=...)``); for each, the share of output frames where MediaPipe's face
detector and face mesh find a face, the median face height, the wall time, and a contact sheet.

    python scripts/measure_portrait_framing.py --json out/portrait_framing.json \
        --sheet docs/images/portrait_framing_sheet.jpg
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import cv2
import numpy as np

import motion2video.apps.synthesize as synth
from motion2video.pose.facemesh import MIN_PRESENCE, detection_roi
from motion2video.stages.pictured_face import face_mesh
from motion2video.stages.reference import load_reference

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
PORTRAITS = ("portrait_mona_lisa.jpg", "portrait_pearl_earring.jpg")
MODELS = ("frames-body-mesh-256", "frames-body-128")
SHEET_STEPS = (0, 16, 28, 40, 52, 63)


def run(photo: Path, frame_model: str, keep: bool) -> tuple[np.ndarray, float]:
    """(K, T, S, S, 3) the frames of two futures of the dancer's first 64 frames, and the wall time."""
    def loader(*args, keep_framing=False, **kwargs):
        return load_reference(*args, keep_framing=keep and keep_framing, **kwargs)

    synth.load_reference = loader
    chunks = []
    t0 = time.perf_counter()
    synth.synthesize(motion_model="mixture-periodic", frame_model=frame_model,
                     input_path=SHARED / "video" / "dancer.avi", reference=photo, output=None,
                     config=synth.SynthesisConfig(samples=2, crop_person=True),
                     on_chunk=lambda start, frames, previews: chunks.append(frames))
    return np.concatenate(chunks).transpose(1, 0, 2, 3, 4), time.perf_counter() - t0


def faces(frames: np.ndarray) -> tuple[float, float]:
    """Share of frames with a face found, and the median face height (landmarks' extent) in pixels."""
    mesh = face_mesh()
    heights = []
    flat = frames.reshape(-1, *frames.shape[-3:])
    for frame in flat:
        frame = np.ascontiguousarray(frame)
        found = mesh.detect(frame)
        if found:
            marks = mesh.landmarks(frame, detection_roi(found[0]))
            if marks.score >= MIN_PRESENCE:
                heights.append(float(np.ptp(marks.xy[:, 1])))
    return len(heights) / len(flat), float(np.median(heights)) if heights else 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    parser.add_argument("--sheet", type=Path, required=True)
    args = parser.parse_args()
    rows, tiles = [], []
    for name in PORTRAITS:
        for model in MODELS:
            for keep in (False, True):
                frames, wall = run(SHARED / "photos" / name, model, keep)
                share, height = faces(frames)
                rows.append({"portrait": name, "model": model, "framing": "picture" if keep else "whole pose",
                             "frames": int(np.prod(frames.shape[:2])), "face_found": round(share, 3),
                             "median_face_px": round(height, 1), "size": int(frames.shape[-2]),
                             "wall_s": round(wall, 1)})
                print(rows[-1], flush=True)
                tiles.append(np.concatenate([cv2.resize(frames[0, t], (160, 160), interpolation=cv2.INTER_AREA)
                                             for t in SHEET_STEPS], axis=1))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(rows, indent=1))
    sheet = np.concatenate(tiles, axis=0)
    cv2.imwrite(str(args.sheet), cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()
