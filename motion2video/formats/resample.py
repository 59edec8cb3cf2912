"""Frame-rate conversion of sampled signals (joint positions, face parameters)."""

from __future__ import annotations

import numpy as np


def resample_linear(values: np.ndarray, fps: float, target_fps: float) -> np.ndarray:
    """Resample a uniformly sampled signal to another frame rate by linear interpolation in time.

    Linear interpolation is sound for joint positions and blend-shape weights at the rates used here
    (it is not for rotations, which this project never resamples).

    Args:
        values: (T, ...) samples at ``fps``; sample ``t`` is at time ``t / fps``.
        fps: source rate, > 0.
        target_fps: output rate, > 0.
    Returns:
        (T', ...) float64 samples at times ``k / target_fps`` for ``k = 0 .. floor((T - 1) * target_fps / fps)``
        (the output never extrapolates past the last input sample).
    """
    if fps <= 0 or target_fps <= 0:
        raise ValueError(f"frame rates must be positive, got fps={fps}, target_fps={target_fps}")
    values = np.asarray(values, dtype=np.float64)
    num_in = values.shape[0]
    if num_in == 0:
        raise ValueError("cannot resample an empty signal")
    # A small tolerance keeps e.g. 120 -> 30 fps from losing the last frame to rounding.
    num_out = int(np.floor((num_in - 1) * target_fps / fps + 1e-9)) + 1
    src = np.arange(num_out) * (fps / target_fps)  # (T',) positions in input frames
    lo = np.minimum(np.floor(src).astype(np.int64), num_in - 1)  # (T',)
    hi = np.minimum(lo + 1, num_in - 1)
    w = (src - lo).reshape((-1,) + (1,) * (values.ndim - 1))  # (T', 1, ...)
    return values[lo] * (1.0 - w) + values[hi] * w


def round_fps(fps: float) -> float:
    """Snap a rate computed from a rounded frame time (1 / 0.0083333 s = 120.0005) to the integer it
    means, when within 0.1% of one; other rates are returned unchanged."""
    nearest = round(fps)
    if nearest > 0 and abs(fps - nearest) <= 1e-3 * nearest:
        return float(nearest)
    return float(fps)
