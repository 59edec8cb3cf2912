"""Observed motion -> K sampled futures -> structure -> RGB frames -> videos (what ``synthesize`` does).

The stages are plain functions with typed results, so each can be called (and timed) alone:

1. :func:`motion2video.stages.reference.load_reference`: the reference appearance image at the frame generator's size, and its pose.
2. :func:`~motion2video.stages.sampling.sample_forecast`: K futures of the observed clip from a motion model.
3. :func:`render_structures`: where the person is in every frame, in the generator's structure conventions
   (the same functions that made its training pairs, :mod:`motion2video.generator.data`):

   - body: 2D joints in generator pixels; :func:`structure_maps` turns them into 17 Gaussian heatmaps + 16
     limb maps (:func:`motion2video.generator.data.body_structures`).
   - face: the Anny face rendered in the shaded grey ``"structure"`` style on black, in each frame's head
     pose and expression (:func:`motion2video.generator.data.face_structures`).
4. :func:`generate_frames`: the frame generator turns (reference image, reference structure, target
   structure) into the target frame, for the observed frames and every future, so the whole video is
   one consistent person.
5. :func:`compose_video`, :func:`structure_previews`, :func:`contact_sheet`: the grid video (every cell
   plays the observed frames framed green, then one future framed red, labelled), the same grid of
   structures, and a contact-sheet PNG.

:func:`synthesize` runs them all and writes ``OUT.mp4``, ``OUT-structure.mp4`` and ``OUT-sheet.png``, all
three or none.

The reference image and its pose (the reference structure) are loaded by :mod:`motion2video.stages.reference`.

Placement
---------
- Body (3D models): the clip is turned about z so the person faces the camera (-y) at the first observed
  frame, and the camera *follows* the person on the ground: each frame's pelvis is moved to the same
  ground position (height, turning and limbs are kept). The generator's training sequences were short
  (1.2 s) with a fixed camera, so a person who walks several metres would leave its comfort zone (and the
  frame); following keeps the person at the reference's place and size. One camera (azimuth 0, elevation
  8 degrees, as the body renderer's default) is fitted to the observed frames (so the observed part does
  not depend on the samples), then one 2D similarity (scale + shift) maps the first observed frame's legs,
  spine and head onto the reference pose's; the futures share both.
- Body (2D models): the same, in the model's virtual-camera pixels (the pelvis keeps its first x).
- Face: one camera for the whole video, the camera of the reference image (from the pose file), else the
  Anny close-up camera of the first observed frame. The structure mesh uses the reference's identity.
"""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from motion2video.core.atomic import check_output_path
from motion2video.core.errors import InputError
from motion2video.stages.reference import cut_to_view, load_reference
from motion2video.stages.generation import GeneratedFrames, default_generator_threads, iter_generated
from motion2video.stages.sampling import sample_forecast
from motion2video.stages.structure import (
    DOMAIN_OF_LAYOUT, Structures, reference_in_view, render_structures, structure_previews,
)
from renderers.registry import renderer_for

STRUCTURE_SUFFIX = "-structure"
SHEET_SUFFIX = "-sheet"
BORDER = 4  # pixels of the green / red frame around each cell
SHEET_COLUMNS = 8


# --- small helpers ---------------------------------------------------------------------------------------

def output_paths(video: str | Path) -> tuple[Path, Path, Path]:
    """``OUT.mp4`` -> (``OUT.mp4``, ``OUT-structure.mp4``, ``OUT-sheet.png``)."""
    video = Path(video)
    return (video, video.with_name(video.stem + STRUCTURE_SUFFIX + video.suffix),
            video.with_name(video.stem + SHEET_SUFFIX + ".png"))


# --- sampling ----------------------------------------------------------------------------------------------

# --- layouts -----------------------------------------------------------------------------------------------

def compose_video(observed: np.ndarray, futures: np.ndarray, *, border: int = BORDER) -> np.ndarray:
    """The grid video: every cell plays the observed frames framed green (labelled ``observed``), then one
    future framed red (labelled ``sample k``).

    Args:
        observed: (To, H, W, 3) uint8. futures: (K, Tf, H, W, 3) uint8.
    Returns:
        (To + Tf, H', W', 3) uint8.
    """
    from motion2video.formats.video import label, observed_future_video

    obs = label(observed, "observed", inset=border)
    futs = [label(f, f"sample {k + 1}", inset=border) for k, f in enumerate(futures)]
    return observed_future_video(obs, futs, None, border=border)


