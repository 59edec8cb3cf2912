"""Evaluation pairs posed by real motion: held-out identities moved by the frames of given mocap clips.

``evaluate-frames --poses PATH`` renders, for every clip at PATH (a motion file or a folder of them), a few
windows spread evenly over the clip; each window is rendered with the Anny body renderer exactly as the
training data is (:func:`motion2video.generator.render_data.render_body_window`: background crop, camera yaw and
elevation, light level, the camera fitted over the window) as one of the frame test split's held-out
identities (:func:`motion2video.generator.specs.identities` ``("test", ...)``), with the visible head masks. Frame
0 of a window is the reference, each later frame a target whose truth is its render.

Everything is a pure function of the clips and :class:`PoseEvalSpec` (fixed seeds), so two runs give the same
pairs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion, Motion
from motion2video.generator.specs import (FrameSequences, SequencesWithHeads, background_images, default_spec,
                                          identities)

# Files a --poses folder may hold (body motions); other files (manifest.csv, READMEs, face captures) are
# passed over.
BODY_SUFFIXES = (".bvh", ".txt", ".json", ".npz")


@dataclass(frozen=True)
class PoseEvalSpec:
    """How the real-motion pairs are drawn.

    Attributes:
        image_size: frame size (the model's).
        windows_per_clip: windows per clip, spread evenly from its start to its end.
        frames_per_window: frames per window (frame 0 is the reference): ``frames_per_window - 1`` pairs each.
        window_seconds: each window spreads its frames evenly over this much of the clip (or the whole clip).
        num_identities: held-out identities, used in turn (the frame test split's).
        seed: base seed of the looks (background, camera, light).
    """

    image_size: int = 128
    windows_per_clip: int = 4
    frames_per_window: int = 9
    window_seconds: float = 1.2
    num_identities: int = 8
    seed: int = 0

    def __post_init__(self) -> None:
        if self.windows_per_clip < 1 or self.frames_per_window < 2 or self.num_identities < 1:
            raise ValueError("windows_per_clip >= 1, frames_per_window >= 2 and num_identities >= 1 are needed")
        if not self.window_seconds > 0:
            raise ValueError("window_seconds must be positive")

    @staticmethod
    def for_size(image_size: int, **overrides) -> "PoseEvalSpec":
        """The defaults with the frame test split's window and identity count for ``image_size``."""
        test = default_spec("body", "test", image_size)
        values = dict(image_size=image_size, frames_per_window=test.frames_per_sequence,
                      window_seconds=test.window_seconds, num_identities=test.num_identities, seed=test.seed)
        values.update(overrides)
        return PoseEvalSpec(**values)


def motion_files(path: str | Path) -> list[Path]:
    """The motion files at ``path``: the file itself, or a folder's body motion files (:data:`BODY_SUFFIXES`,
    recursively, sorted, reference ``*.pose.npz`` files left out). Raises InputError when there are none."""
    path = Path(path)
    if not path.exists():
        raise InputError("no such file or directory", path)
    if path.is_file():
        return [path]
    files = sorted(p for p in path.rglob("*") if p.is_file() and p.suffix.lower() in BODY_SUFFIXES
                   and not p.name.endswith(".pose.npz"))
    if not files:
        raise InputError(f"no motion files ({', '.join(BODY_SUFFIXES)}) in this folder", path)
    return files


def load_body_clips(path: str | Path, *,
                    on_skip: Callable[[Path, str], object] | None = None) -> list[tuple[str, Motion]]:
    """(name, motion) for every clip at ``path``, each a 3D canonical (h36m-17) body motion.

    A single file that is not one raises InputError. In a folder, files that are not (face motions, unreadable
    or 2D files, text files that are no motion) are passed over, each reported to ``on_skip(file, why)``, and
    an error is raised when nothing is left.
    """
    from motion2video.formats.io import load_motion

    path = Path(path)
    clips = []
    for file in motion_files(path):
        try:
            motion = load_motion(file)
            if isinstance(motion, FaceMotion):
                raise InputError("a face motion; --poses needs body motions", file)
            if motion.skeleton != "h36m-17" or motion.dim != 3:
                raise InputError(f"--poses needs 3D body motions on the canonical skeleton, got {motion.skeleton} "
                                 f"with {motion.dim}D joints", file)
            if motion.num_frames < 2:
                raise InputError("the clip has fewer than 2 frames", file)
        except InputError as err:
            if path.is_file():
                raise
            if on_skip is not None:
                on_skip(file, str(err))
            continue
        name = file.name if path.is_file() else file.relative_to(path).as_posix()
        clips.append((name, motion))
    if not clips:
        raise InputError("no body motions in this folder", path)
    return clips


def window_frames(num_frames: int, fps: float, spec: PoseEvalSpec) -> np.ndarray:
    """(windows, frames) source frame indices: ``spec.windows_per_clip`` windows of ``spec.window_seconds``
    (or the whole clip) with evenly spaced starts from the first frame to the last possible one, each with
    ``spec.frames_per_window`` evenly spread frames (rounded to source frames)."""
    span = min(num_frames - 1, int(round(spec.window_seconds * fps)))
    starts = np.round(np.linspace(0, num_frames - 1 - span, spec.windows_per_clip)).astype(np.int64)
    offsets = np.round(np.linspace(0, span, spec.frames_per_window)).astype(np.int64)
    return starts[:, None] + offsets[None, :]


def render_posed_sequences(clips: list[tuple[str, Motion]], spec: PoseEvalSpec, *,
                           on_window: Callable[[int], object] | None = None) -> SequencesWithHeads:
    """Render every window of every clip (:func:`window_frames`) as the held-out identities in turn; window
    ``i`` draws its look from ``np.random.default_rng([spec.seed, 3, i])``. The sequences' ``clip`` holds the
    clip names, ``start`` each window's first source frame."""
    from motion2video.generator.render_data import render_body_window

    people = identities("test", spec.num_identities, seed=spec.seed)
    pool = background_images()
    images, points, masks, heads, names, starts, who, uvs, seen = [], [], [], [], [], [], [], [], []
    for name, motion in clips:
        for frames in window_frames(motion.num_frames, motion.fps, spec):
            i = len(images)
            rng = np.random.default_rng([spec.seed, 3, i])
            window = Motion(motion.joints[frames], motion.fps, source=motion.source)
            out = render_body_window(window, people[i % len(people)], rng, pool, spec.image_size, head=True,
                                     vertices=True)
            images.append(out.images)
            points.append(out.points)
            masks.append(out.masks)
            heads.append(out.head_masks)
            uvs.append(out.vertex_uv.astype(np.float16))
            seen.append(out.vertex_visible)
            names.append(name)
            starts.append(int(frames[0]))
            who.append(i % len(people))
            if on_window is not None:
                on_window(1)
    seqs = FrameSequences(domain="body", images=np.stack(images), points=np.stack(points), structure_images=None,
                          identity=np.asarray(who, np.int64), clip=np.asarray(names),
                          start=np.asarray(starts, np.int64), masks=np.stack(masks), vertex_uv=np.stack(uvs),
                          vertex_visible=np.stack(seen))
    return SequencesWithHeads(seqs, np.stack(heads))
