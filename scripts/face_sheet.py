"""Contact sheet of the pictured face over the generated heads: photos driven by a motion-capture clip's frames.

For each photo (a body reference, its pose estimated), the clip's observed frames drive the mesh frame generator
(``synthesize``'s path: the motion model only supplies the structures of the observed frames, which are the clip's
own) and each picked frame is drawn twice: the generator's own head, and with the photo's face laid over it
(:mod:`motion2video.generator.head_paste`). The sheet shows the whole frame and a close-up of the head (nearest
neighbour, so the pixels are the frame's); ``--json`` records, per photo, how much of the face each frame took and
in what share of all the frames a face detector finds a face on the head, either way.

    python scripts/face_sheet.py ../shared/data/mocap/cmu/08_01.bvh ../shared/data/photos/woman_blue_tracksuit.jpg \
        ../shared/data/photos/fashion_man_red_jacket.png ../shared/data/photos/skier.jpg --size 512 --columns 3 \
        -o docs/images/face_sheet.png --json out/face_sheet.json
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from motion2video.core.skeletons import HEAD, NECK, THORAX

CLOSE_UP_PX = 96  # the head close-up's side on the sheet
LABEL_PX = 14


def head_close_up(frame: np.ndarray, points: np.ndarray, side: int = CLOSE_UP_PX) -> np.ndarray:
    """(side, side, 3) the square of 1.6 x the thorax-to-head distance around the head of (17, 2) joints, enlarged
    by nearest neighbour."""
    centre = 0.5 * (points[NECK] + points[HEAD])
    half = max(4.0, 0.8 * float(np.linalg.norm(points[HEAD] - points[THORAX])))
    k = side / (2 * half)
    mat = np.array([[k, 0.0, -(centre[0] - half) * k], [0.0, k, -(centre[1] - half) * k]])
    return cv2.warpAffine(frame, mat, (side, side), flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)


def label(image: np.ndarray, text: str) -> np.ndarray:
    out = image.copy()
    cv2.rectangle(out, (0, 0), (min(out.shape[1], 8 + 7 * len(text)), LABEL_PX), (0, 0, 0), -1)
    cv2.putText(out, text, (2, LABEL_PX - 3), cv2.FONT_HERSHEY_SIMPLEX, 0.38, (255, 255, 255), 1, cv2.LINE_AA)
    return out


def detected_share(frames: np.ndarray, points: np.ndarray) -> float:
    """The share of (N, S, S, 3) frames in which BlazeFace finds a face in the square of 3 x the thorax-to-head
    distance around the head of their (N, 17, 2) joints, enlarged to 192 px: a face a detector can read."""
    from motion2video.stages.pictured_face import cut_square, face_mesh, head_square

    found = 0
    for frame, p in zip(frames, points):
        square = cv2.resize(cut_square(frame, head_square(p)), (192, 192), interpolation=cv2.INTER_CUBIC)
        found += bool(face_mesh().detect(np.ascontiguousarray(square)))
    return found / max(1, len(frames))


def photo_rows(net, photo: Path, clip, bundle, *, size: int, frames: int, columns: int, crop_person: bool
               ) -> tuple[list[np.ndarray], dict]:
    """Two rows (the generator's head, the photo's face) for one photo; the paste weights of the picked frames and
    the share of all the frames where a face detector finds the face (:func:`detected_share`), either way."""
    from dataclasses import replace

    from motion2video.stages.generation import mesh_frames, mesh_setup
    from motion2video.stages.reference import load_reference
    from motion2video.stages.sampling import sample_forecast
    from motion2video.stages.structure import render_structures

    ref = load_reference(photo, size=size, domain="body", crop_person=crop_person)
    fc = sample_forecast(bundle, clip, samples=1, observed=frames, horizon=1, start=0, seed=0)
    structures = render_structures(fc, domain="body", size=size, reference=ref)
    video = mesh_setup(net, ref, structures)
    every = np.arange(frames)
    all_after = mesh_frames(net, ref, structures, video, every)
    all_before = mesh_frames(net, ref, structures, replace(video, face=None), every)
    detected = {"generator's head": detected_share(all_before, structures.points[1:1 + frames]),
                "photo's face": detected_share(all_after, structures.points[1:1 + frames])}
    picked = np.linspace(0, frames - 1, columns).round().astype(int)
    after, before = all_after[picked], all_before[picked]
    points = structures.points[1 + picked]
    rows = []
    for name, frames_ in (("generator's head", before), ("photo's face", after)):
        cells = [np.concatenate([cv2.resize(f, (CLOSE_UP_PX, CLOSE_UP_PX), interpolation=cv2.INTER_AREA),
                                 head_close_up(f, p)], axis=1) for f, p in zip(frames_, points)]
        rows.append(label(np.concatenate(cells, axis=1), f"{photo.name}: {name}"))
    weights = None if video.head_weights is None else [round(float(w), 2) for w in video.head_weights[picked]]
    mean = None if video.head_weights is None else round(float(video.head_weights[:frames].mean()), 3)
    return rows, {"photo": photo.name, "size": size, "frames": picked.tolist(), "face_found": video.face is not None,
                  "weights": weights, "mean_weight": mean,
                  "face_detected_share": {k: round(v, 3) for k, v in detected.items()}}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clip", type=Path, help="motion-capture clip (.bvh) whose observed frames drive")
    parser.add_argument("photos", type=Path, nargs="+", help="reference photos")
    parser.add_argument("-o", "--output", type=Path, required=True, help="the sheet (.png)")
    parser.add_argument("--frame-model", default="frames-body-mesh-256")
    parser.add_argument("--motion-model", default="mixture-periodic")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--frames", type=int, default=32, help="observed frames of the clip")
    parser.add_argument("--columns", type=int, default=6, help="frames picked, spread over them")
    parser.add_argument("--crop-person", action="store_true")
    parser.add_argument("--json", type=Path, default=None, help="write each photo's numbers here")
    args = parser.parse_args(argv)

    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.models.checkpoint import load_model
    from motion2video.stages.clips import load_clip

    bundle = load_model(args.motion_model)
    net = load_frame_model(args.frame_model).model
    clip = load_clip(bundle, args.clip).data
    rows, infos = [], []
    for photo in args.photos:
        photo_sheet, info = photo_rows(net, photo, clip, bundle, size=args.size, frames=args.frames,
                                       columns=args.columns, crop_person=args.crop_person)
        rows += photo_sheet
        infos.append(info)
        print(info)
    if args.json is not None:
        import json

        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"clip": str(args.clip), "frame_model": args.frame_model, "photos": infos},
                                        indent=2) + "\n")
    sheet = np.concatenate(rows, axis=0)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.output), cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    print(f"wrote {args.output} ({sheet.shape[1]}x{sheet.shape[0]})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
