"""Benchmarks of motion2video, one sub-command each; every one writes its record as JSON.

    python scripts/bench.py render --json out/bench_render.json       # skeleton/heatmap/mp4/mesh speed, peak memory
    python scripts/bench.py batch --json out/bench_batch.json         # batch throughput: local pool vs Ray
    python scripts/bench.py frames --json out/bench_frames.json       # frame generator inference / training speed
    python scripts/bench.py pipeline --json out/bench_pipeline.json   # synthesize: stages, end to end, the demo
    python scripts/bench.py pose --json out/bench_pose.json           # pose estimation on a 720p video
    python scripts/bench.py sampling --json out/bench_sampling.json   # batched vs one-at-a-time sampling
    python scripts/bench.py long-bvh --json out/bench_long_bvh.json   # peak memory of render on a long capture
    python scripts/bench.py mesh-video --json out/bench_mesh_video.json  # mesh generator videos at 256 and 512
    python scripts/bench.py transfer-fit --json out/bench_transfer_fit.json  # transfer's decoder fits: alone vs side by side

``python scripts/bench.py SUB-COMMAND --help`` describes each record's keys. The numbers move with the machine's
load: every record carries the load average and the versions it was measured with.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from importlib import metadata
from pathlib import Path

import cv2
import numpy as np
import torch

import demo  # scripts/demo.py, beside this script: the demo's inputs and checkpoints
from motion2video import __version__
from motion2video.apps.batch import Job, LocalPool, init_ray, jobs_from_template, run_ray, warm_ray
from motion2video.apps.synthesize import (
    SynthesisConfig, compose_video, contact_sheet, output_paths, synthesize, write_outputs,
)
from motion2video.core.atomic import write_json
from motion2video.core.camera import fit_camera
from motion2video.core.motion import Motion
from motion2video.core.skeletons import H36M_17
from motion2video.evaluation.benchtools import bench_parser, median_ms, median_seconds, report
from motion2video.evaluation.benchtools import median_seconds as _median_time
from motion2video.formats.video import ENCODER_ENV, write_video
from motion2video.generator.data import structure_channels
from motion2video.generator.model import (FrameGenerator, FrameGeneratorConfig, count_parameters, generate,
                                       reconstruction_loss)
from motion2video.pose.blazepose import BlazePose, detection_roi
from motion2video.pose.estimate import estimate_video, iter_video_frames
from motion2video.pose.h36m import blazepose_to_h36m
from motion2video.stages.generation import default_generator_threads, generate_frames, generate_video_frames
from motion2video.stages.reference import load_reference
from motion2video.stages.sampling import sample_forecast, torch_threads
from motion2video.stages.structure import render_structures, split_rows, structure_previews
from motion2video.testing.golden import repeated_bvh, synthetic_walk
from renderers.skeleton import SkeletonRenderer, SkeletonStyle, draw_skeleton, gaussian_heatmaps, place_joints

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"



# ----------------------------------------------------------------------------------------------------------------
# render: Render speed, measured side by side in one run (warm-up, medians, fixed seed) and written as JSON.
# ----------------------------------------------------------------------------------------------------------------


RENDER_DOC = """Render speed, measured side by side in one run (warm-up, medians, fixed seed) and written as JSON.

    python scripts/bench.py render --json out/bench_render.json [--frames 120] [--repeats 5] [--no-mesh]

Keys of the JSON record:

- ``skeleton_vs_matplotlib``: 256x256 skeleton maps drawn with OpenCV (:func:`renderers.skeleton.draw_skeleton`)
  vs matplotlib drawing the same limbs and joints with ONE reused figure (Agg canvas, ``set_data`` on
  existing ``Line2D`` objects, ``fig.canvas.draw()`` + ``buffer_rgba``), frames/s and the ratio, plus the
  share of OpenCV's drawn pixels that matplotlib also drew (a check that both draw the same picture).
- ``heatmaps_fps``: 17 separable Gaussian heatmaps per frame at 256x256.
- ``mp4_fps``: :func:`motion2video.formats.video.write_video` of 256x256 skeleton maps (libx264), default preset
  and ``ultrafast``.
- ``mesh_fps``, ``mesh_reuse_vs_recreate``: the posed Anny body (:class:`renderers.body.BodyRenderer`) with
  one reused renderer, and with a new renderer per frame (sharing the process-wide GL context, and also
  with the GL context released after every frame). ``--no-mesh`` skips them (recorded as skipped);
  when the mesh part fails, the other results are still written, then the error is raised (exit != 0).
- ``long_clip_peak_rss_mb``: peak resident memory (the command process plus its ffmpeg child, from
  ``getrusage``) of ``motion2video render LONG_CLIP --size 768`` in a fresh process (default clip:
  ``../shared/data/mocap/cmu/13_10.bvh``, 20 s at 120 fps); ``rss_ratio_4x_length``: the same for the clip
  tiled 4 times (4x the frames, same content) over the clip itself (target <= 1.2: frames are streamed).
  ``--no-long`` skips them.
- ``machine``, ``versions``, ``config``: where and how it was measured.