def contact_sheet(observed: np.ndarray, futures: np.ndarray, *, header: tuple = (),
                  columns: int = SHEET_COLUMNS, border: int = BORDER) -> np.ndarray:
    """One picture of the result.

    Row 0: the ``header`` pictures (e.g. the reference image and its structure), then evenly spaced
    observed frames (green); one row per sample: evenly spaced future frames (red). Cells are labelled.

    Args:
        observed: (To, H, W, 3) uint8. futures: (K, Tf, H, W, 3) uint8.
        header: (image (H, W, 3) uint8, label) pairs shown first, unframed.
    Returns:
        (H', W', 3) uint8.
    """
    to, tf = observed.shape[0], futures.shape[1]
    return contact_sheet_of(lambda t: observed[t], lambda k, t: futures[k, t], to, tf, len(futures),
                            header=header, columns=columns, border=border)


def sheet_steps(observed: int, horizon: int, *, header: int = 0, columns: int = SHEET_COLUMNS) -> tuple[list, list]:
    """The observed and future indices :func:`contact_sheet` shows (so a stream can keep just those)."""
    return _spread(observed, columns - header), _spread(horizon, columns)


def contact_sheet_of(observed_frame, future_frame, to: int, tf: int, k: int, *, header: tuple = (),
                     columns: int = SHEET_COLUMNS, border: int = BORDER) -> np.ndarray:
    """:func:`contact_sheet` from frame getters: ``observed_frame(t)`` and ``future_frame(k, t)`` return
    (H, W, 3) uint8 and are only asked for the indices of :func:`sheet_steps`."""
    from motion2video.formats.video import GREEN, RED, add_border, grid

    cells = [image for image, _ in header]
    labels = [text for _, text in header]
    for t in _spread(to, columns - len(cells)):
        cells.append(add_border(observed_frame(t), GREEN, border))
        labels.append(f"observed {t}")
    blank = np.zeros_like(observed_frame(0))
    cells += [blank] * (columns - len(cells))
    labels += [""] * (columns - len(labels))
    for j in range(k):
        index = _spread(tf, columns)
        for t in index:
            cells.append(add_border(future_frame(j, t), RED, border))
            labels.append(f"s{j + 1} +{t + 1}")
        cells += [blank] * (columns - len(index))
        labels += [""] * (columns - len(index))
    return grid([c[None] for c in cells], labels, columns)[0]


def compose_chunk(frames: np.ndarray, start: int, observed: int, *, border: int = BORDER) -> np.ndarray:
    """:func:`compose_video` for steps ``start..start+t-1`` of the timeline.

    Args:
        frames: (t, K, H, W, 3) uint8, cell k's frame of each step (observed steps: the observed frame).
        start: the first step; steps < ``observed`` are observed (green, ``observed``), later ones cell k's
            future (red, ``sample k``).
    Returns:
        (t, H', W', 3) uint8, equal to the same rows of :func:`compose_video`.
    """
    from motion2video.formats.video import GREEN, RED, add_border, grid, label

    t, k = frames.shape[:2]
    cells = []
    for j in range(k):
        parts = []
        for step in range(t):
            is_obs = start + step < observed
            text = "observed" if is_obs else f"sample {j + 1}"
            parts.append(add_border(label(frames[step, j], text, inset=border), GREEN if is_obs else RED, border))
        cells.append(np.stack(parts))
    return grid(cells, None, None)


def _spread(length: int, count: int) -> list[int]:
    """Up to ``count`` distinct, evenly spaced indices into ``range(length)`` (first and last included)."""
    if length <= count:
        return list(range(length))
    return sorted({int(round(i)) for i in np.linspace(0, length - 1, count)})


