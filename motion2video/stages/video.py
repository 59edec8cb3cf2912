"""Write video: the layouts every application shares, on top of :mod:`motion2video.video` (H.264 mp4 / GIF
writing, borders, labels, grids).
"""

from __future__ import annotations

import numpy as np

from motion2video.core.errors import InputError
from motion2video.video import add_border, label

CELL_SIZES = (32, 2048)  # the smallest and largest grid cell the applications draw, pixels


def check_cell_size(size: int) -> int:
    """A grid cell's width and height in pixels, within :data:`CELL_SIZES` (InputError otherwise)."""
    if not CELL_SIZES[0] <= size <= CELL_SIZES[1]:
        raise InputError(f"--size must be in {CELL_SIZES[0]}..{CELL_SIZES[1]}, got {size}")
    return int(size)


def mark_segments(frames: np.ndarray, segments: list[tuple[int, tuple[int, int, int], str]], *,
                  border: int = 4) -> np.ndarray:
    """Frame consecutive segments of a clip with their own border colour and label.

    Args:
        frames: (T, H, W, 3) uint8.
        segments: (number of frames, RGB border colour, text) per segment; the counts must sum to T.
    """
    if sum(n for n, _, _ in segments) != frames.shape[0]:
        raise ValueError(f"segments cover {sum(n for n, _, _ in segments)} frames, the clip has {frames.shape[0]}")
    parts, start = [], 0
    for n, colour, text in segments:
        part = add_border(frames[start:start + n], colour, border)
        parts.append(label(part, text, inset=border))
        start += n
    return np.concatenate(parts, axis=0)
