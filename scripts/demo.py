"""`make demo`: multimodal future videos of a body clip and a face clip with the shipped checkpoints.

    .venv/bin/python scripts/demo.py --out out

Writes, from the committed ``demo_inputs/`` (and one photo of ``../shared`` when it is there):

- ``out/futures_body.mp4`` (+ ``-structure.mp4``, ``-sheet.png``): K futures of ``cmu_walk.npz`` (a real CMU walk)
  sampled by ``mixture-periodic`` (the best sampler: futures 1 and 4 from ``mtvae-add-dlow``, 2 and 5 from
  ``mixer-cvae-dlow``, 3 from ``mirror-periodic``, the walk's own steps repeated), turned into 256 px frames of ``reference_body.png`` by
  ``frames-body-mesh-256`` (the
  reference person moved through a fitted body mesh);
- ``out/mesh_body.mp4`` (+ ``-sheet.png``): the same futures as the posed Anny body mesh, same layout;
- ``out/futures_face.mp4`` (+ ``-structure.mp4``, ``-sheet.png``): K futures of ``smile.npz`` sampled by
  ``mtvae-add-face``, frames of ``reference_face.png`` by ``frames-face-mesh-128`` (moved through the head mesh);
- ``out/transfer_body.mp4``: behaviour transfer: the jump of ``cmu_jump.npz`` (a real CMU jump)
  re-enacted by ``behavior`` from the standing posture of ``wave.npz``, drawn as the reference person
  ``reference_body.png`` (re-framed to keep the jump in view) by ``frames-body-mesh-256``, side by side
  with the source (skeleton); ``out/transfer_body.npz`` keeps the source and the re-enactment, and
  ``out/transfer_body-sheet.png`` shows its start, crouch, top and landing frames;
- ``out/photo_body.mp4`` (+ ``-structure.mp4``, ``-sheet.png``): a real photo as the reference:
  futures of ``cmu_walk.npz`` drawn as the person of ``../shared/data/photos/PHOTO`` (no pose file: its pose is
  estimated, and the photo cut around the person); only when ``../shared/data/photos`` is beside the repository
  (the photos are not part of it), else skipped with a one-line note (``--photos`` points elsewhere);
- ``out/inputs/<clip>_<style>.mp4``: every demo input rendered in every style that fits it (skip: --no-inputs).

Every video plays the observed frames framed green, then each sampled future framed red.
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DEMO_INPUTS = REPO / "demo_inputs"
WEIGHTS = REPO / "motion2video" / "weights"
BODY = dict(motion_model="mixture-periodic", frame_model="frames-body-mesh-256", clip="cmu_walk.npz",
            reference="reference_body.png", start=24)
FACE = dict(motion_model="mtvae-add-face", frame_model="frames-face-mesh-128", clip="smile.npz",
            reference="reference_face.png", start=0)
MESH_SIZE = 256
# Behaviour transfer: the real CMU jump (cmu_jump.npz, CMU 16_02) re-enacted from wave.npz's first (standing)
# posture. The person jumps higher than the reference picture has room for above the head, so the picture is
# re-framed to keep the whole jump in view (transfer --fit-view).
# A real photo as the reference: the skier of ../shared/data/photos/skier.jpg (one person, full body, on
# plain snow), her pose estimated (no pose file), the photo cut to a square around her (--crop-person: the
# 640x425 photo would otherwise be padded to a square) and generated at 256 px. Two futures of the CMU walk by the
# best sampler (mixture-periodic: one of each DLow component), the second of which turns her sideways. The mesh generator
# draws her (frames-body-mesh-256): the keypoint warp (frames-body-128) tore her legs and jacket into fragments in
# such a turn; the mesh generator keeps her whole, with grey patches on her trousers, a noisy jacket and red patches
# on the side of her face (docs/results.md). The other photos were tried: man_by_truck.jpg and
# three_walking.jpg keep their faces, their forearms break into specks when they swing.
SHARED_PHOTOS = REPO.parent / "shared" / "data" / "photos"
PHOTO = dict(motion_model="mixture-periodic", frame_model="frames-body-mesh-256", clip="cmu_walk.npz", photo="skier.jpg",
             start=24, samples=2, size=256, crop_person=True)
TRANSFER = dict(motion_model="behavior", frame_model="frames-body-mesh-256", behavior="cmu_jump.npz",
                behavior_start=0, target="wave.npz", target_frame=0, reference="reference_body.png", fit_view=True)


def weight_files(weights: Path = WEIGHTS) -> dict[str, Path]:
    """Checkpoint name -> file in ``weights`` for every checkpoint the demo uses."""
    names = [BODY["motion_model"], BODY["frame_model"], FACE["motion_model"], FACE["frame_model"],
             TRANSFER["motion_model"], TRANSFER["frame_model"], PHOTO["frame_model"]]
    names = list(dict.fromkeys(names))  # each once, in order
    return {name: Path(weights) / f"{name}.safetensors" for name in names}


def peak_memory_mb() -> float:
    """Peak resident memory of this process and of its finished children (ffmpeg), MiB (Linux kB units)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return max(own, children) / 1024.0


