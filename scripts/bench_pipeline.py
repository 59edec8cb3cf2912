"""Speed of the multimodal future-video pipeline (``motion2video synthesize``). Writes JSON.

    python scripts/bench_pipeline.py --json out/bench_pipeline.json [--weights DIR] [--repeats 3] [--no-demo]

Measures, with the checkpoints in ``--weights`` (default: the shipped ``motion2video/weights``):

- ``generator``: the keypoint body frame generator (``frames-body-128``) at 128x128 (torch.inference_mode), frames/s by batch size, with and
  without channels_last, through the pipeline's path (:func:`motion2video.stages.frames.generate_frames`, which
  encodes the reference once per video) and through the plain per-frame model call
  (:func:`motion2video.frames.model.generate`), at 1 thread and at the pipeline's default thread count.
  ``generator_fps_128`` = the pipeline path at its defaults (batch 8, channels_last, default threads);
  ``generator_fps_128_batch1`` and ``generator_fps_128_best`` (best batch size) beside it.
- ``generators_side_by_side``: frames/s at 128x128 of the body generator and of each ``--compare-frame-model``
  (default: the previous body generator ``frames-body-128-v1``), measured in the same run, each through
  its pipeline path at the pipeline's defaults (a warp generator through ``encode_reference`` /
  ``decode``: person crop, generation, paste, on the demo reference and poses moved around it).
- ``generators_256``: frames/s of whole synthesized videos at 256x256 (the demo body reference, the real walk
  ``cmu_walk.npz``, K=2 futures x 48 frames after 16 observed, sampled once), through
  :func:`~motion2video.stages.frames.generate_video_frames` for the body generator and each
  ``--mesh-frame-model`` (default: the demo's body generator, ``frames-body-mesh-256``, from --weights) side by
  side: the mesh generator's time includes fitting, posing and rendering the body mesh of every frame.
  ``generators_512``: the same at 512x512 (``synthesize --size 512``): the generators run at their own size on
  the person's crop, which is laid over the reference's background at 512 (targets: 512 px >= 3 frames/s, 256 px
  >= 8).
- ``end_to_end``: K=5 futures x 48 frames after 16 observed, body and face: the wall time of
  :func:`motion2video.apps.synthesize.synthesize` (checkpoint loading included) and each stage timed alone
  (sampling, structure rendering, generation, encoding of the three outputs); ``overhead_ratio`` =
  wall / sum of the stages (target <= 1.3), and each stage's share of that sum. Medians over --repeats
  runs after one warm-up run (Anny, the GL context and the imports are loaded once per process).
- ``demo``: ``scripts/demo.py`` run in a child process: wall time and peak resident memory
  (``resource.getrusage(RUSAGE_CHILDREN).ru_maxrss``; target < 4 GB).

The machine (CPU, load average, versions) is recorded with the numbers: on a shared machine they move.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "scripts"))

import demo  # noqa: E402  (scripts/demo.py: the demo's inputs and checkpoint names)

from motion2video import __version__  # noqa: E402
from motion2video.evaluation.benchtools import median_seconds  # noqa: E402
from motion2video.apps.synthesize import (  # noqa: E402
    SynthesisConfig, compose_video, contact_sheet, output_paths, synthesize, write_outputs,
)
from motion2video.stages.frames import default_generator_threads, generate_frames, generate_video_frames  # noqa: E402
from motion2video.stages.reference import load_reference  # noqa: E402
from motion2video.stages.structure import render_structures, split_rows, structure_previews  # noqa: E402
from motion2video.stages.sampling import sample_forecast, torch_threads  # noqa: E402

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
    from motion2video.frames.model import generate

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
    from motion2video.frames.checkpoint import load_frame_model

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


def bench_video_256(frame_models: dict, motion_model: Path, *, repeats: int, size: int = 256) -> dict:
    """Frames/s of :func:`generate_video_frames` at ``size`` for each frame model (name -> loaded model) on the
    same placed forecast (see ``generators_256`` in the module docstring)."""
    from motion2video.models.checkpoint import load_model

    bundle = load_model(motion_model)
    ref = load_reference(demo.DEMO_INPUTS / "reference_body.png", size=size, domain="body")
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
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
    from motion2video.frames.checkpoint import load_frame_model

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
        print("videos at 512x512 ...", flush=True)
        result["generators_512"] = bench_video_256(models, files[demo.BODY["motion_model"]], repeats=args.repeats,
                                                   size=512)
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


if __name__ == "__main__":
    sys.exit(main())
