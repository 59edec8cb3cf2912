"""Render speed, measured side by side in one run (warm-up, medians, fixed seed) and written as JSON.

    python scripts/bench_render.py --json out/bench_render.json [--frames 120] [--repeats 5] [--no-mesh]

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

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from importlib import metadata
from pathlib import Path

import numpy as np

from motion2video.evaluation.benchtools import bench_parser, median_seconds, report
from motion2video.core.motion import Motion
from motion2video.core.skeletons import H36M_17
from motion2video.core.atomic import write_json
from motion2video.testing.golden import synthetic_walk
from motion2video.formats.video import write_video
from motion2video.core.camera import fit_camera
from renderers.skeleton import SkeletonRenderer, SkeletonStyle, draw_skeleton, gaussian_heatmaps, place_joints

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


# --- skeleton maps ------------------------------------------------------------------------------------

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


# --- mesh (renderers.body) ------------------------------------------------------------------------------

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


# --- main ---------------------------------------------------------------------------------------------

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


def main(argv: list[str] | None = None) -> int:
    parser = bench_parser(__doc__)
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
                        default=Path(__file__).resolve().parents[2] / "shared/data/mocap/cmu/13_10.bvh",
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


if __name__ == "__main__":
    sys.exit(main())