def run_demo(out: Path, *, samples: int = 5, seed: int = 0, weights: Path = WEIGHTS) -> dict[str, Path]:
    """Write the demo videos into ``out`` using the checkpoints in ``weights``; returns name -> path."""
    from motion2video.apps.synthesize import (
        SynthesisConfig, compose_video, contact_sheet, render_mesh_frames, synthesize,
    )
    from motion2video.formats.video import write_image, write_video

    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    for name, spec in (("body", BODY), ("face", FACE)):
        t0 = time.perf_counter()
        files = weight_files(weights)
        result = synthesize(motion_model=files[spec["motion_model"]], frame_model=files[spec["frame_model"]],
                            input_path=DEMO_INPUTS / spec["clip"], reference=DEMO_INPUTS / spec["reference"],
                            output=out / f"futures_{name}.mp4",
                            config=SynthesisConfig(samples=samples, seed=seed, start=spec["start"]))
        for note in result.notes:
            print(f"  note: {note}")
        print(f"{name}: {result.samples} futures of {result.horizon} frames after {result.observed} observed "
              f"in {time.perf_counter() - t0:.1f} s")
        written.update({f"futures_{name}": result.video, f"futures_{name}_structure": result.structure_video,
                        f"futures_{name}_sheet": result.sheet})
        if name == "body":
            t0 = time.perf_counter()
            mesh = render_mesh_frames(result.structures, size=MESH_SIZE, fps=result.fps)
            written["mesh_body"] = write_video(out / "mesh_body.mp4", compose_video(mesh.observed, mesh.futures),
                                               result.fps)
            written["mesh_body_sheet"] = write_image(out / "mesh_body-sheet.png",
                                                     contact_sheet(mesh.observed, mesh.futures))
            print(f"body mesh: {time.perf_counter() - t0:.1f} s")
    written.update(run_transfer_demo(out, weights=weights))
    return written


def run_photo_demo(out: Path, *, photos: Path = SHARED_PHOTOS, weights: Path = WEIGHTS, seed: int = 0
                   ) -> dict[str, Path]:
    """``out/photo_body.mp4`` (+ structure video and sheet): PHOTO's futures drawn as the person of a real photo
    (as ``motion2video synthesize ... --reference PHOTO --crop-person``); nothing but a one-line note when the
    photo is not there."""
    from motion2video.apps.synthesize import SynthesisConfig, synthesize

    spec = PHOTO
    photo = Path(photos) / spec["photo"]
    if not photo.is_file():
        print(f"photo: skipped ({_shown(photo)} not found: the real photos live in ../shared/data/photos beside the "
              "repository)")
        return {}
    t0 = time.perf_counter()
    files = weight_files(weights)
    result = synthesize(motion_model=files[spec["motion_model"]], frame_model=files[spec["frame_model"]],
                        input_path=DEMO_INPUTS / spec["clip"], reference=photo, output=out / "photo_body.mp4",
                        config=SynthesisConfig(samples=spec["samples"], seed=seed, start=spec["start"],
                                               size=spec["size"], crop_person=spec["crop_person"]))
    for note in result.notes:
        print(f"  note: {note}")
    print(f"photo: {result.samples} futures of {spec['clip']} drawn as the person of {photo.name} (pose estimated, "
          f"cut around the person) at {spec['size']} px: {_shown(result.video)} in {time.perf_counter() - t0:.1f} s")
    return {"photo_body": result.video, "photo_body_structure": result.structure_video,
            "photo_body_sheet": result.sheet}


