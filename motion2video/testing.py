"""Helpers for tests and benchmarks: golden-frame comparison and a synthetic human-like motion.

Golden frames (in the spirit of aitviewer's test utilities, but a missing golden FAILS instead of
skipping)::

    assert_frames_match(frames, GOLDEN / "skeleton_walk", tolerance=1, metric="max")

- Goldens are PNG files ``frame_000.png``, ``frame_001.png``, ... in ``golden_dir``.
- ``metric="max"``: the largest absolute difference of any channel of any pixel, in grey levels (0..255),
  must be <= ``tolerance`` (skeleton and heatmap goldens use 1).
- ``metric="rel_l1"``: ``sum|actual - golden| / sum|golden|`` per frame must be <= ``tolerance`` (mesh
  goldens use 2e-2).
- On failure the failing frames are written as ``actual_XXX.png`` and ``diff_XXX.png`` (the absolute
  difference, maximum over channels, stretched so the largest difference is white) to ``out_dir``, or
  ``$MOTION2VIDEO_TEST_OUTPUT/<name>``, or ``./test_output/<name>``; the AssertionError gives the numbers
  and the paths.
- ``UPDATE_GOLDEN=1`` in the environment (re)writes the goldens instead of comparing (stale
  ``frame_*.png`` beyond the new frame count are removed).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2video.motion import Motion
from motion2video.video import read_image, write_image

METRICS = ("max", "rel_l1")
_FRAME_RE = re.compile(r"^frame_(\d+)\.png$")
REGENERATE_HINT = "regenerate with UPDATE_GOLDEN=1 (e.g. `UPDATE_GOLDEN=1 python -m pytest TEST` or `make golden`)"


@dataclass(frozen=True)
class GoldenResult:
    """What :func:`assert_frames_match` did.

    Attributes:
        updated: True when the goldens were (re)written (UPDATE_GOLDEN=1) instead of compared.
        errors: per-frame error in the chosen metric (empty when updated).
        golden_dir: the golden directory.
    """

    updated: bool
    errors: tuple[float, ...]
    golden_dir: Path


def update_requested() -> bool:
    """True when the environment asks to (re)write goldens (UPDATE_GOLDEN=1 / true / yes)."""
    return os.environ.get("UPDATE_GOLDEN", "").strip().lower() in ("1", "true", "yes")


def frame_error(actual: np.ndarray, golden: np.ndarray, metric: str) -> float:
    """Error between two (H, W, 3) uint8 images in ``metric`` (see the module docstring).

    ``rel_l1`` of an all-zero golden is 0 when the actual image is also all zero, else infinity.
    """
    a = np.asarray(actual, np.float64)
    b = np.asarray(golden, np.float64)
    diff = np.abs(a - b)
    if metric == "max":
        return float(diff.max()) if diff.size else 0.0
    if metric == "rel_l1":
        total = float(np.abs(b).sum())
        num = float(diff.sum())
        if total == 0.0:
            return 0.0 if num == 0.0 else float("inf")
        return num / total
    raise ValueError(f"unknown metric {metric!r}; choose one of {', '.join(METRICS)}")


def diff_image(actual: np.ndarray, golden: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 grey image of |actual - golden| (max over channels), stretched so the largest
    difference is 255 (all black when identical)."""
    diff = np.abs(actual.astype(np.int16) - golden.astype(np.int16)).max(axis=-1).astype(np.float64)  # (H, W)
    peak = diff.max()
    grey = np.zeros_like(diff) if peak == 0 else diff * (255.0 / peak)
    grey = np.round(grey).astype(np.uint8)
    return np.repeat(grey[..., None], 3, axis=-1)


def _output_dir(out_dir: str | Path | None, name: str) -> Path:
    if out_dir is not None:
        return Path(out_dir)
    base = os.environ.get("MOTION2VIDEO_TEST_OUTPUT")
    return (Path(base) if base else Path("test_output")) / name


def _golden_frames(golden_dir: Path) -> dict[int, Path]:
    frames = {}
    for p in golden_dir.iterdir():
        m = _FRAME_RE.match(p.name)
        if m:
            frames[int(m.group(1))] = p
    return frames


