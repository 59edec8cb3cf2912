"""Procedural face motion: ARKit expression coefficients and head pose as functions of time.

A clip is a list of face modes with durations (``neutral``, ``smile``, ``blink``, ``talk``, ``surprise``,
``frown``, ``nod``, ``turn``); consecutive modes cross-fade over ``blend`` seconds (never before the new
mode starts). On top of every mode run spontaneous blinks, small gaze saccades and a slow head sway, all
drawn from the seed.

Output: :class:`~motion2video.core.motion.FaceMotion` params (T, 58) = 52 coefficients in [0, 1] in
:data:`~motion2video.core.motion.ARKIT_NAMES` order, head rotation (3, axis-angle, radians) and head
translation (3, metres).

Head pose convention (world frame: metres, z up; the head faces -y at rest, its left is +x):
``R = Rz(yaw) @ Rx(pitch) @ Ry(roll)``, stored as the axis-angle vector of ``R``.

- yaw about +z: positive turns the face towards its own left (+x, the image's right in the default view);
- pitch about +x: positive tilts the face down (a nod down);
- roll about +y: positive tilts the top of the head towards its own left (+x).

The translation is a small sway of the head about its rest position, metres, in the same world axes.
The real Live Link Face takes in ``../shared/data/face/livelinkface`` have no head rotation; pair them with
:func:`head_pose_track`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from motion2video.core.rotations import (
    axis_angle_to_matrix, head_euler_to_axis_angle, head_euler_to_matrix, matrix_to_axis_angle,
)
from motion2video.data.procedural import segment_weights, smootherstep
from motion2video.core.errors import InputError
from motion2video.core.motion import ARKIT_NAMES, FACE_DIM, NUM_EXPRESSIONS, FaceMotion

FACE_MODES: tuple[str, ...] = ("neutral", "smile", "blink", "talk", "surprise", "frown", "nod", "turn")
_IDX = {name: i for i, name in enumerate(ARKIT_NAMES)}
YAW, PITCH, ROLL = 0, 1, 2  # columns of the head Euler arrays used here


@dataclass(frozen=True)
class FaceModeSpec:
    """One segment of a procedural face clip.

    Attributes:
        mode: one of :data:`FACE_MODES`.
        seconds: duration, > 0.
        amplitude: scale of the expression and head-motion excursions, > 0.
        speed: time scale of oscillations (nods, turns, syllables), > 0.
    """

    mode: str
    seconds: float
    amplitude: float = 1.0
    speed: float = 1.0

    def __post_init__(self) -> None:
        if self.mode not in FACE_MODES:
            raise InputError(f"unknown face mode {self.mode!r}; known: {', '.join(FACE_MODES)}")
        if not (np.isfinite(self.seconds) and self.seconds > 0):
            raise InputError(f"face mode {self.mode!r}: duration must be a positive number of seconds, "
                             f"got {self.seconds}")
        if not (self.amplitude > 0 and self.speed > 0):
            raise InputError(f"face mode {self.mode!r}: amplitude and speed must be positive")


# --- building blocks --------------------------------------------------------------------------------------

def _set(expr: np.ndarray, values: Mapping[str, float | np.ndarray], scale=1.0) -> None:
    for name, value in values.items():
        expr[:, _IDX[name]] += scale * np.asarray(value)


def _pulses(t: np.ndarray, onsets: np.ndarray, peaks: np.ndarray, *, close: float, hold: float,
            open_: float) -> np.ndarray:
    """Blink-like pulses: smooth rise over ``close`` s, ``hold`` s at the peak, smooth fall over ``open_`` s.

    Args:
        t: (T,) times, seconds. onsets: (N,) pulse start times. peaks: (N,) pulse heights.
    Returns:
        (T,) the maximum over pulses.
    """
    out = np.zeros_like(t)
    for t0, peak in zip(onsets, peaks):
        x = t - t0
        up = smootherstep(x / close)
        down = 1.0 - smootherstep((x - close - hold) / open_)
        out = np.maximum(out, peak * np.minimum(up, down))
    return out


def _poisson_times(rng: np.random.Generator, *, start: float, stop: float, rate: float,
                   min_gap: float) -> np.ndarray:
    """Event times in [start, stop) with exponential gaps of mean 1/rate, at least ``min_gap`` apart."""
    times = []
    t = start + rng.uniform(0.0, 1.0 / rate)
    while t < stop:
        times.append(t)
        t += min_gap + rng.exponential(max(1.0 / rate - min_gap, 1e-3))
    return np.array(times)


def _slow_noise(rng: np.random.Generator, t: np.ndarray, *, amplitude: float, fmin: float = 0.05,
                fmax: float = 0.5, terms: int = 3) -> np.ndarray:
    """Smooth zero-mean wobble: a sum of sinusoids with random frequencies and phases, peak ~``amplitude``."""
    freqs = rng.uniform(fmin, fmax, size=terms)
    phases = rng.uniform(0.0, 2 * np.pi, size=terms)
    weights = rng.uniform(0.5, 1.0, size=terms)
    weights = weights / weights.sum()
    return amplitude * (weights[None, :] * np.sin(2 * np.pi * freqs[None, :] * t[:, None] + phases)).sum(axis=1)


_VISEMES: dict[str, dict[str, float]] = {
    "a": {"jawOpen": 0.6, "mouthLowerDownLeft": 0.3, "mouthLowerDownRight": 0.3, "mouthStretchLeft": 0.1,
          "mouthStretchRight": 0.1},
    "o": {"jawOpen": 0.35, "mouthFunnel": 0.55, "mouthLowerDownLeft": 0.1, "mouthLowerDownRight": 0.1},
    "u": {"jawOpen": 0.12, "mouthPucker": 0.65, "mouthFunnel": 0.25},
    "e": {"jawOpen": 0.25, "mouthStretchLeft": 0.3, "mouthStretchRight": 0.3, "mouthSmileLeft": 0.15,
          "mouthSmileRight": 0.15, "mouthUpperUpLeft": 0.1, "mouthUpperUpRight": 0.1},
    "m": {"jawOpen": 0.04, "mouthClose": 0.3, "mouthPressLeft": 0.3, "mouthPressRight": 0.3,
          "mouthRollLower": 0.2},
}
_VISEME_PROBS = {"a": 0.3, "o": 0.2, "u": 0.12, "e": 0.23, "m": 0.15}


def _talk(rng: np.random.Generator, tau: np.ndarray, *, duration: float, amp: float, speed: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """Irregular syllables: each a viseme with a smooth envelope, random length, height and pauses."""
    expr = np.zeros((tau.shape[0], NUM_EXPRESSIONS))
    euler = np.zeros((tau.shape[0], 3))
    names = list(_VISEME_PROBS)
    probs = np.array([_VISEME_PROBS[n] for n in names])
    t = 0.0
    while t < duration:
        if rng.uniform() < 0.15:  # a pause between words
            t += rng.uniform(0.15, 0.4) / speed
            continue
        length = rng.uniform(0.12, 0.28) / speed
        viseme = _VISEMES[names[rng.choice(len(names), p=probs)]]
        peak = amp * rng.uniform(0.6, 1.0)
        env = peak * np.sin(np.pi * np.clip((tau - t) / (1.3 * length), 0.0, 1.0)) ** 2  # overlaps the next
        _set(expr, viseme, env)
        if rng.uniform() < 0.25:  # emphasis: brows go up and the head dips a little
            expr[:, _IDX["browInnerUp"]] += 0.3 * env
            euler[:, PITCH] += 0.04 * env
        t += length
    euler[:, YAW] += _slow_noise(rng, tau, amplitude=0.05 * amp, fmin=0.2, fmax=0.8)
    euler[:, PITCH] += _slow_noise(rng, tau, amplitude=0.03 * amp, fmin=0.3, fmax=1.0)
    return expr, euler


def _mode_face(mode: str, rng: np.random.Generator, tau: np.ndarray, *, duration: float, amp: float,
               speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Expressions (T, 52) and head (yaw, pitch, roll) (T, 3) of one mode at segment-local times ``tau``."""
    T = tau.shape[0]
    expr = np.zeros((T, NUM_EXPRESSIONS))
    euler = np.zeros((T, 3))
    wobble = 1.0 + 0.08 * np.sin(2 * np.pi * 0.3 * speed * tau + rng.uniform(0, 2 * np.pi))
    if mode == "neutral":
        pass
    elif mode == "smile":
        _set(expr, {"mouthSmileLeft": 0.75, "mouthSmileRight": 0.72, "cheekSquintLeft": 0.4,
                    "cheekSquintRight": 0.38, "eyeSquintLeft": 0.25, "eyeSquintRight": 0.25,
                    "mouthDimpleLeft": 0.2, "mouthDimpleRight": 0.2, "mouthUpperUpLeft": 0.1,
                    "mouthUpperUpRight": 0.1}, amp * wobble)
        euler[:, PITCH] = -0.04 * amp  # chin up a little
    elif mode == "blink":
        onsets = _poisson_times(rng, start=0.0, stop=duration, rate=1.4 * speed, min_gap=0.35)
        pulse = _pulses(tau, onsets, rng.uniform(0.9, 1.0, size=onsets.size), close=0.08, hold=0.03, open_=0.15)
        expr[:, _IDX["eyeBlinkLeft"]] = pulse
        expr[:, _IDX["eyeBlinkRight"]] = 0.97 * pulse
    elif mode == "talk":
        expr, euler = _talk(rng, tau, duration=duration, amp=amp, speed=speed)
    elif mode == "surprise":
        _set(expr, {"browInnerUp": 0.85, "browOuterUpLeft": 0.75, "browOuterUpRight": 0.75, "eyeWideLeft": 0.7,
                    "eyeWideRight": 0.7, "jawOpen": 0.35, "mouthFunnel": 0.15, "mouthLowerDownLeft": 0.15,
                    "mouthLowerDownRight": 0.15}, amp * wobble)
        euler[:, PITCH] = -0.08 * amp  # head goes back
    elif mode == "frown":
        _set(expr, {"browDownLeft": 0.7, "browDownRight": 0.7, "mouthFrownLeft": 0.6, "mouthFrownRight": 0.6,
                    "mouthPressLeft": 0.25, "mouthPressRight": 0.25, "noseSneerLeft": 0.2, "noseSneerRight": 0.2,
                    "mouthShrugLower": 0.25, "eyeSquintLeft": 0.15, "eyeSquintRight": 0.15}, amp * wobble)
        euler[:, PITCH] = 0.05 * amp  # head down a little
    elif mode == "nod":
        euler[:, PITCH] = 0.15 * amp * (1.0 - np.cos(2 * np.pi * 1.4 * speed * tau))  # 0 .. 0.3 rad down
    elif mode == "turn":
        euler[:, YAW] = 0.6 * amp * np.sin(2 * np.pi * 0.3 * speed * tau)  # looks left, then right
        euler[:, ROLL] = 0.05 * amp * np.sin(2 * np.pi * 0.3 * speed * tau)
    else:  # pragma: no cover - FaceModeSpec validated the name
        raise ValueError(mode)
    return expr, euler