Input: a synthetic human-like H36M-17 walk (:func:`motion2video.testing.golden.synthetic_walk`, fixed seed), or a
real clip with ``--bvh PATH``.
"""

SIZE = 256


DISTRIBUTIONS = ("numpy", "opencv-contrib-python-headless", "matplotlib", "imageio", "imageio-ffmpeg",
                 "pyrender-maintained", "PyOpenGL", "trimesh", "anny", "torch", "motion2video")


def machine_info() -> dict:
    affinity = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    return {"platform": platform.platform(), "processor": platform.processor() or platform.machine(),
            "python": platform.python_version(), "cpu_count": os.cpu_count(), "cpus_usable": affinity,
            "pyopengl_platform": os.environ.get("PYOPENGL_PLATFORM")}


def package_versions() -> dict:
    versions = {}
    for name in DISTRIBUTIONS:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    import cv2
    import imageio_ffmpeg

    versions["cv2"] = cv2.__version__
    versions["ffmpeg"] = imageio_ffmpeg.get_ffmpeg_version()
    return versions


class MatplotlibSkeleton:
    """The same skeleton drawing with matplotlib: one figure, one Agg canvas, Line2D objects reused."""

    def __init__(self, style: SkeletonStyle) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        from matplotlib.lines import Line2D

        from renderers.skeleton import _tint, side_colour

        dpi = 100.0
        width, height = style.size
        self.fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor=np.array(style.background) / 255)
        self.canvas = FigureCanvasAgg(self.fig)
        ax = self.fig.add_axes((0, 0, 1, 1))
        ax.set_xlim(0, width)
        ax.set_ylim(height, 0)  # pixel frame: y down, pixel centres at +0.5 as in motion2video.core.camera
        ax.set_axis_off()
        ax.set_facecolor(np.array(style.background) / 255)
        points_per_pixel = 72.0 / dpi
        self.bones = H36M_17.bones
        self.limbs = []
        for _, child in self.bones:
            line = Line2D([0, 0], [0, 0], color=np.array(side_colour(H36M_17, child)) / 255,
                          linewidth=style.thickness * points_per_pixel, solid_capstyle="round", antialiased=True)
            ax.add_line(line)
            self.limbs.append(line)
        self.joints = []
        for j in range(H36M_17.num_joints):
            marker = Line2D([0], [0], linestyle="none", marker="o",
                            markersize=2 * style.joint_radius * points_per_pixel, markeredgewidth=0,
                            markerfacecolor=np.array(_tint(side_colour(H36M_17, j), 0.45)) / 255)
            ax.add_line(marker)
            self.joints.append(marker)

    def draw(self, joints_2d: np.ndarray) -> np.ndarray:
        """(17, 2) pixels -> (H, W, 3) uint8."""
        for line, (a, b) in zip(self.limbs, self.bones):
            line.set_data([joints_2d[a, 0], joints_2d[b, 0]], [joints_2d[a, 1], joints_2d[b, 1]])
        for j, marker in enumerate(self.joints):
            marker.set_data([joints_2d[j, 0]], [joints_2d[j, 1]])
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()


def bench_skeleton(motion: Motion, *, repeats: int, warmup: int) -> dict:
    style = SkeletonStyle(size=(SIZE, SIZE))
    xy = place_joints(motion.joints, style.size).xy  # (T, 17, 2), one camera for the clip
    canvas = np.zeros((SIZE, SIZE, 3), np.uint8)
    frames = xy.shape[0]

    def opencv() -> list[np.ndarray]:
        return [draw_skeleton(canvas, xy[t], H36M_17, style) for t in range(frames)]

    mpl = MatplotlibSkeleton(style)

    def matplotlib() -> list[np.ndarray]:
        return [mpl.draw(xy[t]) for t in range(frames)]

    cv_s = median_seconds(opencv, repeats=repeats, warmup=warmup)
    mpl_s = median_seconds(matplotlib, repeats=repeats, warmup=warmup)
    drawn_cv = np.stack(opencv()).max(axis=-1) > 0
    drawn_mpl = np.stack(matplotlib()).max(axis=-1) > 0
    return {"size": [SIZE, SIZE], "frames": frames, "opencv_fps": frames / cv_s, "matplotlib_fps": frames / mpl_s,
            "opencv_over_matplotlib": mpl_s / cv_s,
            "shared_pixels": float((drawn_cv & drawn_mpl).sum() / max(drawn_cv.sum(), 1))}


def bench_heatmaps(motion: Motion, *, repeats: int, warmup: int) -> float:
    xy = place_joints(motion.joints, (SIZE, SIZE)).xy
    frames = xy.shape[0]
    seconds = median_seconds(lambda: [gaussian_heatmaps(xy[t], (SIZE, SIZE), 4.0) for t in range(frames)],
                             repeats=repeats, warmup=warmup)
    return frames / seconds


def bench_mp4(motion: Motion, *, repeats: int, warmup: int) -> dict:
    frames = SkeletonRenderer(style=SkeletonStyle(size=(SIZE, SIZE))).render(motion)
    out = {"size": [SIZE, SIZE], "frames": int(frames.shape[0])}
    with tempfile.TemporaryDirectory() as tmp:
        for preset in ("medium", "ultrafast"):
            path = Path(tmp) / f"{preset}.mp4"
            seconds = median_seconds(lambda: write_video(path, frames, motion.fps, preset=preset),
                                     repeats=repeats, warmup=warmup)
            out[f"{preset}_fps"] = frames.shape[0] / seconds
    return out


def bench_mesh(motion: Motion, *, frames: int, recreate_frames: int, repeats: int) -> dict:
    """Posed Anny body at 256x256: one reused BodyRenderer vs a new one per frame.

    Both use the same camera, fitted once to the clip's joints, so they do the same work per frame.
    """
    from renderers.body import BodyRenderer, BodyStyle  # the mesh part fails here if the module is missing
    from renderers.mesh import release_renderers

    style = BodyStyle(size=(SIZE, SIZE))
    clip = motion.slice(0, min(frames, motion.num_frames))
    camera = fit_camera(clip.joints, SIZE, SIZE)
    start = time.perf_counter()
    renderer = BodyRenderer(style)
    construct_s = time.perf_counter() - start
    try:
        start = time.perf_counter()
        renderer.render(clip.slice(0, 1), camera=camera)  # first render: GL context, shaders, Anny
        first_render_s = time.perf_counter() - start
        reuse_s = median_seconds(lambda: renderer.render(clip, camera=camera), repeats=repeats, warmup=0)
    finally:
        renderer.close()
    reuse_fps = clip.num_frames / reuse_s

    def recreate(release_gl: bool) -> None:
        for t in range(recreate_frames):
            with BodyRenderer(style) as fresh:
                fresh.render(clip.slice(t % clip.num_frames, 1), camera=camera)
            if release_gl:
                release_renderers()

    # BodyRenderer shares one process-wide GL context (renderers.mesh); the second variant also drops that
    # context after every frame, i.e. what a renderer-per-frame design without the shared context costs.
    recreate_fps = recreate_frames / median_seconds(lambda: recreate(False), repeats=max(1, repeats // 2), warmup=0)
    recreate_gl_fps = recreate_frames / median_seconds(lambda: recreate(True), repeats=max(1, repeats // 2), warmup=0)
    return {
        "mesh_fps": {"size": [SIZE, SIZE], "frames": clip.num_frames, "fps": reuse_fps,
                     "construct_s": construct_s, "first_render_s": first_render_s},
        "mesh_reuse_vs_recreate": {
            "reuse_fps": reuse_fps, "recreate_frames": recreate_frames,
            "recreate_fps": recreate_fps, "reuse_over_recreate": reuse_fps / recreate_fps,
            "recreate_with_new_gl_context_fps": recreate_gl_fps,
            "reuse_over_recreate_with_new_gl_context": reuse_fps / recreate_gl_fps,
        },
    }


def bench_long_clip(path: Path, *, size: int) -> dict:
    """Peak RSS of ``render`` on ``path`` and on the clip tiled 4x, each in a fresh process."""
    from motion2video.formats.io import load_motion, save_motion
    from motion2video.testing.golden import command_peak_rss_mb, tiled_motion

    motion = load_motion(path)
    with tempfile.TemporaryDirectory() as tmp:
        tiled = save_motion(tiled_motion(motion, 4), Path(tmp) / "tiled4.npz")
        args = ["--size", str(size), "--no-progress"]
        peak = command_peak_rss_mb(["render", path, "-o", Path(tmp) / "long.mp4", *args])
        peak4 = command_peak_rss_mb(["render", tiled, "-o", Path(tmp) / "long4.mp4", *args])
    return {"clip": str(path), "frames": motion.num_frames, "fps": motion.fps, "size": size,
            "peak_rss_mb": peak, "peak_rss_4x_mb": peak4, "ratio_4x": peak4 / peak}


def _rounded(value):
    if isinstance(value, float):
        return round(value, 4)
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    return value


def render_main(argv: list[str] | None = None) -> int:
    parser = bench_parser(RENDER_DOC)
    parser.add_argument("--frames", type=int, default=120, help="frames per skeleton / mp4 measurement")
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats (the median is kept)")
    parser.add_argument("--warmup", type=int, default=1, help="untimed warm-up calls")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic walk")
    parser.add_argument("--bvh", type=Path, default=None, help="use this real BVH clip instead of the synthetic walk")
    parser.add_argument("--mesh", action=argparse.BooleanOptionalAction, default=True,
                        help="include the mesh (Anny body) benchmark (default: yes)")
    parser.add_argument("--mesh-frames", type=int, default=24, help="frames per reused-renderer mesh measurement")
    parser.add_argument("--recreate-frames", type=int, default=6, help="frames for the renderer-per-frame variant")
    parser.add_argument("--long-clip", type=Path,
                        default=SHARED / "data" / "mocap" / "cmu" / "13_10.bvh",
                        help="clip for the peak-memory measurement (default ../shared/data/mocap/cmu/13_10.bvh)")
    parser.add_argument("--long-size", type=int, default=768, help="frame size for the peak-memory measurement")
    parser.add_argument("--long", action=argparse.BooleanOptionalAction, default=True,
                        help="include the long-clip peak-memory measurement (default: yes)")
    args = parser.parse_args(argv)

    if args.bvh is not None:
        from motion2video.formats.bvh import load_bvh

        motion = load_bvh(args.bvh, manifest=True, frames=args.frames)
        source = str(args.bvh)
    else:
        motion = synthetic_walk(args.frames, fps=30.0, seed=args.seed)
        source = f"synthetic_walk(seed={args.seed})"

    record = {
        "machine": machine_info(),
        "versions": package_versions(),
        "config": {"size": [SIZE, SIZE], "frames": motion.num_frames, "fps": motion.fps, "repeats": args.repeats,
                   "warmup": args.warmup, "input": source, "mesh": bool(args.mesh)},
    }
    # Headline keys are plain numbers (ratios: higher is better); the measurements behind them are in
    # record["details"].
    details = record["details"] = {}
    details["skeleton"] = bench_skeleton(motion, repeats=args.repeats, warmup=args.warmup)
    details["heatmaps_fps"] = bench_heatmaps(motion, repeats=args.repeats, warmup=args.warmup)
    details["mp4"] = bench_mp4(motion, repeats=max(1, args.repeats // 2), warmup=args.warmup)
    record["skeleton_vs_matplotlib"] = details["skeleton"]["opencv_over_matplotlib"]
    record["mp4_fps"] = details["mp4"]["medium_fps"]
    record["mesh_fps"] = record["mesh_reuse_vs_recreate"] = None
    record["long_clip_peak_rss_mb"] = record["rss_ratio_4x_length"] = None
    if args.long:
        details["long_clip"] = bench_long_clip(args.long_clip, size=args.long_size)
        record["long_clip_peak_rss_mb"] = details["long_clip"]["peak_rss_mb"]
        record["rss_ratio_4x_length"] = details["long_clip"]["ratio_4x"]
        print(f"render {args.long_clip.name} at {args.long_size}: peak {record['long_clip_peak_rss_mb']:.0f} MB, "
              f"4x longer: x{record['rss_ratio_4x_length']:.2f}")
    write_json(args.json, _rounded(record))  # keep these results if the mesh part fails
    if args.mesh:
        mesh = bench_mesh(motion, frames=args.mesh_frames, recreate_frames=args.recreate_frames,
                          repeats=max(1, args.repeats // 2))
        details.update(mesh)
        record["mesh_fps"] = mesh["mesh_fps"]["fps"]
        # "Creating a renderer per frame" = a new pyrender OffscreenRenderer (GL context) per frame.
        record["mesh_reuse_vs_recreate"] = mesh["mesh_reuse_vs_recreate"]["reuse_over_recreate_with_new_gl_context"]
        write_json(args.json, _rounded(record))

    skel = details["skeleton"]
    lines = [f"skeleton maps {SIZE}x{SIZE}: OpenCV {skel['opencv_fps']:.0f} fps, "
             f"matplotlib {skel['matplotlib_fps']:.0f} fps (x{skel['opencv_over_matplotlib']:.1f}); "
             f"heatmaps {details['heatmaps_fps']:.0f} fps; mp4 "
             f"{details['mp4']['medium_fps']:.0f} fps (ultrafast {details['mp4']['ultrafast_fps']:.0f})"]
    if args.mesh:
        mesh = details["mesh_reuse_vs_recreate"]
        lines.append(f"mesh {SIZE}x{SIZE}: reused renderer {mesh['reuse_fps']:.1f} fps, new BodyRenderer per frame "
                     f"{mesh['recreate_fps']:.1f} fps, new GL context per frame "
                     f"{mesh['recreate_with_new_gl_context_fps']:.1f} fps (x{record['mesh_reuse_vs_recreate']:.1f})")
    report(args.json, *lines)
    return 0


# ----------------------------------------------------------------------------------------------------------------
# batch: Batch throughput, measured side by side in one run and written as JSON.
# ----------------------------------------------------------------------------------------------------------------


BATCH_DOC = """Batch throughput, measured side by side in one run and written as JSON.

    python scripts/bench.py batch --json out/bench_batch.json [--clips 24] [--frames 300] [--repeats 5]

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