def assert_frames_match(
    frames: np.ndarray,
    golden_dir: str | Path,
    *,
    tolerance: float,
    metric: str = "max",
    name: str | None = None,
    out_dir: str | Path | None = None,
) -> GoldenResult:
    """Compare frames with stored golden PNGs (or rewrite them when UPDATE_GOLDEN=1).

    Args:
        frames: (T, H, W, 3) or (H, W, 3) uint8 RGB.
        golden_dir: directory of ``frame_000.png`` ...
        tolerance: largest allowed per-frame error in ``metric``.
        metric: ``"max"`` (grey levels) or ``"rel_l1"`` (fraction).
        name: name of the comparison in messages and in the default output directory (default: the
            golden directory's name).
        out_dir: where ``actual_XXX.png`` / ``diff_XXX.png`` go on failure.
    Returns:
        A :class:`GoldenResult`.
    Raises:
        AssertionError: a frame differs by more than ``tolerance``, the frame count or size differs, or the
            golden directory / a golden frame is missing (never skipped).
    """
    if metric not in METRICS:
        raise ValueError(f"unknown metric {metric!r}; choose one of {', '.join(METRICS)}")
    clip = np.asarray(frames)
    if clip.ndim == 3:
        clip = clip[None]
    if clip.ndim != 4 or clip.shape[-1] != 3 or clip.dtype != np.uint8 or clip.shape[0] < 1:
        raise ValueError(f"frames must be (T, H, W, 3) or (H, W, 3) uint8, got {clip.shape} {clip.dtype}")
    golden_dir = Path(golden_dir)
    name = name or golden_dir.name

    if update_requested():
        golden_dir.mkdir(parents=True, exist_ok=True)
        for t, frame in enumerate(clip):
            write_image(golden_dir / f"frame_{t:03d}.png", frame)
        for index, path in _golden_frames(golden_dir).items():
            if index >= clip.shape[0]:
                path.unlink()
        return GoldenResult(True, (), golden_dir)

    if not golden_dir.is_dir():
        raise AssertionError(f"{name}: golden directory {golden_dir} does not exist; {REGENERATE_HINT}")
    stored = _golden_frames(golden_dir)
    missing = [t for t in range(clip.shape[0]) if t not in stored]
    extra = sorted(t for t in stored if t >= clip.shape[0])
    if missing or extra:
        raise AssertionError(
            f"{name}: {clip.shape[0]} frames rendered but {golden_dir} has golden frames {sorted(stored)} "
            f"(missing {missing}, extra {extra}); {REGENERATE_HINT}")

    out = _output_dir(out_dir, name)
    errors: list[float] = []
    failures: list[str] = []
    written: list[Path] = []
    for t, frame in enumerate(clip):
        golden = read_image(stored[t])
        if golden.shape != frame.shape:
            errors.append(float("inf"))
            written.append(_write_failure(out, t, frame, None))
            failures.append(f"frame {t}: size {frame.shape[1]}x{frame.shape[0]} vs golden "
                            f"{golden.shape[1]}x{golden.shape[0]}")
            continue
        err = frame_error(frame, golden, metric)
        errors.append(err)
        if err > tolerance:
            written.append(_write_failure(out, t, frame, golden))
            failures.append(f"frame {t}: {metric} {err:.6g} > {tolerance:g}")
    if failures:
        raise AssertionError(
            f"{name}: {len(failures)} of {clip.shape[0]} frames differ from {golden_dir}: "
            + "; ".join(failures) + f". Actual and diff images written to {out} ({', '.join(p.name for p in written)}"
            f"). If the change is intended, {REGENERATE_HINT}")
    return GoldenResult(False, tuple(errors), golden_dir)


def _write_failure(out: Path, t: int, frame: np.ndarray, golden: np.ndarray | None) -> Path:
    """Write actual_XXX.png (and diff_XXX.png when sizes match); returns the actual image's path."""
    actual_path = write_image(out / f"actual_{t:03d}.png", frame)
    if golden is not None:
        write_image(out / f"diff_{t:03d}.png", diff_image(frame, golden))
    return actual_path


