"""How much H.264 re-encoding moves rendered frames: the numbers behind the golden tolerances for video files.

    python scripts/measure_golden_h264.py --json out/golden_h264.json [--shared ../shared] [--frames 50]

Real clips from ``shared/data/mocap`` (CMU 08_01 walk, MASS run) are rendered in each body style at 96 and 256
pixels (25 fps), then written with :func:`motion2video.formats.video.write_video` and read back with
:func:`motion2video.formats.video.read_video`. Per frame it measures the three golden metrics of
:mod:`motion2video.testing.golden` (max grey-level difference, rel_l1, 1 - SSIM) for:

- ``raw_vs_h264``: the rendered frames against the decoded mp4 (default crf 18, preset medium): a golden taken
  from the renderer compared with a video the pipeline wrote;
- ``h264_vs_h264_veryfast``: the decoded default mp4 against the decoded mp4 of the same frames at preset
  veryfast (another encoder setting, standing in for another libx264 build);
- ``h264_vs_h264_again``: the decoded mp4 against a second encode with the same settings (determinism);
- ``next_frame``: each rendered frame against the next one (the motion 1/25 s later), the size of a small real
  change that a tolerance must still catch.

The JSON record holds, per case, the worst and the median frame of each metric, plus versions.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from importlib import metadata
from pathlib import Path

import imageio_ffmpeg
import numpy as np

from motion2video.core.atomic import write_json
from motion2video.formats.io import load_motion, resample_motion
from motion2video.apps.render import render_motion
from motion2video.testing.golden import METRICS, frame_error
from motion2video.formats.video import read_video, write_video

CLIPS = {"cmu_08_01_walk": "mocap/cmu/08_01.bvh", "mass_run": "mocap/mass/mass_run.bvh"}
STYLES = ("skeleton", "heatmap", "mesh")
SIZES = (96, 256)
FPS = 25.0


def compare(a: np.ndarray, b: np.ndarray) -> dict:
    """Worst and median per-frame error of (T, H, W, 3) clips ``a`` vs ``b`` in every golden metric."""
    out = {}
    for metric in METRICS:
        errors = [frame_error(x, y, metric) for x, y in zip(a, b)]
        out[metric] = {"worst": max(errors), "median": statistics.median(errors)}
    return out


def roundtrip(frames: np.ndarray, folder: Path, tag: str, preset: str = "medium") -> np.ndarray:
    """Frames after write_video (H.264 crf 18, ``preset``) and read_video."""
    decoded, fps = read_video(write_video(folder / f"{tag}.mp4", frames, FPS, preset=preset))
    assert decoded.shape == frames.shape and abs(fps - FPS) < 1e-9, (decoded.shape, fps)
    return decoded


def measure(shared: Path, num_frames: int) -> dict:
    cases = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for clip, rel in CLIPS.items():
            motion = resample_motion(load_motion(shared / "data" / rel), FPS).slice(0, num_frames)
            for style in STYLES:
                for size in SIZES:
                    raw = render_motion(motion, style=style, size=size)
                    first = roundtrip(raw, folder, "first")
                    cases.append({
                        "clip": clip, "style": style, "size": size, "frames": int(raw.shape[0]),
                        "raw_vs_h264": compare(raw, first),
                        "h264_vs_h264_veryfast": compare(first, roundtrip(raw, folder, "veryfast", "veryfast")),
                        "h264_vs_h264_again": compare(first, roundtrip(raw, folder, "again")),
                        "next_frame": compare(raw[:-1], raw[1:]),
                    })
                    print(clip, style, size, {k: round(v["worst"], 5) for k, v in cases[-1]["raw_vs_h264"].items()},
                          flush=True)
    return {"cases": cases, "fps": FPS, "crf": 18,
            "versions": {"ffmpeg": imageio_ffmpeg.get_ffmpeg_version(),
                         **{p: metadata.version(p) for p in ("imageio-ffmpeg", "scikit-image", "numpy")}}}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True, help="where to write the JSON record")
    parser.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[2] / "shared",
                        help="the shared data folder (default ../shared beside the repository)")
    parser.add_argument("--frames", type=int, default=50, help="frames per clip at 25 fps (default 50 = 2 s)")
    args = parser.parse_args(argv)
    write_json(args.json, measure(args.shared, args.frames))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