MOCAP = SHARED / "data" / "mocap"


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


def batch_main(argv: list[str] | None = None) -> int:
    parser = bench_parser(BATCH_DOC)
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


# ----------------------------------------------------------------------------------------------------------------
# frames: Frame-generator speed: inference frames/s (batch 1 and larger batches, torch.inference_mode +
# ----------------------------------------------------------------------------------------------------------------


FRAMES_DOC = """Frame-generator speed: inference frames/s (batch 1 and larger batches, torch.inference_mode +
channels_last) and training steps/s, on random inputs of the default architecture. Writes JSON.

    python scripts/bench.py frames --json out/bench_frames.json [--size 128] [--threads 2]
"""

def bench(*, size: int, domain: str, batches: tuple[int, ...], train_batch: int, repeats: int) -> dict:
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    s = structure_channels(domain)
    model = FrameGenerator(FrameGeneratorConfig(domain=domain, image_size=size, structure_channels=s))
    infer = {}
    for b in batches:
        imgs = rng.integers(0, 256, (b, size, size, 3), dtype=np.uint8)
        ps = rng.random((b, s, size, size), dtype=np.float32)
        pt = rng.random((b, s, size, size), dtype=np.float32)
        sec = _median_time(lambda: generate(model, imgs, ps, pt, batch_size=b), repeats=repeats)
        infer[str(b)] = round(b / sec, 2)
    model = FrameGenerator(model.config).train()
    opt = torch.optim.Adam(model.parameters(), lr=1e-4)
    x = torch.rand(train_batch, 3, size, size)
    p = torch.rand(train_batch, s, size, size)
    q = torch.rand(train_batch, s, size, size)

    def step():
        loss = reconstruction_loss(model(x, p, q), x, ssim_weight=1.0).total
        opt.zero_grad()
        loss.backward()
        opt.step()

    sec = _median_time(step, repeats=repeats)
    best = max(infer, key=infer.get)
    return {
        "domain": domain,
        "image_size": size,
        "parameters": count_parameters(model),
        "inference_fps_by_batch": infer,
        "inference_fps_batch1": infer.get("1"),
        "best_batch": int(best),
        "inference_fps_best": infer[best],
        "train_batch": train_batch,
        "train_steps_per_second": round(1.0 / sec, 3),
        "train_samples_per_second": round(train_batch / sec, 2),
    }


