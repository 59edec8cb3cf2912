"""Temporal smoothing of video landmarks: the One-Euro filter with MediaPipe's pose settings.

One-Euro (Casiez et al., CHI 2012): a low-pass filter whose cutoff rises with the (low-passed) speed, so slow
motion is smoothed strongly and fast motion lags little. MediaPipe's pose graph
(``pose_landmark_filtering.pbtxt``) filters the image landmarks with min cutoff 0.05 Hz, beta 80, derivative
cutoff 1 Hz, the speed measured in object sizes per second; the world landmarks with min cutoff 0.1, beta 40,
derivative cutoff 1, in metres per second; visibility with an exponential average (alpha 0.1). The derivative
is taken on the raw values. A frame without landmarks resets the filters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OneEuroConfig:
    """One-Euro filter settings (Hz)."""

    min_cutoff: float
    beta: float
    derivative_cutoff: float = 1.0


IMAGE_LANDMARKS = OneEuroConfig(min_cutoff=0.05, beta=80.0)
WORLD_LANDMARKS = OneEuroConfig(min_cutoff=0.1, beta=40.0)
VISIBILITY_ALPHA = 0.1


def _alpha(cutoff: np.ndarray | float, rate: float) -> np.ndarray:
    tau = 1.0 / (2 * np.pi * np.asarray(cutoff, np.float64))
    return 1.0 / (1.0 + tau * rate)


def one_euro(values: np.ndarray, rate: float, config: OneEuroConfig, scale: np.ndarray | None = None
             ) -> np.ndarray:
    """Filter a sequence with the One-Euro filter, every coordinate separately.

    Args:
        values: (T, ...) samples at ``rate`` Hz.
        rate: samples per second.
        config: the filter settings.
        scale: (T,) object size per frame; the speed is measured in sizes per second (None: raw units).
    Returns:
        (T, ...) float64 filtered values (the first frame unchanged).
    """
    x = np.asarray(values, np.float64)
    out = np.empty_like(x)
    out[0] = x[0]
    dx_hat = np.zeros_like(x[0])
    a_d = _alpha(config.derivative_cutoff, rate)
    for t in range(1, len(x)):
        value_scale = 1.0 if scale is None else 1.0 / max(float(scale[t]), 1e-9)
        dx = (x[t] - x[t - 1]) * value_scale * rate  # derivative of the raw values
        dx_hat = a_d * dx + (1 - a_d) * dx_hat
        a = _alpha(config.min_cutoff + config.beta * np.abs(dx_hat), rate)
        out[t] = a * x[t] + (1 - a) * out[t - 1]
    return out


def exponential(values: np.ndarray, alpha: float = VISIBILITY_ALPHA) -> np.ndarray:
    """(T, ...) exponential moving average ``y_t = alpha x_t + (1 - alpha) y_{t-1}`` (y_0 = x_0)."""
    x = np.asarray(values, np.float64)
    out = np.empty_like(x)
    out[0] = x[0]
    for t in range(1, len(x)):
        out[t] = alpha * x[t] + (1 - alpha) * out[t - 1]
    return out


def runs(found: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of True in a (T,) bool array."""
    edges = np.diff(np.concatenate([[0], found.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def smooth_landmarks(xy: np.ndarray, world: np.ndarray, visibility: np.ndarray, size: np.ndarray,
                     found: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MediaPipe's pose smoothing over a tracked video, each run of found frames on its own.

    Args:
        xy: (T, L, 2) image landmarks, pixels; world: (T, L, 3) metres; visibility: (T, L).
        size: (T,) the person's size in pixels (the ROI side), the image filter's object scale.
        found: (T,) frames with landmarks (others are left as they are).
        rate: frames per second.
    Returns:
        smoothed copies of xy, world and visibility.
    """
    xy, world, visibility = (np.array(a, np.float64, copy=True) for a in (xy, world, visibility))
    for start, stop in runs(np.asarray(found, bool)):
        s = slice(start, stop)
        xy[s] = one_euro(xy[s], rate, IMAGE_LANDMARKS, scale=np.asarray(size, np.float64)[s])
        world[s] = one_euro(world[s], rate, WORLD_LANDMARKS)
        visibility[s] = exponential(visibility[s])
    return xy, world, visibility
