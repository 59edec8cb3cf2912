"""Batch throughput, measured side by side in one run and written as JSON.

    python scripts/bench_batch.py --json out/bench_batch.json [--clips 24] [--frames 300] [--repeats 5]

The same jobs (``render CLIP --style skeleton --size 256 --fps 30 --frames F``, every output written) for
the first ``--clips`` BVH clips of ``../shared/data/mocap`` (manifest order) that last at least F / 30 s at
the manifest's frame rate, so that every job renders F frames (10 s of video with the defaults), run on:

- the local pool with 1 worker and with 2 workers, as ``motion2video batch`` runs them (each worker encodes
  in its own process through PyAV, with one x264 thread),
- Ray (a local instance with 2 CPUs) with 2 workers,
- for comparison, the local pool with 1 and 2 workers whose encoder is a separate ffmpeg process per job
  (``MOTION2VIDEO_ENCODER=ffmpeg``, what interactive commands use, and what batch used before),

alternating, ``--repeats`` times each; the median wall time is kept. Every engine is started, its
workers warmed up (processes started, commands imported) and one untimed round of 4 real jobs run before
the clock starts, as in a long batch where start-up is paid once; the start-up times are recorded too.
The local Ray instance is up only for its own rounds (started, warmed and shut down each time): its
background processes take CPU while it is up, and a user of the local pool does not have them running.

Keys:

- ``workers2_vs_1``: wall(1 local worker) / wall(2 local workers); target >= 1.7 on an idle 2-core machine.
- ``ray_vs_local``: wall(Ray, 2 workers) / wall(local pool, 2 workers); target <= 1.25.
- ``clips_per_core_hour``: clips / (wall x 2 cores) of the 2-worker local run, in clips per core-hour.
  The video seconds behind it are counted from the frames the jobs wrote (``results``), not assumed.
- ``encoders``: ``workers2_vs_1`` and ``clips_per_core_hour`` for each encoder (``pyav``: the keys above;
  ``ffmpeg``: the separate-process encoder), measured in the same run.
- ``capacity``: skeleton (the jobs above) and mesh (``--mesh-clips`` jobs of ``--mesh-frames`` frames,
  1 worker) video seconds rendered per core-second, and the core-hours for 10,000 clips of 10 s at 30 fps
  and 256x256 in each style.
- ``load_average``: ``os.getloadavg()`` before and after: on a shared machine other jobs take cores and
  the ratios drop; read them with it.
"""

from __future__ import annotations

import csv
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

from motion2video.core.atomic import write_json
from motion2video.apps.batch import (BatchConfig, Job, LocalPool, init_ray, jobs_from_template, run_ray, warm_ray)
from motion2video.evaluation.benchtools import bench_parser, report
from motion2video.formats.video import ENCODER_ENV

MOCAP = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
FPS = 30


def long_clips(count: int, seconds: float) -> list[Path]:
    """The first ``count`` BVH clips of the manifest lasting at least ``seconds`` at the manifest's fps."""
    with open(MOCAP / "manifest.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    found = [MOCAP / r["file"] for r in rows if r["file"].endswith(".bvh") and r["frames"] and r["fps"]
             and int(r["frames"]) / float(r["fps"]) >= seconds and (MOCAP / r["file"]).is_file()]
    if len(found) < count:
        raise SystemExit(f"only {len(found)} BVH clips of at least {seconds:g} s in {MOCAP / 'manifest.csv'}")
    return found[:count]


def make_jobs(clips: list[Path], out: Path, *, style: str, frames: int) -> list[Job]:
    jobs = []
    for clip in clips:
        jobs += jobs_from_template(str(clip), f"render {{input}} -o {{output}} --style {style} --size 256 "
                                   f"--fps {FPS} --frames {frames}", out)
    return jobs


def timed(run, jobs: list[Job]) -> tuple[float, list]:
    rows = []
    start = time.perf_counter()
    run(jobs, rows.append)
    seconds = time.perf_counter() - start
    failed = [r for r in rows if r.status != "ok"]
    if failed or len(rows) != len(jobs):
        raise RuntimeError(f"benchmark jobs failed: {failed[:3]}")
    return seconds, rows