# --- synthetic motion ---------------------------------------------------------------------------------

# Rest pose of the canonical H36M-17 skeleton: metres, z up, facing -y, the body's left at +x.
_HIP_X, _SHOULDER_X = 0.11, 0.18
_PELVIS_Z, _THIGH, _SHIN = 0.95, 0.43, 0.43
_UPPER_ARM, _FOREARM = 0.28, 0.25


def _swing(angle: np.ndarray) -> np.ndarray:
    """(T,) angles (radians, positive = forward, towards -y) -> (T, 3) unit vectors hanging down."""
    return np.stack([np.zeros_like(angle), -np.sin(angle), -np.cos(angle)], axis=-1)


def synthetic_walk(num_frames: int = 60, *, fps: float = 30.0, seed: int = 0) -> Motion:
    """A human-like H36M-17 walking-in-place motion that slowly turns, for tests and benchmarks.

    Legs and arms swing in opposition at ~1 stride per second, knees and elbows bend, the pelvis bobs and
    the whole body yaws by up to ~35 degrees. ``seed`` changes the phase, cadence and turn (deterministic).

    Returns:
        A Motion with joints (num_frames, 17, 3), world metres, z up, facing -y.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(int(num_frames), dtype=np.float64) / fps  # (T,)
    phase = 2 * np.pi * rng.uniform(0.8, 1.1) * t + rng.uniform(0, 2 * np.pi)  # (T,)
    yaw = rng.uniform(0.3, 0.6) * np.sin(2 * np.pi * 0.2 * t + rng.uniform(0, 2 * np.pi))  # (T,)

    pelvis = np.stack([np.zeros_like(t), np.zeros_like(t), _PELVIS_Z + 0.02 * np.abs(np.cos(phase))], -1)
    joints = np.zeros((t.size, 17, 3))  # (T, 17, 3)
    joints[:, 0] = pelvis
    for side, sign in (("right", -1.0), ("left", 1.0)):
        leg = 0.45 * np.sin(phase) * (1.0 if side == "right" else -1.0)  # hip flexion
        knee_bend = 0.6 * np.clip(np.sin(phase + (0.0 if side == "right" else np.pi) - 0.8), 0, None)
        hip = pelvis + np.array([sign * _HIP_X, 0.0, -0.03])
        knee = hip + _THIGH * _swing(leg)
        ankle = knee + _SHIN * _swing(leg - knee_bend)
        arm = -0.6 * leg  # arms swing against the same-side leg
        shoulder = pelvis + np.array([sign * _SHOULDER_X, 0.0, 0.48])
        elbow = shoulder + _UPPER_ARM * _swing(arm) + np.array([sign * 0.03, 0.0, 0.0])
        wrist = elbow + _FOREARM * _swing(arm + 0.35 + 0.2 * np.abs(np.sin(phase)))
        ids = (1, 2, 3, 14, 15, 16) if side == "right" else (4, 5, 6, 11, 12, 13)
        for j, value in zip(ids, (hip, knee, ankle, shoulder, elbow, wrist)):
            joints[:, j] = value
    joints[:, 7] = pelvis + np.array([0.0, 0.0, 0.23])  # spine
    joints[:, 8] = pelvis + np.array([0.0, 0.0, 0.48])  # thorax
    joints[:, 9] = pelvis + np.array([0.0, -0.06, 0.64])  # neck / nose
    joints[:, 10] = pelvis + np.array([0.0, -0.01, 0.77])  # head

    # Turn the whole body about the vertical axis through the pelvis.
    c, s = np.cos(yaw), np.sin(yaw)  # (T,)
    rel = joints - pelvis[:, None, :]  # (T, 17, 3)
    x = c[:, None] * rel[..., 0] - s[:, None] * rel[..., 1]
    y = s[:, None] * rel[..., 0] + c[:, None] * rel[..., 1]
    joints = np.stack([x, y, rel[..., 2]], axis=-1) + pelvis[:, None, :]
    return Motion(joints.astype(np.float32), fps=fps, skeleton="h36m-17", source=f"synthetic_walk(seed={seed})",
                  label="walk")
