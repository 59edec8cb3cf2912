"""The skirt panel measured: a skirt painted over a shared photo, driven by a real walk, with and without the panel.

    python scripts/measure_skirt.py --sheet docs/images/skirt_sheet.png --json out/skirt.json

No shared photo shows a skirt or a dress, so a knee-length striped skirt is painted over the tracksuit trousers of
``woman_blue_tracksuit.jpg`` (tests/test_garment.py does the same). ``synthesize`` makes 16 observed + 48 future
frames of it (``mixture-periodic``, CMU 08_01, ``--crop-person``, seed 0) with ``frames-body-mesh-256`` and
``frames-body-128`` (at 256), each once as shipped and once with the panel switched off. Printed and written to
--json: on the frames whose legs stand apart (15 px at 128, scaled), the share of points between the legs just
above the hem that show the skirt's colour. The sheet: eight frames of each run, one row each.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import imageio.v3 as iio
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import motion2video.stages.generation as generation  # noqa: E402
import motion2video.stages.mesh_generation as mesh_generation  # noqa: E402
from motion2video.apps.synthesize import SynthesisConfig  # noqa: E402
from motion2video.apps.synthesize import synthesize as synthesize_app  # noqa: E402
from motion2video.generator.garment import (LEFT_LEG, RIGHT_LEG, colours_at, find_skirt, lab_image,  # noqa: E402
                                            leg_points)
from motion2video.pose.estimate import estimate_image  # noqa: E402
from test_garment import WALK, skirt_photo  # noqa: E402


def run(frame_model: str, reference: Path, *, panel: bool) -> tuple[np.ndarray, np.ndarray]:
    """(T, S, S, 3) frames and (T, 17, 2) their poses, the panel on or off."""
    find, warp = mesh_generation.find_skirt, generation.warp_skirt
    if not panel:
        mesh_generation.find_skirt = lambda *args, **kw: None
        generation.warp_skirt = lambda *args, **kw: None
    try:
        frames = []
        result = synthesize_app(motion_model="mixture-periodic", frame_model=frame_model, input_path=WALK,
                                reference=reference, output=None,
                                config=SynthesisConfig(samples=1, horizon=48, crop_person=True, size=256),
                                on_chunk=lambda start, chunk, previews: frames.append(chunk[:, 0]))
    finally:
        mesh_generation.find_skirt, generation.warp_skirt = find, warp
    frames = np.concatenate(frames)
    return frames, result.structures.points[1:1 + len(frames)]


def between_shares(frames: np.ndarray, joints: np.ndarray, skirt) -> list[float]:
    """Per frame whose legs stand apart, the share of 15 points across the middle of the span between the legs,
    just above the hem, within 25 Lab units of the skirt's colour."""
    u = np.array([skirt.hem - 0.15])
    apart = 15.0 * frames.shape[1] / 128
    shares = []
    for frame, pts in zip(frames, joints):
        right, left = leg_points(pts, RIGHT_LEG, u)[0], leg_points(pts, LEFT_LEG, u)[0]
        if np.linalg.norm(right - left) < apart:
            continue
        between = right + np.linspace(0.2, 0.8, 15)[:, None] * (left - right)
        colours = colours_at(lab_image(frame), np.ones(frame.shape[:2], bool), between, 0.5)
        shares.append(float((np.linalg.norm(colours - skirt.colour, axis=1) < 25.0).mean()))
    return shares


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sheet", default=str(ROOT / "docs" / "images" / "skirt_sheet.png"))
    parser.add_argument("--json", default=str(ROOT / "out" / "skirt.json"))
    args = parser.parse_args(argv)
    image = skirt_photo()
    pose = estimate_image(image)
    skirt = find_skirt(image, pose.landmarks.person_mask(pose.width, pose.height), pose.points2d)
    out = ROOT / "out" / "skirt"
    out.mkdir(parents=True, exist_ok=True)
    reference = out / "skirt.png"
    iio.imwrite(reference, image)
    record, rows = {"hem": skirt.hem}, []
    for frame_model in ("frames-body-mesh-256", "frames-body-128"):
        for panel in (False, True):
            frames, joints = run(frame_model, reference, panel=panel)
            shares = between_shares(frames, joints, skirt)
            label = f"{frame_model}, panel {'on' if panel else 'off'}"
            record[label] = {"frames_apart": len(shares), "mean": float(np.mean(shares)), "min": float(np.min(shares))}
            print(f"{label}: {len(shares)} frames with the legs apart, skirt between them mean {np.mean(shares):.2f}, "
                  f"min {np.min(shares):.2f}", flush=True)
            picked = frames[np.linspace(16, len(frames) - 1, 8).astype(int)]
            row = np.concatenate(list(picked), axis=1).copy()
            cv2.putText(row, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (255, 255, 255), 3, cv2.LINE_AA)
            cv2.putText(row, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (0, 0, 0), 1, cv2.LINE_AA)
            rows.append(row)
    sheet = np.concatenate(rows, axis=0)
    Path(args.sheet).parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(args.sheet, sheet)
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(record, indent=1))
    print(f"wrote {args.sheet} and {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
