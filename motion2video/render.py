"""Motion file -> structure video: what ``motion2video render`` does, as a plain function.

Every check that can fail on user input runs BEFORE anything is rendered or written, and the video is written
atomically, so bad input never leaves a partial file behind.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2video.atomic import check_output_path
from motion2video.errors import InputError
from motion2video.formats.io import load_motion, resample_motion
from motion2video.motion import FaceMotion, Motion
from motion2video.video import VIDEO_SUFFIXES

STYLES = ("skeleton", "heatmap", "mesh", "face")
MIN_SIZE, MAX_SIZE = 32, 2048
CHUNK = 32  # frames per progress-bar step


@dataclass(frozen=True)
class RenderRequest:
    """Everything ``render`` needs.

    Attributes:
        input: the motion file (see :func:`motion2video.io.load_motion`).
        output: the .mp4 or .gif to write.
        style: one of :data:`STYLES`.
        size: frame width and height in pixels, 32..2048.
        fps: output frame rate (the motion is resampled to it); None keeps the clip's rate.
        start, frames: the frame range to render, counted at the output rate.
        palette: skeleton palette, ``"leftright"`` or ``"openpose"``.
        progress: show a progress bar.
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


def render_motion(motion: Motion | FaceMotion, *, style: str, size: int, palette: str = "leftright",
                  progress: bool = False) -> np.ndarray:
    """Render a motion in one style.

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
            chunks = []
            with renderer_for(layout, style, size=size, **options) as renderer:
                for start in range(0, total, CHUNK):
                    chunk = joints[start:start + CHUNK]
                    chunks.append(renderer.draw(chunk, skeleton=motion.skeleton, **placement))
                    bar.update(len(chunk))
            return np.concatenate(chunks)
        with renderer_for(layout, style, size=size) as renderer:  # mesh (body) or face
            return renderer.draw(motion, progress=bar.update)


def render_file(request: RenderRequest) -> RenderResult:
    """Load ``request.input``, render it and write ``request.output``; see :class:`RenderRequest`."""
    from motion2video.video import write_video

    out = check_output_path(request.output, VIDEO_SUFFIXES)
    size = check_size(request.size)
    if request.style not in STYLES:
        raise InputError(f"unknown style {request.style!r}; choose one of {', '.join(STYLES)}")
    if request.fps is not None and not request.fps > 0:
        raise InputError(f"--fps must be positive, got {request.fps}")
    motion = load_motion(request.input)
    if request.fps is not None:
        motion = resample_motion(motion, float(request.fps))
    if request.start != 0 or request.frames is not None:
        motion = motion.slice(request.start, request.frames)
    frames = render_motion(motion, style=request.style, size=size, palette=request.palette,
                           progress=request.progress)
    path = write_video(out, frames, motion.fps)
    return RenderResult(path=Path(path), num_frames=int(frames.shape[0]), width=int(frames.shape[2]),
                        height=int(frames.shape[1]), fps=float(motion.fps))