# --- the whole pipeline ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class SynthesisConfig:
    """Options of :func:`synthesize`.

    Attributes:
        samples: K futures (1..64).
        observed: observed frames (None: the motion model's training value).
        horizon: future frames (None: the motion model's training value).
        start: first observed frame of the clip.
        seed: sampling seed (the same seed gives the same frames).
        batch_size: generator frames per forward pass (4 was fastest at 128 px on 2 cores, with channels_last).
        motion_threads: torch threads while sampling (1: the small recurrent models are fastest so).
        generator_threads: torch threads while generating (None: :func:`default_generator_threads`).
        crf, preset: x264 settings of the two videos.
        size: output frame size (None: the generator's size); another size needs a warp generator, which
            keeps the reference's background at this size and generates the person at its own size.
        rigid_bones: give the futures the observed bone lengths (3D body models;
            :func:`motion2video.stages.sampling.forecast`).
        character: the character file of a DeepMimic input (None: found beside it, else the standard one).
        rig_map: the rig map file of a BVH input whose joint names do not tell the body points.
        input_fps: the input's true frame rate when the file states none (joint arrays) or a wrong one.
        crop_person: cut the reference photo to a square around its person first
            (:func:`motion2video.stages.reference.crop_to_person`).
        fit_view: body: when a placed body leaves the reference picture (a jump's head above the top), zoom the
            picture out so that every frame shows the whole person
            (:func:`motion2video.stages.structure.reference_in_view`); without it, a note says so.
    """

    samples: int = 5
    observed: int | None = None
    horizon: int | None = None
    start: int = 0
    seed: int = 0
    batch_size: int = 4
    motion_threads: int | None = 1
    generator_threads: int | None = None
    crf: int = 18
    preset: str = "medium"
    size: int | None = None
    rigid_bones: bool = False
    character: str | None = None
    rig_map: str | None = None
    input_fps: float | None = None
    crop_person: bool = False
    fit_view: bool = False


@dataclass
class SynthesisResult:
    """What :func:`synthesize` wrote and how long each stage took.

    Attributes:
        video, structure_video, sheet: the written files (None when nothing was written).
        frames: (T, H, W, 3) shape of the grid video.
        samples, observed, horizon: K, To, Tf.
        fps: frame rate of the videos.
        domain: ``"body"`` or ``"face"``.
        notes: conversions and assumptions (one line each).
        timings: seconds per stage: load, sampling, structures, generation, compose, encoding, total.
        forecast: the sampled motion (:class:`motion2video.stages.sampling.Forecast`).
        structures: the :class:`Structures` used.
    """

    video: Path | None
    structure_video: Path | None
    sheet: Path | None
    frames: tuple[int, ...]
    samples: int
    observed: int
    horizon: int
    fps: float
    domain: str
    notes: tuple[str, ...]
    timings: dict[str, float]
    forecast: object = field(repr=False)
    structures: Structures = field(repr=False)


def check_output(path: str | Path) -> tuple[Path, Path, Path]:
    """Validate ``OUT.mp4`` before any work: extension and an existing, writable folder.

    Returns:
        :func:`output_paths` of it.
    """
    path = check_output_path(path, (".mp4",))
    for p in output_paths(path):
        if p.is_dir():
            raise InputError("the output path is a directory", p)
    return output_paths(path)


def write_outputs(paths: tuple[Path, Path, Path], video: np.ndarray, structure_video: np.ndarray,
                  sheet: np.ndarray, *, fps: float, crf: int = 18, preset: str = "medium") -> None:
    """Write the video, the structure video and the sheet, all three or none: each is written to a
    temporary name beside its destination and the three are renamed only when all succeeded."""
    from motion2video.formats.video import write_image, write_video

    temps = [p.with_name(f".{p.stem}.{os.getpid()}.partial{p.suffix}") for p in paths]
    try:
        write_video(temps[0], video, fps, crf=crf, preset=preset)
        write_video(temps[1], structure_video, fps, crf=crf, preset=preset)
        write_image(temps[2], sheet)
        for tmp, final in zip(temps, paths):
            os.replace(tmp, final)
    finally:
        for tmp in temps:
            tmp.unlink(missing_ok=True)


