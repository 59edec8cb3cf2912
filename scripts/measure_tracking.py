"""One person through a video: the largest pelvis jump between consecutive frames, the root's path, its extent
along its main direction and its travel in depth, and the frames the tracker was unsure of. Writes JSON.

    python scripts/measure_tracking.py VIDEO [VIDEO ...] --json out/tracking.json [--person largest]

Each video is estimated as `motion2video pose` estimates it (no cache), and measured by
:func:`motion2video.evaluation.tracking.track_measures`.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from motion2video.core.atomic import write_json
from motion2video.evaluation.tracking import track_measures
from motion2video.pose.estimate import estimate_video, parse_person


def measure(video: Path, person: str | int) -> dict:
    start = time.perf_counter()
    pose = estimate_video(video, person=person)
    result = track_measures(pose.points2d[:, 0], pose.joints3d[:, 0], pose.unsure).as_dict()
    result.update(video=str(video), first_frame=pose.first_frame, gaps=pose.gaps,
                  seconds=round(time.perf_counter() - start, 1))
    result["jump_frame"] += pose.first_frame  # as a frame of the video
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("videos", nargs="+", type=Path)
    parser.add_argument("--json", required=True, type=Path, help="output JSON")
    parser.add_argument("--person", default="largest", help="'largest' or an index left to right")
    args = parser.parse_args(argv)
    person = parse_person(args.person)
    results = []
    for video in args.videos:
        results.append(measure(video, person))
        print(results[-1], flush=True)
    write_json(args.json, {"videos": results})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
