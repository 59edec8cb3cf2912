"""Peak memory of ``motion2video render`` on a long capture, written as JSON.

    python scripts/bench_long_bvh.py --json out/bench_long_bvh.json [--clip ../shared/data/mocap/cmu/13_10.bvh]
        [--repeat 16] [--size 256]

Builds the long capture in a temporary folder (never in the repository): the clip's MOTION lines repeated
``--repeat`` times with the ``Frames:`` count fixed (CMU 13_10 x 16: 38,352 frames at 120 fps, 5.3 minutes,
49 MB). Then runs ``/usr/bin/time -v python -m motion2video.cli render LONG.bvh -o OUT.mp4 --size N`` in a
fresh process and records its "Maximum resident set size" (the command process; ffmpeg children are not
included in GNU time's figure) and the wall time, plus the same for the clip itself.

Keys: ``long`` and ``original`` (``frames``, ``file_mb``, ``peak_rss_mb``, ``wall_s``), ``ratio_peak_to_file``
(long), ``target_mb`` (600) and ``config``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from motion2video.testing.golden import repeated_bvh

ROOT = Path(__file__).resolve().parents[1]


def measure(path: Path, out: Path, size: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT), OMP_NUM_THREADS="1")
    t0 = time.perf_counter()
    run = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "motion2video.cli", "render", str(path),
                          "-o", str(out), "--size", str(size), "--no-progress"],
                         capture_output=True, text=True, env=env, cwd=ROOT)
    wall = time.perf_counter() - t0
    if run.returncode != 0:
        raise SystemExit(f"render failed ({run.returncode}): {run.stderr.strip()[-500:]}")
    rss_kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", run.stderr).group(1))
    return {"file_mb": round(path.stat().st_size / 1e6, 1), "peak_rss_mb": round(rss_kb / 1024, 1),
            "wall_s": round(wall, 1), "stdout": run.stdout.strip()}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", required=True, help="where to write the results")
    parser.add_argument("--clip", default=str(ROOT.parent / "shared" / "data" / "mocap" / "cmu" / "13_10.bvh"))
    parser.add_argument("--repeat", type=int, default=16)
    parser.add_argument("--size", type=int, default=256)
    args = parser.parse_args()
    clip = Path(args.clip)
    with tempfile.TemporaryDirectory() as tmp:
        long = Path(tmp) / f"{clip.stem}_x{args.repeat}.bvh"
        frames = repeated_bvh(clip, long, args.repeat)
        result = {"long": {"frames": frames, **measure(long, Path(tmp) / "long.mp4", args.size)},
                  "original": {"frames": frames // args.repeat, **measure(clip, Path(tmp) / "orig.mp4", args.size)}}
    result["ratio_peak_to_file"] = round(result["long"]["peak_rss_mb"] / result["long"]["file_mb"], 2)
    result["target_mb"] = 600
    result["config"] = {"clip": str(clip), "repeat": args.repeat, "size": args.size}
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