def _gaze(rng: np.random.Generator, t: np.ndarray, duration: float) -> np.ndarray:
    """(T, 52) small saccades: the gaze holds a random target, then jumps in 50 ms to the next."""
    expr = np.zeros((t.shape[0], NUM_EXPRESSIONS))
    onsets = np.concatenate([[0.0], _poisson_times(rng, start=0.3, stop=duration, rate=0.7, min_gap=0.4)])
    targets = rng.uniform(-1.0, 1.0, size=(onsets.size, 2)) * np.array([0.3, 0.2])  # (N, 2) x left+, y up+
    gaze = np.zeros((t.shape[0], 2))
    gaze[:] = targets[0]
    for t0, prev, nxt in zip(onsets[1:], targets[:-1], targets[1:]):
        gaze += smootherstep((t - t0) / 0.05)[:, None] * (nxt - prev)
    x, y = gaze[:, 0], gaze[:, 1]
    # Looking to the subject's left: the left eye looks out, the right eye looks in.
    expr[:, _IDX["eyeLookOutLeft"]] = np.maximum(x, 0)
    expr[:, _IDX["eyeLookInRight"]] = np.maximum(x, 0)
    expr[:, _IDX["eyeLookInLeft"]] = np.maximum(-x, 0)
    expr[:, _IDX["eyeLookOutRight"]] = np.maximum(-x, 0)
    expr[:, _IDX["eyeLookUpLeft"]] = expr[:, _IDX["eyeLookUpRight"]] = np.maximum(y, 0)
    expr[:, _IDX["eyeLookDownLeft"]] = expr[:, _IDX["eyeLookDownRight"]] = np.maximum(-y, 0)
    return expr


