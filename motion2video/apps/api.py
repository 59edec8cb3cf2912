"""The pipeline as Python functions: what the commands do, with arrays and typed results instead of files.

::

    import motion2video as m2v

    model = m2v.load_model("mtvae-add")
    futures = m2v.sample(model, "demo_inputs/walk_to_run.npz", samples=3)     # futures.futures: (3, 48, 17, 3)
    video = m2v.synthesize("mtvae-add", "frames-body-128", "demo_inputs/walk_to_run.npz",
                           "demo_inputs/reference_body_128.png", samples=2, output="out/walk.mp4")
    video.frames                                                            # (2, 64, 128, 128, 3) uint8

Every function is a thin wrapper over the application the matching command runs (:mod:`motion2video.apps.sample`,
:mod:`~motion2video.apps.synthesize`, :mod:`~motion2video.apps.transfer`, :mod:`~motion2video.apps.analogy`,
:mod:`motion2video.stages.people`): the same defaults, the same checks, the same
:class:`~motion2video.core.errors.InputError` (one line naming the file and the problem) for bad input. Models
are given as a shipped name, a checkpoint path or what :func:`load_model` returned; clips as a path of any
format :func:`motion2video.formats.io.load_motion` reads, or a video of a person (its pose is estimated and
cached). Outputs are optional: with ``output`` a function also writes the mp4 the command writes, atomically.

Functions that take ``progress`` call it as ``progress(stage, fraction)`` (``fraction`` in [0, 1] within the
stage); an exception it raises stops the work at the next step and leaves no partial file, which is how a caller
(the web app) cancels.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from safetensors import SafetensorError, safe_open

from motion2video.apps.analogy import analogy as analogy_app
from motion2video.apps.analogy import iter_analogy
from motion2video.apps.sample import iter_forecast, load_clip_for, save_forecast_npz
from motion2video.apps.synthesize import SynthesisConfig
from motion2video.apps.synthesize import synthesize as synthesize_app
from motion2video.apps.transfer import (frame_style_inputs, iter_transfer, requested_style, sample_behaviors, style_for,
                                        transfer_behavior, transfer_forecast)
from motion2video.core.atomic import check_output_path
from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion, Motion
from motion2video.data.dataset import DatasetConfig
from motion2video.formats.bvh_write import check_bvh_dir, write_bvh_files
from motion2video.formats.video import VIDEO_SUFFIXES, VideoWriter
from motion2video.generator.checkpoint import FORMAT as FRAMES_FORMAT
from motion2video.generator.checkpoint import LoadedFrameModel, load_frame_model
from motion2video.models import checkpoint
from motion2video.models.baselines import BASELINES, RULES
from motion2video.models.checkpoint import ModelBundle
from motion2video.pose.estimate import open_video
from motion2video.pose.files import save_video_pose
from motion2video.stages import people
from motion2video.stages.clips import load_clip
from motion2video.stages.latents import ADAPT_STEPS, analogy_model, behavior_model
from motion2video.stages.layout import check_cell_size
from motion2video.stages.people import is_video, reference_pose_of
from motion2video.stages.reference import save_reference_pose
from motion2video.stages.sampling import Forecast, sample_forecast
from motion2video.stages.structure import reference_in_view
from renderers.registry import check_style

Progress = Callable[[str, float], None]

POSE_STAGE = "pose estimation"


def _no_progress(stage: str, fraction: float) -> None:
    """The ``progress`` of a caller that asks for none."""


# --- models --------------------------------------------------------------------------------------------------


def load_model(name_or_path: str | Path, *, device: str = "cpu"):
    """A motion model or a frame generator, from a shipped name, a checkpoint path, or a baseline's name.

    Args:
        name_or_path: ``"mtvae-add"``, ``"frames-body-128"``, ``"runs/cvae.safetensors"``, ``"zero-velocity"``, ...
        device: torch device of a motion model (frame generators run on the CPU).
    Returns:
        A :class:`~motion2video.models.checkpoint.ModelBundle` (motion models and baselines; ``.model``,
        ``.data_config``) or a :class:`~motion2video.generator.checkpoint.LoadedFrameModel` (frame generators;
        ``.model``, ``.config``), as the checkpoint says.
    Raises:
        InputError: no such file or name, or not a motion2video checkpoint.
    """


    if str(name_or_path) in BASELINES + RULES:
        return checkpoint.baseline_bundle(str(name_or_path), DatasetConfig())
    path = checkpoint.resolve_checkpoint(name_or_path)
    try:
        with safe_open(str(path), framework="pt") as f:
            kind = (f.metadata() or {}).get("format")
    except (SafetensorError, OSError, ValueError) as err:
        raise InputError(f"not a readable safetensors checkpoint ({str(err).splitlines()[0]})", path) from None
    if kind == FRAMES_FORMAT:
        return load_frame_model(path)
    return checkpoint.load_model(path, device=device)


def _motion_model(model):
    """A loaded motion model (a ModelBundle) from whatever :func:`load_model` takes or returned."""

    bundle = model if isinstance(model, ModelBundle) else load_model(model)
    if not isinstance(bundle, ModelBundle):
        raise InputError("this is a frame generator; a motion model is needed here", bundle.path)
    return bundle


def _frame_model(model):
    """A loaded frame generator from a name, a path or what :func:`load_model` returned."""

    loaded = model if isinstance(model, LoadedFrameModel) else load_model(model)
    if not isinstance(loaded, LoadedFrameModel):
        raise InputError(f"{loaded.label} is a motion model; a frame generator (frames-body-128, ...) is needed here")
    return loaded


def _motions(sequences: np.ndarray, fps: float, layout: str, source: str | None) -> list[Motion | FaceMotion]:
    """(K, T, ...) sequences of a model's layout as K :class:`Motion` (body: h36m-17, 3D metres or 2D pixels) or
    :class:`FaceMotion` (T, 58)."""
    if layout == "face":
        return [FaceMotion(np.asarray(s, np.float32), fps, {}, source) for s in sequences]
    return [Motion(np.asarray(s, np.float32), fps, "h36m-17", source) for s in sequences]


def _write_bvh(folder: str | Path, stem: str, sequences: np.ndarray, fps: float, layout: str) -> list[Path]:

    if layout != "body3d":
        raise InputError(f"BVH files hold 3D body motion; this model's output is {layout}", folder)
    return write_bvh_files(check_bvh_dir(folder), stem, sequences, fps)


def _render(chunks: Iterable[np.ndarray], fps: float, output: str | Path | None, *, frames: int = 0,
            progress: Progress = _no_progress) -> tuple[np.ndarray, Path | None]:
    """A stream of (t, H, W, 3) uint8 chunks as one (T, H, W, 3) array, written to ``output`` (mp4 / GIF) too when
    given (atomically, as it is drawn); ``progress("frames", done / frames)`` after every chunk."""

    kept: list[np.ndarray] = []
    with contextlib.ExitStack() as stack:
        writer = None if output is None else stack.enter_context(VideoWriter(output, fps))
        for chunk in chunks:
            if writer is not None:
                writer.write(chunk)
            kept.append(chunk)
            progress("frames", min(1.0, sum(len(c) for c in kept) / max(1, frames)))
    return np.concatenate(kept), None if output is None else Path(output)


def _check_video_output(output: str | Path | None) -> Path | None:

    return None if output is None else check_output_path(output, VIDEO_SUFFIXES)


# --- sample --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Futures:
    """K sampled futures of one observed clip (what ``motion2video sample`` draws).

    Attributes:
        observed: (To, 17, 3) world joints in metres (3D body models), (To, 17, 2) pixels of the model's virtual
            camera (2D body models) or (To, 58) face parameters.
        futures: (K, Tf, ...) the same per frame, each continuing ``observed``.
        fps: frame rate of both.
        layout: ``"body3d"``, ``"body2d"`` or ``"face"``.
        model: the model's name; seed: the sampling seed.
        source: the observed clip's file.
        video: (T, H, W, 3) uint8 grid video (observed frames framed green, then each future framed red), when
            it was rendered; path: where it was written.
    """

    observed: np.ndarray
    futures: np.ndarray
    fps: float
    layout: str
    model: str
    seed: int
    source: str | None = None
    video: np.ndarray | None = field(default=None, repr=False)
    path: Path | None = None

    @property
    def motions(self) -> list[Motion | FaceMotion]:
        """One :class:`Motion` (body) or :class:`FaceMotion` (face) per future: the observed frames, then it."""
        k = len(self.futures)
        whole = np.concatenate([np.broadcast_to(self.observed, (k,) + self.observed.shape), self.futures], axis=1)
        return _motions(whole, self.fps, self.layout, self.source)

    def save_npz(self, path: str | Path) -> Path:
        """``observed``, ``futures``, ``fps``, ``layout``, ``model``, ``seed`` in one .npz (``sample --npz``)."""

        return save_forecast_npz(self._forecast(), path)

    def save_bvh(self, folder: str | Path, stem: str = "sample") -> list[Path]:
        """``FOLDER/STEM_1.bvh`` ...: each future after the observed frames (3D body models; ``sample --bvh``)."""
        whole = np.stack([m.joints for m in self.motions])  # (K, To + Tf, 17, 3)
        return _write_bvh(folder, stem, whole, self.fps, self.layout)

    def _forecast(self):

        return Forecast(observed=self.observed, futures=self.futures, fps=self.fps, layout=self.layout,
                        model=self.model, seed=self.seed)


def sample(model, clip: str | Path, *, samples: int = 5, observed: int | None = None, horizon: int | None = None,
           start: int = 0, seed: int = 0, rigid_bones: bool = False, fps: float | None = None,
           character: str | Path | None = None, render: bool = False, style: str = "skeleton", size: int = 256,
           output: str | Path | None = None) -> Futures:
    """K futures of ``clip[start:start + observed]`` (``motion2video sample``).

    Args:
        model: a motion model (shipped name, checkpoint path, baseline name, or :func:`load_model`'s result).
        clip: the observed clip (a motion file or a video of a person for body models; a face capture for face
            models).
        samples: K (1..64). observed, horizon: frames (default: the model's). start: first observed frame.
        seed: the same seed gives the same futures. rigid_bones: keep the observed bone lengths (3D bodies).
        fps: the clip's true frame rate when the file states none (joint arrays, OpenPose folders).
        character: a DeepMimic file's character file.
        render: also draw the grid video into ``Futures.video`` (``style`` ``"skeleton"`` or ``"mesh"``,
            ``size`` px cells); implied by ``output``.
        output: write that video here (.mp4 or .gif).
    Returns:
        :class:`Futures`.
    """

    check_cell_size(size)
    out = _check_video_output(output)
    bundle = _motion_model(model)
    data = load_clip_for(bundle, clip, character=character, fps=fps)
    fc = sample_forecast(bundle, data, samples=samples, observed=observed, horizon=horizon, start=start, seed=seed,
                         threads=None, source=str(clip), rigid_bones=rigid_bones)
    video = path = None
    if render or out is not None:
        video, path = _render(iter_forecast(fc, style=style, size=size), fc.fps, out)
    return Futures(observed=fc.observed, futures=fc.futures, fps=float(fc.fps), layout=fc.layout, model=fc.model,
                   seed=fc.seed, source=str(clip), video=video, path=path)


# --- synthesize ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Synthesis:
    """K futures of a clip as video of the reference person (``motion2video synthesize``).

    Attributes:
        futures: the sampled motion (:class:`Futures`).
        frames: (K, To + Tf, S, S, 3) uint8: per future, the observed frames then that future, generated.
        structure: (K, To + Tf, S, S, 3) uint8: the structure the generator was given for each frame.
        fps: frame rate.
        notes: what was assumed or converted (one line each: the reference resized, its pose estimated, ...).
        video, structure_video, sheet: the written ``OUT.mp4``, ``OUT-structure.mp4``, ``OUT-sheet.png`` (None
            without ``output``).
        timings: seconds per stage (load, sampling, structures, generation, compose, encoding, total).
    """

    futures: Futures
    frames: np.ndarray = field(repr=False)
    structure: np.ndarray = field(repr=False)
    fps: float
    notes: tuple[str, ...]
    video: Path | None
    structure_video: Path | None
    sheet: Path | None
    timings: dict[str, float]


def synthesize(motion_model, frame_model, clip: str | Path, reference: str | Path, *, samples: int = 5,
               observed: int | None = None, horizon: int | None = None, start: int = 0, seed: int = 0,
               size: int | None = None, rigid_bones: bool = False, crop_person: bool = False,
               fit_view: bool = False, reference_pose: str | Path | None = None, fps: float | None = None,
               character: str | Path | None = None, batch_size: int = 4, threads: int | None = None,
               max_seconds: float | None = None, output: str | Path | None = None,
               progress: Progress | None = None) -> Synthesis:
    """Observed clip + reference photo -> K futures as frames of the pictured person.

    Args:
        motion_model, frame_model: names, checkpoint paths or :func:`load_model`'s results.
        clip: the observed clip (a video of a person too: its pose is estimated first, stage
            ``"pose estimation"``).
        reference: the photo to animate. reference_pose: its pose file (default ``IMAGE.pose.npz`` beside it;
            without one the pose is estimated). crop_person: cut the photo to its person first (a photo where
            nobody is found is then an InputError). fit_view: zoom out when the motion leaves the picture.
        samples, observed, horizon, start, seed, rigid_bones, fps, character: as in :func:`sample`.
        size: output frame size (default: the frame model's).
        batch_size, threads: generator frames per pass and torch threads (default: half the cores, 1 to 4).
        max_seconds: refuse a video clip longer than this (:func:`estimate_pose`).
        output: ``OUT.mp4``: also write it, ``OUT-structure.mp4`` and ``OUT-sheet.png`` (all three or none).
        progress: ``progress(stage, fraction)``: ``"pose estimation"`` (video clips), ``"loading"``,
            ``"sampling"``, ``"structures"``, ``"frames"``.
    Returns:
        :class:`Synthesis`.
    """

    report = progress or _no_progress
    if is_video(clip):
        report(POSE_STAGE, 0.0)
        estimate_pose(clip, max_seconds=max_seconds)  # cached by the file's hash: the loading below reads it back
    config = SynthesisConfig(samples=samples, observed=observed, horizon=horizon, start=start, seed=seed,
                             batch_size=batch_size, generator_threads=threads, size=size, rigid_bones=rigid_bones,
                             character=None if character is None else str(character), input_fps=fps,
                             crop_person=crop_person, fit_view=fit_view)
    chunks: list[tuple[np.ndarray, np.ndarray]] = []
    result = synthesize_app(motion_model=_motion_model(motion_model), frame_model=_frame_model(frame_model),
                            input_path=clip,
                            reference=reference, output=output, config=config, reference_pose=reference_pose,
                            on_chunk=lambda start, frames, previews: chunks.append((frames, previews)),
                            progress=report)
    frames = np.concatenate([f for f, _ in chunks]).swapaxes(0, 1)  # (T, K, S, S, 3) -> (K, T, S, S, 3)
    structure = np.concatenate([p for _, p in chunks]).swapaxes(0, 1)
    fc = result.forecast
    futures = Futures(observed=fc.observed, futures=fc.futures, fps=float(fc.fps), layout=fc.layout,
                      model=fc.model, seed=fc.seed, source=str(clip))
    return Synthesis(futures=futures, frames=np.ascontiguousarray(frames), structure=np.ascontiguousarray(structure),
                     fps=result.fps, notes=result.notes, video=result.video, structure_video=result.structure_video,
                     sheet=result.sheet, timings=result.timings)


# --- transfer ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Transfer:
    """A behaviour re-enacted from a target's posture, or flow-sampled behaviours (``motion2video transfer``).

    Attributes:
        source: (1 + H, ...) the behaviour's source window (None for flow samples).
        reenacted: (K, 1 + H, ...) the target's start posture then H generated frames, per behaviour (K = 1 for
            a source clip).
        z: (K, Z) the behaviour latents.
        fps, layout: as in :class:`Futures`.
        style: how the video draws it (``mesh``, ``frames`` or ``skeleton``).
        notes: what was assumed about the reference photo (style ``frames``).
        video: (T, H', W', 3) uint8 side-by-side video, when rendered; path: where it was written.
    """

    source: np.ndarray | None
    reenacted: np.ndarray
    z: np.ndarray
    fps: float
    layout: str
    style: str
    notes: tuple[str, ...] = ()
    video: np.ndarray | None = field(default=None, repr=False)
    path: Path | None = None

    @property
    def motions(self) -> list[Motion | FaceMotion]:
        """One :class:`Motion` / :class:`FaceMotion` per re-enactment."""
        return _motions(self.reenacted, self.fps, self.layout, None)

    def save_bvh(self, folder: str | Path, stem: str = "reenacted") -> list[Path]:
        """``FOLDER/STEM_1.bvh`` ...: each re-enactment (3D body models; ``transfer --bvh``)."""
        return _write_bvh(folder, stem, self.reenacted, self.fps, self.layout)


def transfer(model, target: str | Path, *, behavior: str | Path | None = None, samples: int | None = None,
             target_frame: int = 0, behavior_start: int = 0, horizon: int | None = None,
             adapt_steps: int | None = None, seed: int = 0, style: str | None = None,
             frame_model=None, reference: str | Path | None = None, reference_pose: str | Path | None = None,
             crop_person: bool = False, fit_view: bool = False, fps: float | None = None,
             character: str | Path | None = None, render: bool = False, size: int = 256,
             max_seconds: float | None = None, output: str | Path | None = None,
             progress: Progress | None = None) -> Transfer:
    """Re-enact the behaviour of ``behavior`` from ``target``'s posture at ``target_frame``, or ``samples`` new
    behaviours drawn through the flow (exactly one of the two).

    Args:
        model: a behaviour model (``"behavior"``, a checkpoint, or :func:`load_model`'s result).
        behavior_start: the source's first frame. target_frame: the target's start frame (file frames).
        horizon: generated frames (default: the model's). adapt_steps: fit the decoder to the source first
            (default 300; 0: the model as trained). seed: the flow samples' seed.
        style: ``mesh`` (default for 3D bodies and faces), ``skeleton``, or ``frames`` (default when
            ``reference`` is given: the frame generator ``frame_model`` animates the photo).
        render: also draw the side-by-side video into ``Transfer.video`` (``size`` px cells); implied by
            ``output`` (.mp4 or .gif).
        max_seconds: refuse a video clip longer than this (:func:`estimate_pose`).
        progress: ``progress(stage, fraction)``: ``"pose estimation"`` (video clips), ``"loading"``,
            ``"sampling"`` (the re-enactment), ``"frames"``.
    Returns:
        :class:`Transfer`.
    """

    report = progress or _no_progress
    check_cell_size(size)
    out = _check_video_output(output)
    if (behavior is None) == (samples is None):
        raise InputError("give either a behaviour clip or a number of flow samples, not both and not neither")
    if adapt_steps is not None and behavior is None:
        raise InputError("adapt_steps fits the decoder to a behaviour source; flow samples have none")
    for clip in (target, behavior):
        if clip is not None and is_video(clip):
            report(POSE_STAGE, 0.0)
            estimate_pose(clip, max_seconds=max_seconds)
    report("loading", 0.0)
    style = requested_style(style, reference)
    bundle = _motion_model(model)
    behavior_model(bundle)  # the wrong kind of model fails before any clip is read
    style = style_for(bundle.data_config.layout, style)
    frames_model = ref = None
    if style == "frames":
        name = None if frame_model is None else str(getattr(frame_model, "path", frame_model))
        frames_model, ref = frame_style_inputs(bundle, frame_model=name,
                                               reference=reference, reference_pose=reference_pose,
                                               crop_person=crop_person)
    options = {"character": character, "fps": fps}
    tgt = load_clip(bundle, target, **options)
    report("sampling", 0.0)
    if behavior is not None:
        src = load_clip(bundle, behavior, **options)
        result = transfer_behavior(bundle, src, tgt, source_start=behavior_start, target_frame=target_frame,
                                   horizon=horizon, adapt_steps=ADAPT_STEPS if adapt_steps is None else adapt_steps)
    else:
        result = sample_behaviors(bundle, tgt, num_samples=samples, target_frame=target_frame, horizon=horizon,
                                  seed=seed)
    if ref is not None:
        ref = reference_in_view(transfer_forecast(result), ref, size=ref.image.shape[0], fit_view=fit_view)
    video = path = None
    if render or out is not None:
        report("frames", 0.0)
        video, path = _render(iter_transfer(result, style=style, size=size, frame_model=frames_model,
                                            reference=ref), result.fps, out, frames=result.reenacted.shape[1],
                              progress=report)
    return Transfer(source=result.source, reenacted=result.reenacted, z=result.z, fps=float(result.fps),
                    layout=result.layout, style=style, notes=() if ref is None else tuple(ref.notes), video=video,
                    path=path)


# --- analogy -------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Analogy:
    """A : B :: C : D (``motion2video analogy``).

    Attributes:
        ab: (observed + horizon, ...) A's window then B's. cd: (observed + horizon, ...) C's window then the
            generated D.
        observed: frames of A and C. z: (Z,) the transition's latent.
        fps, layout: as in :class:`Futures`. consecutive: whether A and B were one window of one file.
        video: (T, H, W, 3) uint8 side-by-side video, when rendered; path: where it was written.
    """

    ab: np.ndarray
    cd: np.ndarray
    observed: int
    z: np.ndarray
    fps: float
    layout: str
    consecutive: bool
    video: np.ndarray | None = field(default=None, repr=False)
    path: Path | None = None

    @property
    def motion(self) -> Motion | FaceMotion:
        """C then the generated D as one :class:`Motion` / :class:`FaceMotion`."""
        return _motions(self.cd[None], self.fps, self.layout, None)[0]


def analogy(model, a: str | Path, b: str | Path, c: str | Path, *, a_start: int = 0, b_start: int | None = None,
            c_start: int = 0, observed: int | None = None, horizon: int | None = None, fps: float | None = None,
            character: str | Path | None = None, render: bool = False, style: str = "skeleton", size: int = 256,
            output: str | Path | None = None) -> Analogy:
    """D = decode(C, E(A, B)): the transition from A to B, applied to C.

    Args:
        model: a latent motion model (``"mtvae-add"``, ``"mtvae-add-face"``, ...).
        a, b, c: clips (B is often A's file: then B follows A's window unless ``b_start`` says otherwise).
        a_start, b_start, c_start: first frames (file frames). observed, horizon: default the model's.
        render: also draw the side-by-side video (``style`` skeleton / mesh, ``size`` px cells); implied by
            ``output``.
    Returns:
        :class:`Analogy`.
    """

    check_cell_size(size)
    out = _check_video_output(output)
    bundle = _motion_model(model)
    analogy_model(bundle)
    check_style(bundle.data_config.layout, style)
    options = {"character": character, "fps": fps}
    clip_a = load_clip(bundle, a, **options)
    clip_b = clip_a if str(b) == str(a) else load_clip(bundle, b, **options)
    clip_c = load_clip(bundle, c, **options)
    result = analogy_app(bundle, clip_a, clip_b, clip_c, a_start=a_start, b_start=b_start, c_start=c_start,
                         observed=observed, horizon=horizon)
    video = path = None
    if render or out is not None:
        video, path = _render(iter_analogy(result, style=style, size=size), result.fps, out)
    return Analogy(ab=result.ab, cd=result.cd, observed=result.observed, z=result.z, fps=float(result.fps),
                   layout=result.layout, consecutive=result.consecutive, video=video, path=path)


# --- pose ----------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Pose:
    """One person's pose in a photo (T = 1) or a video (``motion2video pose``).

    Attributes:
        points2d: (T, 17, 2) canonical H36M-17 joints in the input's pixels.
        joints3d: (T, 17, 3) the same joints in metres, z up, floor at 0.
        confidence: (T, 17) per-joint visibility in [0, 1] (0 on a video's interpolated frames).
        width, height: the input's size in pixels.
        fps: a video's frame rate (None for a photo).
        people: how many people a photo shows (None for a video).
        source: the input file.
    """

    points2d: np.ndarray
    joints3d: np.ndarray
    confidence: np.ndarray
    width: int
    height: int
    fps: float | None
    people: int | None
    source: Path
    estimate: object = field(repr=False, default=None)

    @property
    def motion(self) -> Motion:
        """A video's 3D joints as an ``h36m-17`` :class:`Motion` at its own rate (every motion function reads it)."""
        if self.fps is None:
            raise InputError("a photo's pose is one frame, not a motion", self.source)
        return Motion(self.joints3d.astype(np.float32), self.fps, "h36m-17", str(self.source))

    def save(self, path: str | Path) -> Path:
        """A photo's reference pose file (``IMAGE.pose.npz``, which ``synthesize`` reads beside the image) or a
        video's motion .npz, as ``motion2video pose -o`` writes them."""

        out = check_output_path(path, (".npz",))
        if self.fps is None:

            return save_reference_pose(out, reference_pose_of(self.estimate))

        return save_video_pose(out, self.estimate)


def estimate_pose(path: str | Path, *, person: str | int = "largest", max_seconds: float | None = None,
                  cache: bool = True) -> Pose:
    """The pose of one person in a photo or a video (BlazePose full, bundled; no download).

    Args:
        path: a photo (.png, .jpg, ...) or a video (.mp4, .avi, .mov, ...).
        person: ``"largest"`` or an index counted left to right.
        max_seconds: refuse a video longer than this (InputError) before estimating anything.
        cache: videos: read and keep the estimate in ``~/.cache/motion2video/pose`` (by the file's hash).
    Returns:
        :class:`Pose`.
    Raises:
        InputError: a missing or unreadable file, another extension, nobody found, a video too long.
    """

    src = Path(path)
    if not src.exists():
        raise InputError("no such file", src)
    if people.is_video(src):
        if max_seconds is not None:

            cap, info = open_video(src)
            cap.release()
            seconds = (info.frames or 0) / info.fps
            if seconds > max_seconds:
                raise InputError(f"the video is {seconds:.1f} s long; at most {max_seconds:g} s is taken", src)
        pose = people.video_pose(src, person=person, cache=None if cache else False)
        return Pose(points2d=pose.points2d, joints3d=pose.joints3d, confidence=pose.confidence, width=pose.width,
                    height=pose.height, fps=float(pose.fps), people=None, source=src, estimate=pose)
    if not people.is_image(src):
        raise InputError(f"unsupported input extension {src.suffix or '(none)'!r}: a photo (.png, .jpg, ...) or a "
                         "video (.mp4, .avi, .mov, ...)", src)
    photo = people.photo_pose(src, person=person)
    p = photo.pose
    return Pose(points2d=p.points2d[None], joints3d=p.joints3d[None], confidence=p.confidence[None], width=p.width,
                height=p.height, fps=None, people=photo.people, source=src, estimate=p)