def main(argv: list[str] | None = None) -> int:
    parser = bench_parser(__doc__)
    parser.add_argument("--clips", type=int, default=24, help="skeleton jobs (default 24)")
    parser.add_argument("--frames", type=int, default=300, help="frames per skeleton job at 30 fps (default 300: the 10-s clips of the capacity plan)")
    parser.add_argument("--repeats", type=int, default=5, help="runs per engine, alternating (median kept)")
    parser.add_argument("--mesh-clips", type=int, default=2, help="mesh jobs for the capacity estimate")
    parser.add_argument("--mesh-frames", type=int, default=300, help="frames per mesh job (default 300: 10-s clips, as the skeleton jobs)")
    parser.add_argument("--no-ray", action="store_true", help="skip Ray (ray_vs_local is recorded as null)")
    args = parser.parse_args(argv)

    clips = long_clips(args.clips, args.frames / FPS)
    load_before = os.getloadavg()
    record = {"config": {"clips": len(clips), "clip_files": [str(c.relative_to(MOCAP)) for c in clips], "frames": args.frames, "fps": FPS, "size": 256, "style": "skeleton",
                         "repeats": args.repeats, "cpu_count": os.cpu_count(),
                         "python": sys.version.split()[0]}}
    walls: dict[str, list[float]] = {"local1": [], "local2": [], "ray2": [], "local1_ffmpeg": [], "local2_ffmpeg": []}
    startup = {}
    frames_written: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        pools = {}
        # Workers read the encoder from the environment they are started with: the ffmpeg-process pools
        # first, then the batch default (PyAV) for the others, Ray included.
        for encoder in ("ffmpeg", None):
            if encoder:
                os.environ[ENCODER_ENV] = encoder
            else:
                os.environ.pop(ENCODER_ENV, None)
            for workers in (1, 2):
                name = f"local{workers}" + (f"_{encoder}" if encoder else "")
                start = time.perf_counter()
                pools[name] = LocalPool(workers)
                pools[name].warm()
                startup[f"{name}_s"] = time.perf_counter() - start
        engines = {name: (lambda jobs, cb, pool=pool: pool.run(jobs, retries=0, on_result=cb))
                   for name, pool in pools.items()}
        ray_engine = lambda jobs, cb: run_ray(jobs, workers=2, retries=0, address=None, on_result=cb)  # noqa: E731
        ray_started = False
        try:
            for name, run in engines.items():  # one untimed round of real jobs per engine
                timed(run, make_jobs(clips[:4], tmp / f"warm_{name}", style="skeleton", frames=args.frames))
            for r in range(args.repeats):
                rounds = list(engines.items()) + ([] if args.no_ray else [("ray2", ray_engine)])
                for name, run in rounds:
                    if name == "ray2":
                        # Ray's own processes (GCS, raylet, agents) keep taking CPU while it is up: it runs
                        # only for its own rounds, so that the local pools are measured as a user runs them.
                        start = time.perf_counter()
                        init_ray(2)
                        ray_started = True
                        warm_ray(2)
                        timed(run, make_jobs(clips[:4], tmp / f"warm_ray_{r}", style="skeleton", frames=args.frames))
                        startup.setdefault("ray2_s", []).append(time.perf_counter() - start)
                    jobs = make_jobs(clips, tmp / f"{name}_{r}", style="skeleton", frames=args.frames)
                    seconds, rows = timed(run, jobs)
                    walls[name].append(seconds)
                    frames_written[name] = sum(row.frames or 0 for row in rows)
                    print(f"{name} run {r + 1}: {seconds:.1f} s for {len(jobs)} clips (load {os.getloadavg()[0]:.1f})")
                    if name == "ray2":
                        import ray

                        ray.shutdown()
                        ray_started = False
            mesh_jobs = make_jobs(clips[: args.mesh_clips], tmp / "mesh", style="mesh", frames=args.mesh_frames)
            timed(engines["local1"], mesh_jobs[:1])  # first mesh job: Anny model and GL context
            mesh_s, mesh_rows = timed(engines["local1"], make_jobs(clips[: args.mesh_clips], tmp / "mesh2",
                                                                   style="mesh", frames=args.mesh_frames))
        finally:
            for pool in pools.values():
                pool.close()
            if ray_started:
                import ray

                ray.shutdown()
    median = {k: statistics.median(v) for k, v in walls.items() if v}
    skeleton_rate = frames_written["local2"] / FPS / (median["local2"] * 2)  # video s per core-second
    mesh_rate = sum(row.frames or 0 for row in mesh_rows) / FPS / mesh_s
    corpus_video_s = 10_000 * 10.0
    per_hour = {k: len(clips) / (median[k] * 2 / 3600.0) for k in ("local2", "local2_ffmpeg")}
    record.update({
        "workers2_vs_1": median["local1"] / median["local2"],
        "ray_vs_local": median["ray2"] / median["local2"] if "ray2" in median else None,
        "clips_per_core_hour": per_hour["local2"],
        "encoders": {
            "pyav": {"workers2_vs_1": median["local1"] / median["local2"], "clips_per_core_hour": per_hour["local2"]},
            "ffmpeg": {"workers2_vs_1": median["local1_ffmpeg"] / median["local2_ffmpeg"],
                       "clips_per_core_hour": per_hour["local2_ffmpeg"]},
        },
        "capacity": {
            "skeleton_video_s_per_core_s": skeleton_rate,
            "mesh_video_s_per_core_s": mesh_rate,
            "mesh_config": {"clips": args.mesh_clips, "frames": args.mesh_frames, "workers": 1, "wall_s": mesh_s},
            "core_hours_10000_clips_10s_skeleton_256": corpus_video_s / skeleton_rate / 3600.0,
            "core_hours_10000_clips_10s_mesh_256": corpus_video_s / mesh_rate / 3600.0,
        },
        "frames_written": frames_written, "wall_s": walls, "median_wall_s": median, "startup_s": startup,
        "load_average": {"before": list(load_before), "after": list(os.getloadavg())},
        "note": "wall times exclude engine start-up (startup_s); ratios measured on a machine shared with other "
                "jobs are depressed by their load (load_average)",
    })
    write_json(args.json, record)
    report(args.json, f"workers2_vs_1 {record['workers2_vs_1']:.2f} (ffmpeg-process encoder "
           f"{record['encoders']['ffmpeg']['workers2_vs_1']:.2f}), ray_vs_local "
           f"{record['ray_vs_local'] if record['ray_vs_local'] is None else round(record['ray_vs_local'], 2)}, "
           f"{record['clips_per_core_hour']:.0f} clips/core-hour; "
           f"load {load_before[0]:.1f} -> {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