def head_pose_track(num_frames: int, fps: float, seed: int, *, amplitude: float = 1.0) -> np.ndarray:
    """A plausible head pose track to pair with captured expressions that have no head rotation.

    Slow, smooth wobble (sums of sinusoids of 0.05-0.5 Hz): yaw ~0.2 rad, pitch ~0.08 rad, roll ~0.06 rad
    and a sway of ~5 mm, times ``amplitude``.

    Args:
        num_frames: T, > 0.
        fps: frame rate, > 0.
        seed: the same seed gives the same track.
        amplitude: scale of every excursion.
    Returns:
        (T, 6) float32: axis-angle head rotation (3, radians) and translation (3, metres), the layout of
        ``FaceMotion.params[:, 52:]``.
    """
    if num_frames < 1 or not (np.isfinite(fps) and fps > 0):
        raise InputError(f"head pose track needs num_frames >= 1 and fps > 0, got {num_frames}, {fps}")
    rng = np.random.default_rng([int(seed), 7])
    t = np.arange(num_frames) / float(fps)
    euler = np.stack([_slow_noise(rng, t, amplitude=a * amplitude) for a in (0.2, 0.08, 0.06)], axis=1)
    trans = np.stack([_slow_noise(rng, t, amplitude=a * amplitude) for a in (0.005, 0.004, 0.003)], axis=1)
    return np.concatenate([head_euler_to_axis_angle(euler), trans], axis=1).astype(np.float32)