def synthesize(*, motion_model, frame_model, input_path: str | Path, reference: str | Path,
               output: str | Path | None, config: SynthesisConfig = SynthesisConfig(),
               reference_pose: str | Path | None = None,
               on_chunk: Callable[[int, np.ndarray, np.ndarray], None] | None = None,
               progress: Callable[[str, float], None] | None = None) -> SynthesisResult:
    """Observed clip + reference image -> K futures as RGB videos: ``OUT.mp4``, ``OUT-structure.mp4`` and
    ``OUT-sheet.png`` (see the module docstring); with ``output=None`` nothing is written and ``on_chunk`` is
    the only way the frames come out.

    Args:
        motion_model: a checkpoint path / shipped name, or a loaded ModelBundle.
        frame_model: a checkpoint path / shipped name, or a loaded frame model (LoadedFrameModel).
        input_path: the observed clip (.bvh / body .npz / a video of a person for body models; FaceMotion
            .npz / .csv for face).
        reference: the reference appearance image.
        output: ``OUT.mp4``, or None.
        config: the options.
        reference_pose: the reference pose file (default: ``IMAGE.pose.npz`` when it exists).
        on_chunk: called with every generated chunk, ``(start, frames, previews)`` as
            :func:`~motion2video.stages.generation.iter_generated` yields them, before it is written.
        progress: called with ``(stage, fraction)``: ``"loading"``, ``"sampling"``, ``"structures"``, then
            ``"frames"`` after every chunk (fraction of the video's steps done). An exception it raises (a
            cancelled request) stops the work and leaves no file.
    Returns:
        A :class:`SynthesisResult`.
    Raises:
        InputError: any user-fixable problem, before anything is written.
    """
    from motion2video.models.checkpoint import load_model
    from motion2video.stages.clips import load_clip
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.formats.video import VideoWriter, write_image

    timings: dict[str, float] = {}
    t_all = t0 = time.perf_counter()
    report = progress or (lambda stage, fraction: None)
    paths = None if output is None else check_output(output)
    report("loading", 0.0)
    bundle = load_model(motion_model) if isinstance(motion_model, (str, Path)) else motion_model
    frames_model = load_frame_model(frame_model) if isinstance(frame_model, (str, Path)) else frame_model
    gen_config = frames_model.model.config
    domain = gen_config.domain
    layout_domain = DOMAIN_OF_LAYOUT[bundle.data_config.layout]
    if layout_domain != domain:
        raise InputError(f"the frame model makes {domain} frames but the motion model {bundle.label} predicts "
                         f"{layout_domain} motion: give a {layout_domain} frame model (frames-{layout_domain}-128)")
    kind = getattr(frames_model, "kind", "analogy")
    if kind == "mesh" and domain == "body" and bundle.data_config.layout != "body3d":
        raise InputError(f"the mesh frame generator needs a 3D body motion (the motion model {bundle.label} predicts "
                         f"2D keypoints); use --frame-model frames-body-128")
    size = gen_config.image_size if config.size is None else int(config.size)
    if size != gen_config.image_size and (kind not in ("warp", "mesh") or domain == "face"):
        raise InputError(f"--size {size} needs a body warp or mesh frame model (this {domain} generator makes "
                         f"{gen_config.image_size} px frames only)")
    clip = load_clip(bundle, input_path, character=config.character, fps=config.input_fps,
                     rig_map=config.rig_map).data
    ref = load_reference(reference, size=size, domain=domain, pose_path=reference_pose,
                         crop_person=config.crop_person, keep_framing=kind in ("warp", "mesh"))
    canvas = ref.image.shape[0]  # the generator's frame size: ``size``, or larger when the picture's framing is kept
    timings["load"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    report("sampling", 0.0)
    fc = sample_forecast(bundle, clip, samples=config.samples, observed=config.observed, horizon=config.horizon,
                        start=config.start, seed=config.seed, threads=config.motion_threads, source=str(input_path),
                        rigid_bones=config.rigid_bones)
    timings["sampling"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    report("structures", 0.0)
    ref = reference_in_view(fc, ref, size=canvas, fit_view=config.fit_view)
    structures = render_structures(fc, domain=domain, size=canvas, reference=ref)
    timings["structures"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    threads = config.generator_threads or default_generator_threads()
    clock: dict[str, float] = {}
    to, tf = structures.observed, structures.horizon
    ref_preview = structure_previews(structures, slice(0, 1))[0]
    header = ((cut_to_view(ref.image, ref.view, size), "reference"), (cut_to_view(ref_preview, ref.view, size),
                                                                      "ref. structure"))
    obs_steps, fut_steps = sheet_steps(to, tf, header=len(header))
    picked: dict[tuple[int, int], np.ndarray] = {}  # (cell, step) -> frame, for the contact sheet
    compose_s = 0.0
    chunks = iter_generated(frames_model, ref, structures, batch_size=config.batch_size, threads=threads,
                            clock=clock)
    temps = [] if paths is None else [p.with_name(f".{p.stem}.{os.getpid()}.partial{p.suffix}") for p in paths]
    steps = to + tf
    grid_shape = None
    report("frames", 0.0)
    try:
        with contextlib.ExitStack() as stack:
            writers = [stack.enter_context(VideoWriter(tmp, fc.fps, crf=config.crf, preset=config.preset))
                       for tmp in temps[:2]]
            for start, frames, previews in chunks:
                frames, previews = cut_to_view(frames, ref.view, size), cut_to_view(previews, ref.view, size)
                if on_chunk is not None:
                    on_chunk(start, frames, previews)
                c0 = time.perf_counter()
                if writers:
                    grid = compose_chunk(frames, start, to)
                    writers[0].write(grid)
                    writers[1].write(compose_chunk(previews, start, to))
                    grid_shape = grid.shape[1:]
                elif grid_shape is None:  # nothing written: the shape the grid video would have
                    grid_shape = compose_chunk(frames[:1], start, to).shape[1:]
                for i in range(len(frames)):
                    step = start + i
                    if step < to and step in obs_steps:
                        picked[0, step] = frames[i, 0]
                    elif step >= to and step - to in fut_steps:
                        for j in range(frames.shape[1]):
                            picked[j, step] = frames[i, j]
                compose_s += time.perf_counter() - c0
                report("frames", (start + len(frames)) / steps)
        c0 = time.perf_counter()
        sheet = contact_sheet_of(lambda t: picked[0, t], lambda j, t: picked[j, to + t], to, tf,
                                 structures.samples, header=header)
        if paths is not None:
            write_image(temps[2], sheet)
        compose_s += time.perf_counter() - c0
        for tmp, final in zip(temps, paths or ()):
            os.replace(tmp, final)
    finally:
        for tmp in temps:
            tmp.unlink(missing_ok=True)
    loop_s = time.perf_counter() - t0
    timings["generation"] = clock.get("generation", 0.0)
    timings["compose"] = compose_s
    timings["encoding"] = max(0.0, loop_s - timings["generation"] - compose_s)
    timings["total"] = time.perf_counter() - t_all
    return SynthesisResult(video=paths and paths[0], structure_video=paths and paths[1], sheet=paths and paths[2],
                           frames=(to + tf, *grid_shape),
                           samples=structures.samples, observed=structures.observed, horizon=structures.horizon,
                           fps=float(fc.fps), domain=domain, notes=ref.notes, timings=timings, forecast=fc,
                           structures=structures)


# --- the Anny mesh path of the same futures ---------------------------------------------------------------

def render_mesh_frames(structures: Structures, *, size: int = 256, fps: float = 25.0) -> GeneratedFrames:
    """The Anny body in the same placed poses as the structures (the followed, front-facing 3D joints and
    the camera they were placed with), one body fit for all frames so every cell shows the same body.

    Args:
        structures: body structures from a 3D body model (:func:`render_structures`).
        size: frame size in pixels.
    Returns:
        :class:`GeneratedFrames`: observed (To, size, size, 3) and futures (K, Tf, size, size, 3) uint8.
    """
    placement = structures.placement
    if placement is None or placement.world_observed is None:
        raise InputError("the mesh video needs a 3D body model (this forecast has no 3D joints)")
    k, tf = placement.world_futures.shape[:2]
    to = placement.world_observed.shape[0]
    every = np.concatenate([placement.world_observed, placement.world_futures.reshape(k * tf, 17, 3)])
    camera = placement.camera.with_size(size, size)
    with renderer_for("body3d", "mesh", size=size) as renderer:
        frames = renderer.draw(every.astype(np.float32), fps, camera=camera)
    return GeneratedFrames(observed=frames[:to], futures=frames[to:].reshape(k, tf, size, size, 3))