def frames_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=FRAMES_DOC, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", required=True, help="output JSON")
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--threads", type=int, default=None, help="torch threads (default: torch's)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    if args.threads:
        torch.set_num_threads(args.threads)
    results = [bench(size=args.size, domain=d, batches=(1, 4, 8, 16), train_batch=8, repeats=args.repeats)
               for d in ("body", "face")]
    payload = {
        "results": results,
        "torch_threads": torch.get_num_threads(),
        "versions": {"motion2video": __version__, "torch": torch.__version__, "numpy": np.__version__,
                     "python": sys.version.split()[0]},
        "machine": platform.platform(),
    }
    print(write_json(args.json, payload).read_text(), end="")
    return 0


# ----------------------------------------------------------------------------------------------------------------
# pipeline: Speed of the multimodal future-video pipeline (``motion2video synthesize``). Writes JSON.
# ----------------------------------------------------------------------------------------------------------------


PIPELINE_DOC = """Speed of the multimodal future-video pipeline (``motion2video synthesize``). Writes JSON.

    python scripts/bench.py pipeline --json out/bench_pipeline.json [--weights DIR] [--repeats 3] [--no-demo]

Measures, with the checkpoints in ``--weights`` (default: the shipped ``motion2video/weights``):

- ``generator``: the keypoint body frame generator (``frames-body-128``) at 128x128 (torch.inference_mode), frames/s by batch size, with and
  without channels_last, through the pipeline's path (:func:`motion2video.stages.generation.generate_frames`, which
  encodes the reference once per video) and through the plain per-frame model call
  (:func:`motion2video.generator.model.generate`), at 1 thread and at the pipeline's default thread count.
  ``generator_fps_128`` = the pipeline path at its defaults (batch 8, channels_last, default threads);
  ``generator_fps_128_batch1`` and ``generator_fps_128_best`` (best batch size) beside it.
- ``generators_side_by_side``: frames/s at 128x128 of the body generator and of each ``--compare-frame-model``
  (default: the previous body generator ``frames-body-128-v1``), measured in the same run, each through
  its pipeline path at the pipeline's defaults (a warp generator through ``encode_reference`` /
  ``decode``: person crop, generation, paste, on the demo reference and poses moved around it).
- ``generators_256``: frames/s of whole synthesized videos at 256x256 (the demo body reference, the real walk
  ``cmu_walk.npz``, K=2 futures x 48 frames after 16 observed, sampled once), through
  :func:`~motion2video.stages.generation.generate_video_frames` for the body generator and each
  ``--mesh-frame-model`` (default: the demo's body generator, ``frames-body-mesh-256``, from --weights) side by
  side: the mesh generator's time includes fitting, posing and rendering the body mesh of every frame.
- ``end_to_end``: K=5 futures x 48 frames after 16 observed, body and face: the wall time of
  :func:`motion2video.apps.synthesize.synthesize` (checkpoint loading included) and each stage timed alone
  (sampling, structure rendering, generation, encoding of the three outputs); ``overhead_ratio`` =
  wall / sum of the stages (target <= 1.3), and each stage's share of that sum. Medians over --repeats
  runs after one warm-up run (Anny, the GL context and the imports are loaded once per process).
- ``demo``: ``scripts/demo.py`` run in a child process: wall time and peak resident memory
  (``resource.getrusage(RUSAGE_CHILDREN).ru_maxrss``; target < 4 GB).

The machine (CPU, load average, versions) is recorded with the numbers: on a shared machine they move.
"""


SAMPLES, OBSERVED, HORIZON = 5, 16, 48


KEYPOINT_BODY = "frames-body-128"  # ``generator`` and ``generators_side_by_side`` measure it (keypoints in, frames out)


BATCHES = (1, 4, 8, 16)


def machine() -> dict:
    import cv2

    return {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "load_average_1min": round(os.getloadavg()[0], 2),
        "python": platform.python_version(),
        "torch": torch.__version__,
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "motion2video": __version__,
        "torch_default_threads": torch.get_num_threads(),
        "pipeline_generator_threads": default_generator_threads(),
    }


def bench_generator(frame_model, *, repeats: int, frames: int = 16) -> dict:
    """Frames/s of the generator at its size on random structures (speed does not depend on the values)."""
    from motion2video.generator.model import generate

    net = frame_model.model
    cfg = net.config
    size, channels = cfg.image_size, cfg.structure_channels
    rng = np.random.default_rng(0)
    ref = rng.integers(0, 256, (size, size, 3), dtype=np.uint8)
    ref_s = rng.random((channels, size, size), dtype=np.float32)
    tgt = rng.random((frames, channels, size, size), dtype=np.float32)
    refs, ref_ss = np.repeat(ref[None], frames, 0), np.repeat(ref_s[None], frames, 0)
    table = []
    for threads in sorted({1, default_generator_threads()}):
        with torch_threads(threads):
            for batch in BATCHES:
                for channels_last in (False, True):
                    sec = median_seconds(lambda: generate_frames(net, ref, ref_s, tgt, batch_size=batch,
                                                                   channels_last=channels_last), repeats=repeats)
                    table.append({"path": "pipeline", "threads": threads, "batch": batch,
                                  "channels_last": channels_last, "fps": round(frames / sec, 2)})
                sec = median_seconds(lambda: generate(net, refs, ref_ss, tgt, batch_size=batch), repeats=repeats)
                table.append({"path": "model.generate", "threads": threads, "batch": batch, "channels_last": True,
                              "fps": round(frames / sec, 2)})
    default_threads = default_generator_threads()
    mine = [r for r in table if r["path"] == "pipeline" and r["threads"] == default_threads]
    default = next(r for r in mine if r["batch"] == SynthesisConfig.batch_size and r["channels_last"])
    best = max(mine, key=lambda r: r["fps"])
    batch1 = max((r for r in mine if r["batch"] == 1), key=lambda r: r["fps"])
    plain = [r for r in table if r["path"] == "model.generate" and r["threads"] == default_threads]
    return {
        "image_size": size,
        "frames_per_measurement": frames,
        "generator_fps_128": default["fps"] if size == 128 else None,
        "generator_fps_128_batch1": batch1["fps"],
        "generator_fps_128_best": best["fps"],
        "best": best,
        "model_generate_fps_batch1": next(r["fps"] for r in plain if r["batch"] == 1),
        "model_generate_fps_best": max(r["fps"] for r in plain),
        "table": table,
    }


def bench_warp_generator(frame_model, *, repeats: int, frames: int = 16) -> dict:
    """Frames/s of a warp generator at its size through ``decode`` (the pipeline's path): the demo body
    reference resized to the model size, target poses = its pose moved and bent a little (a real pose, so
    the crop is the size the pipeline would use)."""
    import cv2

    from motion2video.stages.reference import load_reference_pose

    net = frame_model.model
    size = net.config.image_size
    image = cv2.cvtColor(cv2.imread(str(demo.DEMO_INPUTS / "reference_body_128.png")), cv2.COLOR_BGR2RGB)
    image = cv2.resize(image, (size, size), interpolation=cv2.INTER_AREA)
    pose = load_reference_pose(demo.DEMO_INPUTS / "reference_body_128.pose.npz")
    points = np.asarray(pose.points, np.float32) * (size / pose.width)
    rng = np.random.default_rng(0)
    targets = points[None] + rng.normal(0.0, 0.02 * size, (frames, 17, 2)).astype(np.float32)
    table = []
    for threads in sorted({1, default_generator_threads()}):
        with torch_threads(threads):
            state = net.encode_reference(image, points)
            for batch in (1, 4, 8):
                sec = median_seconds(lambda: net.decode(state, targets, batch_size=batch), repeats=repeats)
                table.append({"path": "decode", "threads": threads, "batch": batch, "fps": round(frames / sec, 2)})
    mine = [r for r in table if r["threads"] == default_generator_threads()]
    default = next(r for r in mine if r["batch"] == SynthesisConfig.batch_size)
    return {
        "image_size": size,
        "kind": "warp",
        "frames_per_measurement": frames,
        "generator_fps_128": default["fps"] if size == 128 else None,
        "generator_fps_128_batch1": next(r["fps"] for r in mine if r["batch"] == 1),
        "generator_fps_128_best": max(r["fps"] for r in mine),
        "table": table,
    }


def bench_any_generator(frame_model, *, repeats: int) -> dict:
    """:func:`bench_warp_generator` or :func:`bench_generator`, by the model's kind."""
    if getattr(frame_model, "kind", "analogy") == "warp":
        return bench_warp_generator(frame_model, repeats=repeats)
    return bench_generator(frame_model, repeats=repeats)


def bench_end_to_end(spec: dict, files: dict, *, repeats: int, work: Path) -> dict:
    """Wall time of synthesize vs the sum of its stages timed alone, for one demo clip."""
    from motion2video.models.checkpoint import load_model
    from motion2video.apps.sample import load_clip_for
    from motion2video.generator.checkpoint import load_frame_model

    clip_path = demo.DEMO_INPUTS / spec["clip"]
    ref_path = demo.DEMO_INPUTS / spec["reference"]
    motion_ckpt, frame_ckpt = files[spec["motion_model"]], files[spec["frame_model"]]
    config = SynthesisConfig(samples=SAMPLES, observed=OBSERVED, horizon=HORIZON, start=spec["start"])
    out = work / f"bench_{spec['clip']}.mp4"

    def whole() -> None:
        synthesize(motion_model=motion_ckpt, frame_model=frame_ckpt, input_path=clip_path, reference=ref_path,
                     output=out, config=config)

    # The stages alone, on inputs prepared outside the timers.
    bundle = load_model(motion_ckpt)
    frames_model = load_frame_model(frame_ckpt)
    size, domain = frames_model.config.image_size, frames_model.config.domain
    clip = load_clip_for(bundle, clip_path)
    ref = load_reference(ref_path, size=size, domain=domain)
    threads = default_generator_threads()
    state: dict = {}

    def sampling() -> None:
        state["fc"] = sample_forecast(bundle, clip, samples=SAMPLES, observed=OBSERVED, horizon=HORIZON,
                                       start=spec["start"], seed=0)

    def structures() -> None:
        state["st"] = render_structures(state["fc"], domain=domain, size=size, reference=ref)

    def generation() -> None:
        state["gen"] = generate_video_frames(frames_model, ref, state["st"], batch_size=config.batch_size,
                                               threads=threads)

    def encoding() -> None:
        write_outputs(output_paths(work / "bench_stage.mp4"), state["video"], state["structure_video"],
                        state["sheet"], fps=state["fc"].fps)

    whole()  # warm-up: imports, Anny, the GL context, ffmpeg
    walls, stage_runs = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        whole()
        walls.append(time.perf_counter() - t0)
        times = {}
        for name, fn in (("sampling", sampling), ("structures", structures), ("generation", generation)):
            t0 = time.perf_counter()
            fn()
            times[name] = time.perf_counter() - t0
        g, st = state["gen"], state["st"]
        ref_prev, obs_prev, fut_prev = split_rows(structure_previews(st), st)
        state.update(video=compose_video(g.observed, g.futures), structure_video=compose_video(obs_prev, fut_prev),
                     sheet=contact_sheet(g.observed, g.futures, header=((ref.image, "reference"),
                                                                          (ref_prev, "ref. structure"))))
        t0 = time.perf_counter()
        encoding()
        times["encoding"] = time.perf_counter() - t0
        stage_runs.append(times)
    stages = {k: statistics.median(run[k] for run in stage_runs) for k in stage_runs[0]}
    total_stages = sum(stages.values())
    wall = statistics.median(walls)
    return {
        "clip": spec["clip"],
        "domain": domain,
        "samples": SAMPLES,
        "observed": OBSERVED,
        "horizon": HORIZON,
        "frames_generated": OBSERVED + SAMPLES * HORIZON,
        "wall_s": round(wall, 3),
        "stages_s": {k: round(v, 3) for k, v in stages.items()},
        "stages_sum_s": round(total_stages, 3),
        "stage_share": {k: round(v / total_stages, 4) for k, v in stages.items()},
        "overhead_ratio": round(wall / total_stages, 4),
        "walls_s": [round(w, 3) for w in walls],
    }


def bench_video_256(frame_models: dict, motion_model: Path, *, repeats: int, size: int = 256,
                    reference: Path | None = None) -> dict:
    """Frames/s of :func:`generate_video_frames` at ``size`` for each frame model (name -> loaded model) on the
    same placed forecast (see ``generators_256`` in the module docstring); ``reference``: the body reference
    (default: the demo's)."""
    from motion2video.models.checkpoint import load_model

    bundle = load_model(motion_model)
    ref = load_reference(reference or demo.DEMO_INPUTS / "reference_body.png", size=size, domain="body")
    from motion2video.stages.clips import load_clip

    clip = load_clip(bundle, demo.DEMO_INPUTS / "cmu_walk.npz").data
    fc = sample_forecast(bundle, clip, samples=2, observed=OBSERVED, horizon=HORIZON, start=0, seed=0)
    st = render_structures(fc, domain="body", size=size, reference=ref)
    out = {"size": size, "frames": st.num_targets}
    for name, model in frame_models.items():
        sec = median_seconds(lambda: generate_video_frames(model, ref, st, batch_size=SynthesisConfig.batch_size),
                             repeats=repeats)
        out[name] = round(st.num_targets / sec, 2)
    return out


def bench_demo(weights: Path, work: Path) -> dict:
    """Run scripts/demo.py in a child process; its wall time and peak resident memory."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(REPO / "scripts" / "demo.py"), "--out", str(work / "demo"),
                           "--weights", str(weights)], capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    peak_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    if proc.returncode != 0:
        raise RuntimeError(f"the demo failed (exit {proc.returncode}): {proc.stderr.strip()[-500:]}")
    return {
        "wall_s": round(wall, 2),
        "peak_rss_mb": round(peak_kb / 1024, 1),
        "peak_rss_note": "ru_maxrss of RUSAGE_CHILDREN: the largest waited-for descendant (the demo process; "
        "the earlier children of the benchmark are ffmpeg encoders, far smaller)",
        "target_peak_rss_mb": 4096,
    }


def pipeline_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=PIPELINE_DOC.split("\n\n")[0])
    parser.add_argument("--json", required=True, type=Path, help="output JSON")
    parser.add_argument("--weights", type=Path, default=demo.WEIGHTS,
                        help="folder with mtvae-add, mtvae-add-face, frames-body-128, frames-face-128 "
                        "(default: the shipped motion2video/weights)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per measurement (default 3)")
    parser.add_argument("--no-demo", action="store_true", help="skip the demo run (peak memory)")
    parser.add_argument("--compare-frame-model", action="append", default=None, metavar="MODEL",
                        help="also measure this body generator's frames/s at 128 in the same run (repeatable; "
                        "default: frames-body-128-v1 from --weights when it is there)")
    parser.add_argument("--mesh-frame-model", action="append", default=None, metavar="MODEL",
                        help="a mesh body generator measured at 256x256 beside the body generator (repeatable; "
                        "default: the demo's body generator frames-body-mesh-256 from --weights)")
    args = parser.parse_args(argv)
    files = demo.weight_files(args.weights)
    missing = [str(p) for p in [*files.values(), args.weights / f"{KEYPOINT_BODY}.safetensors"] if not p.is_file()]
    if missing:
        print(f"bench_pipeline: error: missing weight file(s): {', '.join(missing)}", file=sys.stderr)
        return 2
    from motion2video.generator.checkpoint import load_frame_model

    result: dict = {"machine": machine(), "weights": str(args.weights)}
    with tempfile.TemporaryDirectory(prefix="bench_pipeline_") as tmp:
        work = Path(tmp)
        print("frame generator ...", flush=True)
        keypoint = args.weights / f"{KEYPOINT_BODY}.safetensors"  # the generator that takes keypoints alone
        result["generator"] = bench_any_generator(load_frame_model(keypoint), repeats=args.repeats)
        result["generator_fps_128"] = result["generator"]["generator_fps_128"]
        side = {KEYPOINT_BODY: result["generator_fps_128"]}
        compare = args.compare_frame_model
        if compare is None:
            previous = args.weights / "frames-body-128-v1.safetensors"
            compare = [str(previous)] if previous.is_file() else []
        for name in compare:
            print(f"frame generator {name} ...", flush=True)
            other = load_frame_model(name)
            side[other.path.name.removesuffix(".safetensors")] = bench_any_generator(
                other, repeats=args.repeats)["generator_fps_128"]
        result["generators_side_by_side"] = side
        meshes = args.mesh_frame_model
        if meshes is None:
            meshes = [str(files[demo.BODY["frame_model"]])] if demo.BODY["frame_model"] != KEYPOINT_BODY else []
        models = {KEYPOINT_BODY: load_frame_model(keypoint)}
        for name in meshes:
            loaded = load_frame_model(name)
            models[loaded.path.name.removesuffix(".safetensors")] = loaded
        print("videos at 256x256 ...", flush=True)
        result["generators_256"] = bench_video_256(models, files[demo.BODY["motion_model"]], repeats=args.repeats)
        result["end_to_end"] = {}
        for name, spec in (("body", demo.BODY), ("face", demo.FACE)):
            print(f"end to end ({name}) ...", flush=True)
            result["end_to_end"][name] = bench_end_to_end(spec, files, repeats=args.repeats, work=work)
        result["overhead_ratio"] = max(r["overhead_ratio"] for r in result["end_to_end"].values())
        result["overhead_ratio_target"] = 1.3
        if not args.no_demo:
            print("demo ...", flush=True)
            result["demo"] = bench_demo(args.weights, work)
    result["machine"]["load_average_1min_end"] = round(os.getloadavg()[0], 2)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    gen, e2e = result["generator"], result["end_to_end"]
    parts = [f"generator {gen['generator_fps_128']} frames/s at 128 (batch 1: {gen['generator_fps_128_batch1']}, "
             f"best: {gen['generator_fps_128_best']})"]
    parts += [f"{k} overhead {v['overhead_ratio']} (wall {v['wall_s']} s)" for k, v in e2e.items()]
    if "demo" in result:
        parts.append(f"demo {result['demo']['wall_s']} s, peak {result['demo']['peak_rss_mb']} MB")
    parts.append("side by side: " + ", ".join(f"{k} {v}" for k, v in result["generators_side_by_side"].items()))
    parts.append("at 256: " + ", ".join(f"{k} {v}" for k, v in result["generators_256"].items()
                                       if k not in ("size", "frames")))
    print(f"wrote {args.json}: " + "; ".join(parts))
    return 0


# ----------------------------------------------------------------------------------------------------------------
# pose: Pose-estimation speed: frames/s of `motion2video pose` on a 720p video, and the tracker's agreement with
# ----------------------------------------------------------------------------------------------------------------


POSE_DOC = """Pose-estimation speed: frames/s of `motion2video pose` on a 720p video, and the tracker's agreement with
per-frame detection. Writes JSON.

    python scripts/bench.py pose --json out/bench_pose.json [--video ../shared/data/video/dancer.avi]
        [--frames 150] [--repeats 3] [--threads 2]

The 720p video is made from the first ``--frames`` frames of ``--video`` (padded to 16:9 by repeating the
border, resized to 1280x720, H.264) in a temporary folder. Timed: the whole estimate (decoding, detection,
tracking, landmarks, the mapping to H36M-17) after one warm-up run, median of ``--repeats``; and the two
models per call. Agreement: on the same frames, the tracked joints (ROI from the previous frame, before
smoothing) against the joints with the detector run on every frame, as the median over frames and joints of the distance in % of
the person's height (pelvis-relative height of the 2D head above the lowest ankle).
"""


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


def pose_main(argv: list[str] | None = None) -> int:
    parser = bench_parser(POSE_DOC)
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


# ----------------------------------------------------------------------------------------------------------------
# sampling: Sampling speed: 50 futures of 48 frames from mtvae-add, batched (one call) versus one sample at a time.
# ----------------------------------------------------------------------------------------------------------------


SAMPLING_DOC = """Sampling speed: 50 futures of 48 frames from mtvae-add, batched (one call) versus one sample at a time.

    python scripts/bench.py sampling --json out/bench_sampling.json

Uses the shipped ``mtvae-add`` checkpoint when it exists, else an untrained ``mtvae-add`` with its default
config (the speed does not depend on the weights; the JSON says which). The observation is a real 16-frame
window from the mocap folder. Warm-up runs first; the reported times are medians over repeats; one torch
thread unless --threads says otherwise.

JSON keys: ``batched_ms`` (milliseconds for the 50 futures in one call), ``loop_ms`` (50 calls of one
sample), ``batched_vs_loop`` (loop_ms / batched_ms), plus the settings and library versions.
"""

def run_benchmark(*, samples: int = 50, horizon: int = 48, repeats: int = 7, threads: int = 1,
                  data: str | None = None, seed: int = 0) -> dict:
    """Time batched and one-at-a-time sampling; returns the JSON record."""
    from motion2video.evaluation.benchtools import median_ms
    from motion2video.models.checkpoint import WEIGHTS_DIR, load_model
    from motion2video.data.dataset import DEFAULT_MOCAP, DatasetConfig, build_dataset
    from motion2video.models.base import build_model

    torch.set_num_threads(threads)
    shipped = WEIGHTS_DIR / "mtvae-add.safetensors"
    if shipped.is_file():
        bundle = load_model(shipped)
        model, stats, cfg, source = bundle.model, bundle.stats, bundle.data_config, str(shipped)
    else:
        cfg = DatasetConfig()
        torch.manual_seed(seed)
        model, stats, source = build_model("mtvae-add", {"feature_dim": 51}).eval(), None, "untrained default config"
    dataset = build_dataset(data or DEFAULT_MOCAP, cfg, stats=stats)
    window = dataset.windows("test", stride=cfg.length)
    obs = torch.from_numpy(window.obs[:1])  # (1, 16, F)
    gen = torch.Generator().manual_seed(seed)

    def batched():
        with torch.no_grad():
            out = model.sample(obs, num_samples=samples, horizon=horizon, generator=gen)
        assert out.shape == (1, samples, horizon, obs.shape[-1])

    def loop():
        with torch.no_grad():
            for _ in range(samples):
                model.sample(obs, num_samples=1, horizon=horizon, generator=gen)

    batched(), loop()  # warm-up
    batched_ms = median_ms(batched, repeats=repeats)
    loop_ms = median_ms(loop, repeats=max(3, repeats // 2))
    return {
        "batched_ms": round(batched_ms, 3),
        "loop_ms": round(loop_ms, 3),
        "batched_vs_loop": round(loop_ms / batched_ms, 2),
        "samples": samples,
        "horizon": horizon,
        "model": "mtvae-add",
        "weights": source,
        "parameters": int(sum(p.numel() for p in model.parameters())),
        "repeats": repeats,
        "threads": threads,
        "versions": {"python": sys.version.split()[0], "torch": torch.__version__, "numpy": np.__version__},
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
    }


def sampling_main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=SAMPLING_DOC.splitlines()[0])
    p.add_argument("--json", required=True, help="write the record here")
    p.add_argument("--samples", type=int, default=50)
    p.add_argument("--horizon", type=int, default=48)
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--data", default=None, help="mocap folder for the observation (default ../shared/data/mocap)")
    args = p.parse_args(argv)
    record = run_benchmark(samples=args.samples, horizon=args.horizon, repeats=args.repeats, threads=args.threads,
                           data=args.data)
    out = Path(args.json)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(record, indent=2) + "\n")
    print(json.dumps({k: record[k] for k in ("batched_ms", "loop_ms", "batched_vs_loop", "weights")}))
    return 0


# ----------------------------------------------------------------------------------------------------------------
# long_bvh: Peak memory of ``motion2video render`` on a long capture, written as JSON.
# ----------------------------------------------------------------------------------------------------------------


LONG_BVH_DOC = """Peak memory of ``motion2video render`` on a long capture, written as JSON.

    python scripts/bench.py long-bvh --json out/bench_long_bvh.json [--clip ../shared/data/mocap/cmu/13_10.bvh]
        [--repeat 16] [--size 256]

Builds the long capture in a temporary folder (never in the repository): the clip's MOTION lines repeated
``--repeat`` times with the ``Frames:`` count fixed (CMU 13_10 x 16: 38,352 frames at 120 fps, 5.3 minutes,
49 MB). Then runs ``/usr/bin/time -v python -m motion2video.cli render LONG.bvh -o OUT.mp4 --size N`` in a
fresh process and records its "Maximum resident set size" (the command process; ffmpeg children are not
included in GNU time's figure) and the wall time, plus the same for the clip itself.

Keys: ``long`` and ``original`` (``frames``, ``file_mb``, ``peak_rss_mb``, ``wall_s``), ``ratio_peak_to_file``
(long), ``target_mb`` (600) and ``config``.
"""


def measure(path: Path, out: Path, size: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(REPO), OMP_NUM_THREADS="1")
    t0 = time.perf_counter()
    run = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "motion2video.cli", "render", str(path),
                          "-o", str(out), "--size", str(size), "--no-progress"],
                         capture_output=True, text=True, env=env, cwd=REPO)
    wall = time.perf_counter() - t0
    if run.returncode != 0:
        raise SystemExit(f"render failed ({run.returncode}): {run.stderr.strip()[-500:]}")
    rss_kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", run.stderr).group(1))
    return {"file_mb": round(path.stat().st_size / 1e6, 1), "peak_rss_mb": round(rss_kb / 1024, 1),
            "wall_s": round(wall, 1), "stdout": run.stdout.strip()}


def long_bvh_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=LONG_BVH_DOC.splitlines()[0])
    parser.add_argument("--json", required=True, help="where to write the results")
    parser.add_argument("--clip", default=str(SHARED / "data" / "mocap" / "cmu" / "13_10.bvh"))
    parser.add_argument("--repeat", type=int, default=16)
    parser.add_argument("--size", type=int, default=256)
    args = parser.parse_args(argv)
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


# ----------------------------------------------------------------------------------------------------------------
# mesh-video: frames/s of the mesh generator's videos at each output size
# ----------------------------------------------------------------------------------------------------------------


MESH_VIDEO_DOC = """Frames/s of the mesh generator's whole videos at each output size (256 and 512 by default).

    python scripts/bench.py mesh-video --json out/bench_mesh_video.json [--sizes 256 512] [--repeats 3]
        [--reference ../shared/data/photos/woman_blue_tracksuit.jpg]

The same measurement as ``pipeline``'s ``generators_256`` (the real walk ``cmu_walk.npz``, K=2 futures x 48 frames
after 16 observed, sampled once; :func:`~motion2video.stages.generation.generate_video_frames`: fitting, posing and
rendering the body mesh of every frame, generation, compositing, the photo's face laid over the heads), at each
``--sizes`` output size, for ``--frame-model`` (default ``frames-body-mesh-256``). Targets: 512 px >= 3 frames/s and
256 px >= 8 on 2 cores. Medians over --repeats after one warm-up run; the load average is recorded at the start and
the end (on a shared machine the numbers move with it).
"""


def mesh_video_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=MESH_VIDEO_DOC.split("\n\n")[0])
    parser.add_argument("--json", required=True, type=Path, help="output JSON")
    parser.add_argument("--frame-model", default="frames-body-mesh-256")
    parser.add_argument("--sizes", type=int, nargs="+", default=[256, 512])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--reference", type=Path, default=None, help="body reference (default: the demo's)")
    parser.add_argument("--threads", type=int, default=None, help="torch threads (default: the pipeline's)")
    args = parser.parse_args(argv)
    from motion2video.generator.checkpoint import load_frame_model

    files = demo.weight_files(demo.WEIGHTS)
    model = load_frame_model(args.frame_model)
    name = model.path.name.removesuffix(".safetensors")
    threads = args.threads or default_generator_threads()
    result: dict = {"machine": machine(), "frame_model": name, "threads": threads,
                    "reference": str(args.reference or demo.DEMO_INPUTS / "reference_body.png"),
                    "targets_fps": {"256": 8.0, "512": 3.0}}
    with torch_threads(threads):
        for size in args.sizes:
            print(f"videos at {size}x{size} ...", flush=True)
            out = bench_video_256({name: model}, files[demo.BODY["motion_model"]], repeats=args.repeats, size=size,
                                  reference=args.reference)
            result[f"fps_{size}"] = out[name]
            result["frames"] = out["frames"]
    result["machine"]["load_average_1min_end"] = round(os.getloadavg()[0], 2)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.json}: " + ", ".join(f"{k} {v}" for k, v in result.items() if k.startswith("fps_")))
    return 0


# ----------------------------------------------------------------------------------------------------------------
# transfer-fit: behaviour transfer's decoder fits, one source at a time against side by side
# ----------------------------------------------------------------------------------------------------------------


TRANSFER_FIT_DOC = """Behaviour transfer's re-enactments (``stages.latents.reenact_sources``), each decoder fitted alone
against all of them side by side (the decoders' weights stacked, one vmapped step for all), on one torch thread.

    python scripts/bench.py transfer-fit --json out/bench_transfer_fit.json [--sources 8]

The sources are the first --sources pairs of the transfer benchmark's held-out cases (real CMU jumps, kicks and
walks retargeted onto other subjects' postures, fitted for ``ADAPT_STEPS`` steps as ``motion2video transfer``
fits them), for the shipped ``behavior`` model. Both ways run in one process, alone first; each is timed once (a
fit takes seconds).

JSON keys: ``alone_s_per_source``, ``side_by_side_s_per_source``, ``speedup`` (the first over the second),
``joint_difference_m`` (max and mean distance between a joint re-enacted alone and side by side: the stacked
arithmetic rounds differently, and 300 Adam steps carry that a little way), plus the settings.
"""


def transfer_fit_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=TRANSFER_FIT_DOC.split("\n\n")[0])
    parser.add_argument("--json", required=True, type=Path, help="output JSON")
    parser.add_argument("--sources", type=int, default=8)
    args = parser.parse_args(argv)
    from motion2video import load_model
    from motion2video.evaluation import transfer_benchmark as B
    from motion2video.stages.latents import ADAPT_STEPS, reenact_source, reenact_sources

    torch.set_num_threads(1)
    bundle = load_model("behavior")
    pairs = []
    for case in (c for c in B.CASES if c.split == "held-out"):
        clip = B.load_clip_25(str(MOCAP), case.clip)
        pairs += [(clip[case.start:case.start + 1 + case.horizon], B.load_clip_25(str(MOCAP), t[0])[t[1]])
                  for t in B.targets_for(case)]
    length = len(pairs[0][0])
    pairs = [p for p in pairs if len(p[0]) == length][:args.sources]  # one length: one side-by-side fit
    start = time.perf_counter()
    alone = np.stack([reenact_source(bundle, source, posture)[1][0] for source, posture in pairs])
    alone_s = (time.perf_counter() - start) / len(pairs)
    start = time.perf_counter()
    together = reenact_sources(bundle, np.stack([p[0] for p in pairs]), np.stack([p[1] for p in pairs]))[1]
    together_s = (time.perf_counter() - start) / len(pairs)
    apart = np.linalg.norm(alone - together, axis=-1)
    result = {"machine": machine(), "sources": len(pairs), "steps": ADAPT_STEPS, "threads": 1,
              "alone_s_per_source": round(alone_s, 2), "side_by_side_s_per_source": round(together_s, 2),
              "speedup": round(alone_s / together_s, 2),
              "joint_difference_m": {"max": round(float(apart.max()), 4), "mean": round(float(apart.mean()), 5)}}
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    return 0


# ----------------------------------------------------------------------------------------------------------------

COMMANDS = {
    "render": (render_main, RENDER_DOC),
    "batch": (batch_main, BATCH_DOC),
    "frames": (frames_main, FRAMES_DOC),
    "pipeline": (pipeline_main, PIPELINE_DOC),
    "pose": (pose_main, POSE_DOC),
    "sampling": (sampling_main, SAMPLING_DOC),
    "long-bvh": (long_bvh_main, LONG_BVH_DOC),
    "mesh-video": (mesh_video_main, MESH_VIDEO_DOC),
    "transfer-fit": (transfer_fit_main, TRANSFER_FIT_DOC),
}


def main(argv: list[str] | None = None) -> int:
    """``bench.py SUB-COMMAND [options]``: run one benchmark (its options are its own; ``SUB-COMMAND --help``)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] not in COMMANDS:
        lines = [f"  {name:<10} {doc.splitlines()[0]}" for name, (_, doc) in COMMANDS.items()]
        print("usage: bench.py {" + ",".join(COMMANDS) + "} [options]\n\nbenchmarks:\n" + "\n".join(lines),
              file=sys.stdout if argv[:1] in (["-h"], ["--help"]) else sys.stderr)
        return 0 if argv[:1] in (["-h"], ["--help"]) else 2
    run, _ = COMMANDS[argv[0]]
    return run(argv[1:]) or 0


if __name__ == "__main__":
    sys.exit(main())