def run_transfer_demo(out: Path, *, weights: Path = WEIGHTS, size: int = 256) -> dict[str, Path]:
    """``out/transfer_body.mp4`` and ``.npz``: TRANSFER's behaviour re-enacted by the reference person, side by
    side with the source (as ``motion2video transfer --style frames --reference ... --npz ...``)."""
    import numpy as np

    from motion2video.apps.transfer import iter_transfer, transfer_behavior, transfer_forecast
    from motion2video.models.checkpoint import load_model
    from motion2video.core.atomic import save_npz
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.stages.reference import load_reference
    from motion2video.stages.clips import load_clip
    from motion2video.stages.structure import reference_in_view
    from motion2video.formats.video import VideoWriter, write_image

    t0 = time.perf_counter()
    spec = TRANSFER
    bundle = load_model(Path(weights) / f"{spec['motion_model']}.safetensors")
    frame_model = load_frame_model(Path(weights) / f"{spec['frame_model']}.safetensors")
    reference = load_reference(DEMO_INPUTS / spec["reference"], size=frame_model.config.image_size, domain="body")
    source = load_clip(bundle, DEMO_INPUTS / spec["behavior"])
    target = load_clip(bundle, DEMO_INPUTS / spec["target"])
    result = transfer_behavior(bundle, source, target, source_start=spec["behavior_start"],
                               target_frame=spec["target_frame"])
    reference = reference_in_view(transfer_forecast(result), reference, size=frame_model.config.image_size,
                                  fit_view=spec["fit_view"])
    video = out / "transfer_body.mp4"
    kept = []
    z = result.source[:, 0, 2]  # the source's pelvis height: the sheet shows start, crouch, top, landing
    low = int(np.argmin(z[: int(np.argmax(z)) + 1]))
    top = int(np.argmax(z))
    shown = sorted({0, low, top, min(top + (top - low), len(z) - 1)})
    with VideoWriter(video, result.fps) as writer:
        done = 0
        for chunk in iter_transfer(result, style="frames", size=size, frame_model=frame_model, reference=reference):
            writer.write(chunk)
            kept += [chunk[i - done] for i in shown if done <= i < done + len(chunk)]
            done += len(chunk)
    kept += kept[-1:] * (len(kept) % 2)  # an even number of cells: two per row
    rows = [np.concatenate(kept[i:i + 2], axis=1) for i in range(0, len(kept), 2)]
    sheet = write_image(out / "transfer_body-sheet.png", np.concatenate(rows, axis=0))
    npz = save_npz(out / "transfer_body.npz", {"source": result.source, "reenacted": result.reenacted,
                                               "z": result.z, "fps": np.float64(result.fps)})
    rise = lambda seq: float(seq[:, 0, 2].max() - seq[:, 0, 2].min())  # noqa: E731
    print(f"transfer: {spec['behavior']} re-enacted from {spec['target']} by {spec['reference']}: pelvis rises "
          f"{rise(result.source):.2f} m in the source, {rise(result.reenacted[0]):.2f} m in the re-enactment "
          f"({time.perf_counter() - t0:.1f} s)")
    return {"transfer_body": video, "transfer_body_npz": npz, "transfer_body_sheet": sheet}


def render_inputs(out: Path, *, size: int = 128) -> dict[str, Path]:
    """Render every demo input in every style that fits it (body: skeleton, heatmap, mesh; face: face) into
    ``out/inputs/<clip>_<style>.mp4``: the structure renderers on their own, as ``motion2video render`` does."""
    from motion2video.formats.io import load_motion
    from motion2video.core.motion import FaceMotion
    from motion2video.apps.render import render_motion
    from motion2video.formats.video import write_video

    written: dict[str, Path] = {}
    (out / "inputs").mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    for clip in sorted(DEMO_INPUTS.glob("*.npz")):
        if clip.name.endswith(".pose.npz"):
            continue
        motion = load_motion(clip)
        styles = ("face",) if isinstance(motion, FaceMotion) else ("skeleton", "heatmap", "mesh")
        for style in styles:
            frames = render_motion(motion, style=style, size=size)
            written[f"{clip.stem}_{style}"] = write_video(out / "inputs" / f"{clip.stem}_{style}.mp4", frames,
                                                          motion.fps)
    print(f"demo inputs in every style: {len(written)} videos in {time.perf_counter() - t0:.1f} s")
    return written


def _shown(path: Path) -> str:
    """A path relative to the repository when it lies inside it."""
    path = path.resolve()
    return str(path.relative_to(REPO)) if path.is_relative_to(REPO) else str(path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    parser.add_argument("--samples", type=int, default=5, help="futures per clip (default 5)")
    parser.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    parser.add_argument("--weights", type=Path, default=WEIGHTS,
                        help="folder holding the four checkpoints (default: the shipped motion2video/weights)")
    parser.add_argument("--no-inputs", dest="inputs", action="store_false",
                        help="skip rendering every demo input in every style into OUT/inputs/")
    parser.add_argument("--photos", type=Path, default=SHARED_PHOTOS,
                        help="folder of the real photos (default ../shared/data/photos beside the repository; "
                        "the photo video is skipped with a note when it is not there)")
    args = parser.parse_args(argv)
    if args.samples < 1:
        print(f"demo: error: --samples must be >= 1, got {args.samples}", file=sys.stderr)
        return 2
    missing = [path for path in weight_files(args.weights).values() if not path.is_file()]
    if missing:
        shown = ", ".join(_shown(path) for path in missing)
        print(f"demo: error: missing weight file(s): {shown} (the shipped checkpoints "
              "are trained with `motion2video train` and `motion2video train-frames`; see the model cards)",
              file=sys.stderr)
        return 2
    from motion2video.core.errors import InputError

    t0 = time.perf_counter()
    try:
        written = run_demo(args.out, samples=args.samples, seed=args.seed, weights=args.weights)
        written.update(run_photo_demo(args.out, photos=args.photos, weights=args.weights, seed=args.seed))
        if args.inputs:
            written.update(render_inputs(args.out))
    except InputError as err:
        print(f"demo: error: {err}", file=sys.stderr)
        return 2
    print(f"demo done in {time.perf_counter() - t0:.1f} s, peak memory {peak_memory_mb():.0f} MiB:")
    for path in written.values():
        print(f"  {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