def _as_face_spec(item) -> FaceModeSpec:
    if isinstance(item, FaceModeSpec):
        return item
    if not (isinstance(item, (tuple, list)) and len(item) == 2):
        raise InputError(f"each face mode must be (name, seconds) or a FaceModeSpec, got {item!r}")
    return FaceModeSpec(str(item[0]), float(item[1]))


def generate_face(
    modes: Sequence[tuple[str, float] | FaceModeSpec],
    *,
    fps: float = 25.0,
    seed: int = 0,
    identity: Mapping[str, float] | None = None,
    blend: float = 0.3,
    blink_rate: float = 0.25,
    gaze: bool = True,
    sway: float = 1.0,
) -> FaceMotion:
    """A procedural face clip.

    Args:
        modes: segments, each ``(mode, seconds)`` or a :class:`FaceModeSpec`.
        fps: frame rate; the clip has ``round(total seconds * fps)`` frames.
        seed: draws syllables, blink times, saccades, sway and a +-10 % amplitude jitter per segment.
        identity: Anny phenotype values in [0, 1] (e.g. ``{"gender": 0.2}``); ``None`` means Anny's
            defaults (an empty dict).
        blend: cross-fade duration at each segment start, seconds.
        blink_rate: spontaneous blinks per second on top of every mode (0 for none).
        gaze: add small eye saccades.
        sway: scale of the slow head wobble and translation sway (0 for a still head).
    Returns:
        FaceMotion with params (T, 58) float32 and label = the mode names joined by ``">"``.
    """
    specs = [_as_face_spec(m) for m in modes]
    if not specs:
        raise InputError("the face mode list is empty")
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be positive, got {fps}")
    if not (blend >= 0 and blink_rate >= 0 and sway >= 0):
        raise InputError("blend, blink_rate and sway must be non-negative")
    ident = dict(identity or {})
    for key, value in ident.items():
        if not (np.isfinite(value) and 0.0 <= value <= 1.0):
            raise InputError(f"identity value {key}={value} must be in [0, 1]")
    durations = np.array([sp.seconds for sp in specs])
    starts = np.concatenate([[0.0], np.cumsum(durations)[:-1]])
    total = float(durations.sum())
    T = int(round(total * fps))
    if T < 1:
        raise InputError(f"the clip is shorter than one frame at {fps} fps")
    t = np.arange(T) / fps
    w = segment_weights(t, starts, blend)  # (T, S)

    expr = np.zeros((T, NUM_EXPRESSIONS))
    euler = np.zeros((T, 3))
    for i, sp in enumerate(specs):
        rng = np.random.default_rng([int(seed), i, 1])
        amp = sp.amplitude * rng.uniform(0.9, 1.1)
        seg_expr, seg_euler = _mode_face(sp.mode, rng, t - starts[i], duration=sp.seconds, amp=amp, speed=sp.speed)
        expr += w[:, i, None] * seg_expr
        euler += w[:, i, None] * seg_euler

    rng = np.random.default_rng([int(seed), 2**20])
    if blink_rate > 0:
        onsets = _poisson_times(rng, start=0.0, stop=total, rate=blink_rate, min_gap=1.0)
        blink = _pulses(t, onsets, rng.uniform(0.85, 1.0, size=onsets.size), close=0.08, hold=0.03, open_=0.15)
        for name in ("eyeBlinkLeft", "eyeBlinkRight"):
            expr[:, _IDX[name]] = np.maximum(expr[:, _IDX[name]], blink)
    if gaze:
        expr += _gaze(rng, t, total)
    sway_pose = head_pose_track(T, fps, int(seed), amplitude=sway * 0.3)  # gentle: 30 % of a free track
    params = np.zeros((T, FACE_DIM))
    params[:, :NUM_EXPRESSIONS] = np.clip(expr, 0.0, 1.0)
    rot = head_euler_to_matrix(euler) @ axis_angle_to_matrix(sway_pose[:, :3].astype(np.float64))
    params[:, NUM_EXPRESSIONS:NUM_EXPRESSIONS + 3] = matrix_to_axis_angle(rot)
    params[:, NUM_EXPRESSIONS + 3:] = sway_pose[:, 3:]
    label = ">".join(sp.mode for sp in specs)
    return FaceMotion(params.astype(np.float32), float(fps), ident, label=label)
