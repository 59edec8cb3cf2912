"""Write video: the layouts every application shares, on top of :mod:`motion2video.formats.video` (H.264 mp4 / GIF
writing, borders, labels, grids), and the checks of the grid applications' outputs (video, npz, BVH folder).
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from motion2video.core.atomic import check_output_path
from motion2video.core.errors import InputError
from motion2video.formats.bvh_write import check_bvh_dir
from motion2video.formats.video import VIDEO_SUFFIXES, add_border, label

CELL_SIZES = (32, 2048)  # the smallest and largest grid cell the applications draw, pixels


def check_cell_size(size: int) -> int:
    """A grid cell's width and height in pixels, within :data:`CELL_SIZES` (InputError otherwise)."""
    if not CELL_SIZES[0] <= size <= CELL_SIZES[1]:
        raise InputError(f"--size must be in {CELL_SIZES[0]}..{CELL_SIZES[1]}, got {size}")
    return int(size)


def check_video_and_npz(output: str | Path, npz: str | Path | None) -> Path:
    """Validate ``-o OUT.mp4|.gif`` and an optional ``--npz OUT.npz`` before any work; returns the video path."""
    out = check_output_path(output, VIDEO_SUFFIXES)
    if npz is not None:
        check_output_path(npz, (".npz",))
    return out


def check_bvh_output(folder: str | Path | None, layout: str) -> Path | None:
    """Validate ``--bvh DIR`` for a model of ``layout`` before any work (InputError unless 3D body motion)."""
    out = check_bvh_dir(folder)
    if out is not None and layout != "body3d":
        raise InputError(f"--bvh writes 3D body motion; this model's output is {layout}")
    return out


def mark_segments(frames: np.ndarray, segments: list[tuple[int, tuple[int, int, int], str]], *,
                  border: int = 4) -> np.ndarray:
    """Frame consecutive segments of a clip with their own border colour and label.

    Args:
        frames: (T, H, W, 3) uint8.
        segments: (number of frames, RGB border colour, text) per segment; the counts must sum to T.
    """
    if sum(n for n, _, _ in segments) != frames.shape[0]:
        raise ValueError(f"segments cover {sum(n for n, _, _ in segments)} frames, the clip has {frames.shape[0]}")
    return np.concatenate(list(iter_mark_segments([frames], segments, border=border)))


def iter_mark_segments(chunks: Iterable[np.ndarray], segments: list[tuple[int, tuple[int, int, int], str]], *,
                       border: int = 4, corner: str = "top-left") -> Iterator[np.ndarray]:
    """:func:`mark_segments` on a stream of (t, H, W, 3) chunks; yields the marked chunks (split at the
    segment boundaries), the text in ``corner`` (:func:`motion2video.formats.video.label`). Raises ValueError when
    the stream is longer than the segments."""
    bounds = np.cumsum([n for n, _, _ in segments])
    done = 0
    for chunk in chunks:
        while len(chunk):
            k = int(np.searchsorted(bounds, done, side="right"))
            if k >= len(segments):
                raise ValueError(f"segments cover {int(bounds[-1])} frames, the clip has more")
            take = min(len(chunk), int(bounds[k]) - done)
            _, colour, text = segments[k]
            yield label(add_border(chunk[:take], colour, border), text, inset=border, corner=corner)
            chunk, done = chunk[take:], done + take
