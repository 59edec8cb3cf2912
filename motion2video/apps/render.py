"""Motion file -> structure video: what ``motion2video render`` does, as a plain function.

Every check that can fail on user input runs BEFORE anything is rendered or written, and the video is written
atomically, so bad input never leaves a partial file behind. Frames stream from the renderer to the encoder
in chunks (:func:`iter_frames`), so memory does not grow with the clip's length.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from motion2video.core.atomic import check_output_path
from motion2video.core.errors import InputError
from motion2video.formats.io import load_motion, resample_motion
from motion2video.core.motion import FaceMotion, Motion
from motion2video.formats.mocap import is_deepmimic_file
from motion2video.formats.video import VIDEO_SUFFIXES
from motion2video.pose.files import pose_motion_3d
from motion2video.stages.people import is_video, video_pose

STYLES = ("skeleton", "heatmap", "mesh", "face")
MIN_SIZE, MAX_SIZE = 32, 2048
CHUNK = 32  # frames per progress-bar step


@dataclass(frozen=True)
class RenderRequest:
    """Everything ``render`` needs.

    Attributes:
        input: the motion file (see :func:`motion2video.formats.io.load_motion`), or a video of a person, whose
            pose is estimated (and cached, :func:`motion2video.stages.people.video_pose`) and drawn.
        output: the .mp4 or .gif to write.
        style: one of :data:`STYLES`.
        size: frame width and height in pixels, 32..2048.
        fps: output frame rate (the motion is resampled to it); None keeps the clip's rate. An OpenPose
            folder (or JSON file) has no rate of its own: ``fps`` is then its true rate (default 25).
        start, frames: the frame range to render, counted at the output rate.
        palette: skeleton palette, ``"leftright"`` or ``"openpose"``.
        progress: show a progress bar.
        character: the character file of a DeepMimic motion file (None: found beside it, else the standard).
        rig_map: the rig map file of a BVH whose joint names do not tell the body points.
        input_fps: the input's true frame rate, for files that state none (joint arrays) or a wrong one.

    A joint array of K clips ``(K, T, J, 3)`` renders as one grid of K cells (skeleton style, one camera).
    """

    input: str
    output: str
    style: str = "skeleton"
    size: int = 256
    fps: float | None = None
    start: int = 0
    frames: int | None = None
    palette: str = "leftright"
    progress: bool = False
    character: str | None = None
    rig_map: str | None = None
    input_fps: float | None = None


@dataclass(frozen=True)
class RenderResult:
    path: Path
    num_frames: int
    width: int
    height: int
    fps: float


def check_size(size: int) -> int:
    if not MIN_SIZE <= int(size) <= MAX_SIZE:
        raise InputError(f"frame size must be between {MIN_SIZE} and {MAX_SIZE} pixels, got {size}")
    return int(size)


def _progress_bar(total: int, enabled: bool, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, unit="frame", desc=desc, disable=not enabled, leave=False)


def check_style(motion: Motion | FaceMotion, style: str) -> None:
    """Raise InputError when ``style`` cannot draw ``motion`` (see :func:`render_motion`)."""
    if style not in STYLES:
        raise InputError(f"unknown style {style!r}; choose one of {', '.join(STYLES)}")
    is_face = isinstance(motion, FaceMotion)
    if style == "face" and not is_face:
        raise InputError("style 'face' needs a face motion (Live Link Face .csv or FaceMotion .npz); "
                         "this is a body motion", motion.source)
    if style != "face" and is_face:
        raise InputError(f"style {style!r} needs a body motion; this is a face motion (use --style face)",
                         motion.source)
    if style == "mesh" and (motion.dim != 3 or motion.skeleton != "h36m-17"):
        raise InputError(f"style 'mesh' needs 3D h36m-17 joints, got {motion.skeleton} with D={motion.dim}",
                         motion.source)


def iter_frames(motion: Motion | FaceMotion, *, style: str, size: int, palette: str = "leftright",
                progress: bool = False) -> Iterator[np.ndarray]:
    """Render a motion in one style, chunk by chunk: the streaming form of :func:`render_motion`.

    The style is checked at once (InputError before any frame is drawn); the frames are drawn lazily, so
    only one chunk (about :data:`CHUNK` frames, or the mesh renderer's batch) is in memory at a time. The
    renderer (and its GL context, for mesh and face) lives as long as the iterator.

    Args: as :func:`render_motion`.
    Yields:
        (t, size, size, 3) uint8 chunks, ``motion.num_frames`` frames in all. The camera (or 2D framing) is
        fitted once to the whole clip.
    """
    check_style(motion, style)
    return _iter_frames(motion, style, size, palette, progress)


def _iter_frames(motion, style: str, size: int, palette: str, progress: bool) -> Iterator[np.ndarray]:
    from renderers.registry import layout_of, renderer_for

    total = motion.num_frames
    layout = layout_of(motion)
    with _progress_bar(total, progress, f"render {style}") as bar:
        if style in ("skeleton", "heatmap"):
            from motion2video.core.camera import fit_camera, fit_image_framing

            joints = motion.joints
            if motion.dim == 3:
                placement = {"camera": fit_camera(joints, size, size)}
            else:
                placement = {"framing": fit_image_framing(joints, size, size)}
            options = {"palette": palette} if style == "skeleton" else {}
            with renderer_for(layout, style, size=size, **options) as renderer:
                for start in range(0, total, CHUNK):
                    chunk = renderer.draw(joints[start:start + CHUNK], skeleton=motion.skeleton, **placement)
                    bar.update(len(chunk))
                    yield chunk
            return
        with renderer_for(layout, style, size=size) as renderer:  # mesh (body) or face
            for chunk in renderer.iter_draw(motion):
                bar.update(len(chunk))
                yield chunk


def render_motion(motion: Motion | FaceMotion, *, style: str, size: int, palette: str = "leftright",
                  progress: bool = False) -> np.ndarray:
    """Render a motion in one style (all frames in memory; prefer :func:`iter_frames` for long clips).

    Args:
        motion: a canonical 3D body :class:`Motion`, a 2D one (skeleton/heatmap styles only), or a
            :class:`FaceMotion` (face style only).
        style: one of :data:`STYLES`.
        size: square frame size in pixels.
        palette: skeleton palette.
        progress: show a progress bar.
    Returns:
        (T, size, size, 3) uint8 frames. The camera (or 2D framing) is fitted once to the whole clip.
    """
    return np.concatenate(list(iter_frames(motion, style=style, size=size, palette=palette, progress=progress)))


def _joint_futures(path: str, fps: float | None) -> list[Motion] | None:
    """The K clips of a ``(K, T, J, 3)`` joint array (:mod:`motion2video.formats.joint_arrays`); None for any
    other input (including a single ``(T, J, 3)`` array, which renders as one clip)."""
    from motion2video.formats.joint_arrays import is_joint_array, load_joint_futures, read_joint_array
    from motion2video.formats.npz import npz_keys, npz_kind

    p = Path(path)
    if p.suffix.lower() not in (".npy", ".npz") or not p.is_file():
        return None
    keys = npz_keys(p) if p.suffix.lower() == ".npz" else None
    if not is_joint_array(p, keys) or (keys is not None and npz_kind(keys) in ("face", "videopose3d")):
        return None
    if read_joint_array(p).ndim != 4:
        return None
    return load_joint_futures(p, fps=fps)


def iter_futures_grid(futures: list[Motion], *, size: int, palette: str = "leftright") -> Iterator[np.ndarray]:
    """K clips as one grid video drawn the way ``sample`` draws its futures: one camera fitted to every
    clip, each cell framed red and labelled ``sample k``.

    Args:
        futures: K h36m-17 Motions (3D), any lengths (a shorter cell holds its last frame).
    Yields:
        (t, H, W, 3) uint8 chunks of the grid.
    """
    from motion2video.core.camera import fit_camera
    from motion2video.formats.video import RED, add_border, iter_grid
    from renderers.registry import renderer_for

    camera = fit_camera(np.concatenate([m.joints.reshape(-1, 3) for m in futures]), size, size, margin=0.1)
    labels = [f"sample {k + 1}" for k in range(len(futures))]

    def cell(renderer, motion: Motion) -> Iterator[np.ndarray]:
        for start in range(0, motion.num_frames, CHUNK):
            yield add_border(renderer.draw(motion.joints[start:start + CHUNK], skeleton=motion.skeleton,
                                           camera=camera), RED)

    with renderer_for("body3d", "skeleton", size=size, palette=palette) as renderer:
        yield from iter_grid([cell(renderer, m) for m in futures], labels)


def video_motion(path: Path, *, style: str, input_fps: float | None) -> Motion:
    """The person of a video as an ``h36m-17`` Motion (3D joints, metres, z up) at the video's own rate: the pose
    estimated once and cached by the file's hash (:func:`motion2video.stages.people.video_pose`); one note on
    stderr says whether it was estimated or read from the cache."""
    if input_fps is not None:
        raise InputError("a video has its own frame rate; --input-fps is for files without one", path)
    if style == "face":
        raise InputError("a video gives body motion; --style face draws face captures (.csv, face .npz)", path)
    pose = video_pose(path, note=lambda line: print(f"note: {line}", file=sys.stderr))
    return pose_motion_3d(pose, path)


def render_file(request: RenderRequest) -> RenderResult:
    """Load ``request.input``, render it and write ``request.output``; see :class:`RenderRequest`."""
    from motion2video.formats.video import VideoWriter

    out = check_output_path(request.output, VIDEO_SUFFIXES)
    size = check_size(request.size)
    if request.style not in STYLES:
        raise InputError(f"unknown style {request.style!r}; choose one of {', '.join(STYLES)}")
    if request.fps is not None and not request.fps > 0:
        raise InputError(f"--fps must be positive, got {request.fps}")
    if request.input_fps is not None and not request.input_fps > 0:
        raise InputError(f"--input-fps must be positive, got {request.input_fps}")
    src = Path(request.input)
    input_fps = request.input_fps
    if (input_fps is None and request.fps is not None and (src.is_dir() or src.suffix.lower() == ".json")
            and not (src.is_file() and is_deepmimic_file(src))):
        # OpenPose keypoints carry no frame rate: --fps is the rate of the video they came from.
        input_fps = float(request.fps)
    video = is_video(src)
    futures = None if video else _joint_futures(request.input, input_fps)
    if futures is not None:
        if request.style != "skeleton":
            raise InputError(f"a joint array of {len(futures)} clips renders as a skeleton grid only, not "
                             f"--style {request.style}", request.input)
        if request.fps is not None:
            futures = [resample_motion(m, float(request.fps)) for m in futures]
        if request.start != 0 or request.frames is not None:
            futures = [m.slice(request.start, request.frames) for m in futures]
        motion = futures[0]
        frames = iter_futures_grid(futures, size=size, palette=request.palette)
    else:
        if video:
            motion = video_motion(src, style=request.style, input_fps=request.input_fps)
        else:
            motion = load_motion(src, fps=input_fps, character=request.character, rig_map=request.rig_map)
        if request.fps is not None:
            motion = resample_motion(motion, float(request.fps))
        if request.start != 0 or request.frames is not None:
            motion = motion.slice(request.start, request.frames)
        frames = iter_frames(motion, style=request.style, size=size, palette=request.palette,
                             progress=request.progress)
    with VideoWriter(out, motion.fps) as writer:
        for chunk in frames:
            writer.write(chunk)
    return RenderResult(path=writer.path, num_frames=writer.num_frames, width=writer.width,
                        height=writer.height, fps=float(motion.fps))
