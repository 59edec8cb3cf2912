"""Helpers for tests and benchmarks: golden-frame comparison and a synthetic human-like motion.

Golden frames (in the spirit of aitviewer's test utilities, but a missing golden FAILS instead of skipping). The
pytest plugin (:mod:`motion2video.testing.pytest_plugin`, fixture ``golden_frames``) calls :func:`assert_frames_match`;
it can also be called directly::

    assert_frames_match(frames, GOLDEN / "skeleton_walk", tolerance=1, metric="max")

- A golden is a directory of PNG files ``frame_000.png``, ``frame_012.png``, ... named by the frame's index in
  the clip, plus ``golden.json`` recording the clip's frame count, size, fps and the indices kept. Goldens
  written before the manifest existed (PNGs only) still compare; their frame count is the PNG count.
- ``indices`` / ``every``: keep chosen frames of a clip (``indices=(0, 12, 24)``) or every k-th frame
  (``every=6``: 0, 6, 12, ...); default: every frame.
- Checked first, with one message naming every difference: the clip's frame count, frame size and fps (when
  both sides know it) against the manifest; then the stored frame indices; then each golden PNG is read
  (a corrupt PNG or one of another size is a clear failure, not a crash).
- Metrics, per compared frame, each an error that must be <= ``tolerance``:

  - ``"max"``: the largest absolute difference of any channel of any pixel, in grey levels (0..255);
  - ``"rel_l1"``: ``sum|actual - golden| / sum|golden|`` (0 when both are all zero, else inf for a black golden);
  - ``"ssim"``: ``1 - SSIM`` (scikit-image ``structural_similarity`` over the RGB channels, data range 255).

- On failure each failing frame is written as ``actual_XXX.png`` (the actual frame, as is) and ``diff_XXX.png``
  (golden | actual | stretched difference side by side, with the frame's numbers written under them) to
  ``out_dir`` (the plugin's ``--golden-results DIR/<name>``), or ``$MOTION2VIDEO_TEST_OUTPUT/<name>``, or
  ``./test_output/<name>``; the AssertionError gives the numbers and the paths.
- ``update=True`` (``--update-golden``; ``UPDATE_GOLDEN=1`` in the environment when ``update`` is None) (re)writes
  the goldens instead of comparing. A PNG whose pixels did not change is left untouched (byte-identical); stale
  ``frame_*.png`` not among the kept indices are removed.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

from motion2video.core.atomic import write_json
from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion, Motion
from motion2video.formats.video import VIDEO_SUFFIXES, read_image, read_video, write_image

METRICS = ("max", "rel_l1", "ssim")
MANIFEST = "golden.json"
FRAME_RE = re.compile(r"^frame_(\d+)\.png$")
REGENERATE_HINT = ("regenerate with `pytest --update-golden TEST` (or UPDATE_GOLDEN=1; `make golden` in this "
                   "repository)")


@dataclass(frozen=True)
class GoldenResult:
    """What :func:`assert_frames_match` did.

    Attributes:
        updated: True when the goldens were (re)written instead of compared.
        errors: per compared frame, the error in the chosen metric (empty when updated).
        golden_dir: the golden directory.
        indices: the clip's frame indices kept in the golden.
    """

    updated: bool
    errors: tuple[float, ...]
    golden_dir: Path
    indices: tuple[int, ...] = ()


@dataclass(frozen=True)
class GoldenClip:
    """A clip ready for comparison: frames (T, H, W, 3) uint8 RGB, fps (None when unknown), and what it was."""

    frames: np.ndarray
    fps: float | None
    what: str


def update_requested() -> bool:
    """True when the environment asks to (re)write goldens (UPDATE_GOLDEN=1 / true / yes)."""
    return os.environ.get("UPDATE_GOLDEN", "").strip().lower() in ("1", "true", "yes")


# --- metrics (pure functions on (H, W, 3) uint8 images) ----------------------------------------------------

def ssim(actual: np.ndarray, golden: np.ndarray) -> float:
    """Structural similarity of two (H, W, 3) uint8 images (scikit-image, channels averaged, data range 255).

    The window is 7 pixels, or the largest odd size that fits frames smaller than 7 pixels (at least 3).
    """
    from skimage.metrics import structural_similarity

    side = min(actual.shape[0], actual.shape[1])
    win = 7 if side >= 7 else side - (1 - side % 2)
    if win < 3:
        raise ValueError(f"ssim needs frames of at least 3x3 pixels, got {actual.shape[1]}x{actual.shape[0]}")
    return float(structural_similarity(actual, golden, channel_axis=-1, data_range=255, win_size=win))


def frame_error(actual: np.ndarray, golden: np.ndarray, metric: str) -> float:
    """Error between two (H, W, 3) uint8 images in ``metric`` (see the module docstring); larger is worse."""
    a = np.asarray(actual, np.float64)
    b = np.asarray(golden, np.float64)
    if metric == "max":
        return float(np.abs(a - b).max()) if a.size else 0.0
    if metric == "rel_l1":
        total = float(np.abs(b).sum())
        num = float(np.abs(a - b).sum())
        if total == 0.0:
            return 0.0 if num == 0.0 else float("inf")
        return num / total
    if metric == "ssim":
        return 1.0 - ssim(np.asarray(actual), np.asarray(golden))
    raise ValueError(f"unknown metric {metric!r}; choose one of {', '.join(METRICS)}")


def describe_error(metric: str, error: float) -> str:
    """``"max 37"``, ``"rel_l1 0.0312"`` or ``"ssim 0.9124 (1-ssim 0.0876)"``."""
    if metric == "ssim":
        return f"ssim {1.0 - error:.4f} (1-ssim {error:.4g})"
    return f"{metric} {error:.6g}"


def diff_image(actual: np.ndarray, golden: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 grey image of |actual - golden| (max over channels), stretched so the largest
    difference is 255 (all black when identical)."""
    diff = np.abs(actual.astype(np.int16) - golden.astype(np.int16)).max(axis=-1).astype(np.float64)  # (H, W)
    peak = diff.max()
    grey = np.zeros_like(diff) if peak == 0 else diff * (255.0 / peak)
    grey = np.round(grey).astype(np.uint8)
    return np.repeat(grey[..., None], 3, axis=-1)


def select_indices(num_frames: int, *, indices: Sequence[int] | None = None, every: int | None = None) -> tuple[int, ...]:
    """The frame indices of a ``num_frames`` clip to compare: ``indices`` (sorted, distinct, in range), every
    ``every``-th frame from 0, or all frames."""
    if indices is not None and every is not None:
        raise ValueError("give indices or every, not both")
    if every is not None:
        if int(every) < 1:
            raise ValueError(f"every must be >= 1, got {every}")
        return tuple(range(0, num_frames, int(every)))
    if indices is None:
        return tuple(range(num_frames))
    chosen = tuple(sorted({int(i) for i in indices}))
    if not chosen:
        raise ValueError("indices is empty")
    if chosen[0] < 0 or chosen[-1] >= num_frames:
        raise ValueError(f"indices {list(chosen)} out of range for a clip of {num_frames} frames")
    return chosen


# --- the failure picture: golden | actual | diff, with the numbers ------------------------------------------

PANEL_MIN_SIDE = 160  # small frames are enlarged (nearest neighbour, whole pixels) to at least this
PANEL_GAP = 4
PANEL_HEADER = 20
PANEL_LINE = 16
_FONT = cv2.FONT_HERSHEY_SIMPLEX


@dataclass(frozen=True)
class PanelLayout:
    """Where the three images sit in a failure panel: ``boxes[name] = (rows, cols)`` slices for ``"golden"``,
    ``"actual"`` and ``"diff"``; each image is enlarged ``scale`` times; the text lines start at ``text_top``."""

    scale: int
    height: int
    width: int
    boxes: dict
    text_top: int


def panel_layout(height: int, width: int, num_lines: int) -> PanelLayout:
    """Layout of :func:`failure_panel` for (height, width) frames and ``num_lines`` lines of text."""
    scale = max(1, math.ceil(PANEL_MIN_SIDE / max(height, width)))
    h, w = height * scale, width * scale
    rows = slice(PANEL_HEADER, PANEL_HEADER + h)
    boxes = {name: (rows, slice(k * (w + PANEL_GAP), k * (w + PANEL_GAP) + w))
             for k, name in enumerate(("golden", "actual", "diff"))}
    text_top = PANEL_HEADER + h + 4
    return PanelLayout(scale, text_top + num_lines * PANEL_LINE + 4, 3 * w + 2 * PANEL_GAP, boxes, text_top)


def failure_panel(golden: np.ndarray, actual: np.ndarray, lines: Sequence[str]) -> np.ndarray:
    """(H', W', 3) uint8 picture of one failing frame: golden | actual | |actual - golden| (stretched, the gain
    in its title) side by side on dark grey, with ``lines`` of text (the numbers) written underneath."""
    layout = panel_layout(golden.shape[0], golden.shape[1], len(lines))
    panel = np.full((layout.height, layout.width, 3), 40, np.uint8)
    peak = int(np.abs(actual.astype(np.int16) - golden.astype(np.int16)).max())
    titles = {"golden": "golden", "actual": "actual",
              "diff": f"|diff| x{255.0 / peak:.1f}" if peak else "|diff| (none)"}
    images = {"golden": golden, "actual": actual, "diff": diff_image(actual, golden)}
    for name, (rows, cols) in layout.boxes.items():
        big = np.repeat(np.repeat(images[name], layout.scale, axis=0), layout.scale, axis=1)
        panel[rows, cols] = big
        cv2.putText(panel, titles[name], (cols.start + 2, PANEL_HEADER - 6), _FONT, 0.45, (255, 255, 255), 1,
                    cv2.LINE_AA)
    for k, line in enumerate(lines):
        y = layout.text_top + (k + 1) * PANEL_LINE - 4
        cv2.putText(panel, line, (4, y), _FONT, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
    return panel


def _panel_lines(t: int, actual: np.ndarray, golden: np.ndarray, metric: str, error: float,
                 tolerance: float) -> list[str]:
    changed = np.abs(actual.astype(np.int16) - golden.astype(np.int16)).max(axis=-1) > 0  # (H, W)
    numbers = []
    for m in METRICS:
        try:
            numbers.append(describe_error(m, frame_error(actual, golden, m)).split(" (")[0])
        except ValueError:  # SSIM of frames under 3x3 pixels
            numbers.append(f"{m} n/a")
    return [f"frame {t}: {describe_error(metric, error)} > tolerance {tolerance:g}",
            "  ".join(numbers),
            f"{int(changed.sum())} of {changed.size} pixels differ ({100.0 * changed.mean():.1f}%)"]


# --- sources: a frame array, a video file, or a Motion rendered in a style ----------------------------------

def golden_clip(source, *, style: str | None = None, size: int | None = None, palette: str = "leftright",
                fps: float | None = None) -> GoldenClip:
    """Turn what a test wants to compare into frames.

    Args:
        source: (T, H, W, 3) or (H, W, 3) uint8 frames; a ``.mp4`` / ``.gif`` path (read whole, fps from the
            file); or a :class:`Motion` / :class:`FaceMotion`, rendered with
            :func:`motion2video.apps.render.render_motion` (``style`` and ``size`` required; fps from the motion).
        fps: the frame array's fps (ignored for videos and motions, which carry their own).
    """
    if isinstance(source, (Motion, FaceMotion)):
        if style is None or size is None:
            raise ValueError("a Motion is compared after rendering: give style= and size=")
        from motion2video.apps.render import render_motion

        frames = render_motion(source, style=style, size=int(size), palette=palette)
        return GoldenClip(frames, float(source.fps), f"{type(source).__name__} rendered as {style} {size}px")
    if style is not None or size is not None:
        raise ValueError("style= and size= apply to a Motion only")
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if path.suffix.lower() not in VIDEO_SUFFIXES:
            raise ValueError(f"{path}: a video to compare must be one of {', '.join(VIDEO_SUFFIXES)}")
        frames, video_fps = read_video(path)
        return GoldenClip(frames, float(video_fps), f"video {path.name}")
    frames = np.asarray(source)
    if frames.ndim == 3:
        frames = frames[None]
    return GoldenClip(frames, None if fps is None else float(fps), "frames")


# --- goldens on disk -----------------------------------------------------------------------------------------

def golden_frame_files(golden_dir: Path) -> dict[int, Path]:
    """``{frame index: path}`` of the ``frame_*.png`` files in a golden directory."""
    frames = {}
    for p in golden_dir.iterdir():
        m = FRAME_RE.match(p.name)
        if m:
            frames[int(m.group(1))] = p
    return frames


def is_golden_dir(path: Path) -> bool:
    """True for a directory holding a golden (a manifest or at least one ``frame_*.png``)."""
    try:
        return path.is_dir() and ((path / MANIFEST).is_file() or bool(golden_frame_files(path)))
    except OSError:
        return False


def _output_dir(out_dir: str | Path | None, name: str) -> Path:
    if out_dir is not None:
        return Path(out_dir)
    base = os.environ.get("MOTION2VIDEO_TEST_OUTPUT")
    return (Path(base) if base else Path("test_output")) / name


def _fail(name: str, problem: str) -> AssertionError:
    return AssertionError(f"{name}: {problem}")


def _read_manifest(golden_dir: Path, name: str) -> dict | None:
    path = golden_dir / MANIFEST
    if not path.exists():
        return None
    try:
        record = json.loads(path.read_text())
        return {"frames": int(record["frames"]), "width": int(record["width"]), "height": int(record["height"]),
                "fps": None if record.get("fps") is None else float(record["fps"]),
                "indices": [int(i) for i in record["indices"]]}
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise _fail(name, f"cannot read the golden manifest {path} ({type(err).__name__}: {err}); "
                          f"{REGENERATE_HINT}") from None


def _clip_summary(frames: int, width: int, height: int, fps: float | None) -> str:
    rate = "" if fps is None else f" at {fps:g} fps"
    return f"{frames} frames of {width}x{height}{rate}"


def _write_goldens(clip: np.ndarray, fps: float | None, chosen: tuple[int, ...], golden_dir: Path, name: str) -> None:
    if golden_dir.exists() and not golden_dir.is_dir():
        raise _fail(name, f"golden path {golden_dir} is a file, not a directory; remove it or choose another name")
    try:
        golden_dir.mkdir(parents=True, exist_ok=True)
        for t in chosen:
            path = golden_dir / f"frame_{t:03d}.png"
            try:
                unchanged = path.is_file() and np.array_equal(read_image(path), clip[t])
            except InputError:
                unchanged = False  # a corrupt golden is rewritten
            if not unchanged:
                write_image(path, clip[t])
        for index, path in golden_frame_files(golden_dir).items():
            if index not in chosen:
                path.unlink()
        write_json(golden_dir / MANIFEST, {"frames": int(clip.shape[0]), "width": int(clip.shape[2]),
                                           "height": int(clip.shape[1]), "fps": fps, "indices": list(chosen)})
    except (OSError, InputError) as err:
        raise _fail(name, f"cannot write goldens to {golden_dir}: {err}") from None


def assert_frames_match(
    frames: np.ndarray,
    golden_dir: str | Path,
    *,
    tolerance: float,
    metric: str = "max",
    name: str | None = None,
    out_dir: str | Path | None = None,
    indices: Sequence[int] | None = None,
    every: int | None = None,
    fps: float | None = None,
    update: bool | None = None,
) -> GoldenResult:
    """Compare a clip with its golden PNGs (or rewrite them in update mode); see the module docstring.

    Args:
        frames: (T, H, W, 3) or (H, W, 3) uint8 RGB.
        golden_dir: the golden directory (``frame_XXX.png`` + ``golden.json``).
        tolerance: largest allowed per-frame error in ``metric``.
        metric: ``"max"`` (grey levels), ``"rel_l1"`` (fraction) or ``"ssim"`` (1 - SSIM).
        name: name of the comparison in messages and in the default output directory (default: the golden
            directory's name).
        out_dir: where ``actual_XXX.png`` / ``diff_XXX.png`` go on failure.
        indices, every: the frames kept (default all); see :func:`select_indices`.
        fps: the clip's frame rate, checked against the golden's when both are known.
        update: rewrite the goldens; None reads ``UPDATE_GOLDEN`` from the environment.
    Returns:
        A :class:`GoldenResult`.
    Raises:
        AssertionError: the frame count, size or fps differ; a golden is missing, not a directory, corrupt or of
            another size; or a frame differs by more than ``tolerance`` (never skipped).
        ValueError: a programming error (unknown metric, frames not uint8 RGB, bad indices).
    """
    __tracebackhide__ = True  # pytest shows the caller's line and this message, not the checks below
    if metric not in METRICS:
        raise ValueError(f"unknown metric {metric!r}; choose one of {', '.join(METRICS)}")
    clip = np.asarray(frames)
    if clip.ndim == 3:
        clip = clip[None]
    if clip.ndim != 4 or clip.shape[-1] != 3 or clip.dtype != np.uint8 or clip.shape[0] < 1:
        raise ValueError(f"frames must be (T, H, W, 3) or (H, W, 3) uint8, got {clip.shape} {clip.dtype}")
    chosen = select_indices(clip.shape[0], indices=indices, every=every)
    golden_dir = Path(golden_dir)
    name = name or golden_dir.name
    fps = None if fps is None else float(fps)

    if update_requested() if update is None else update:
        _write_goldens(clip, fps, chosen, golden_dir, name)
        return GoldenResult(True, (), golden_dir, chosen)

    if golden_dir.exists() and not golden_dir.is_dir():
        raise _fail(name, f"golden path {golden_dir} is a file, not a directory of frame_*.png; remove it and "
                          f"{REGENERATE_HINT}")
    if not golden_dir.is_dir():
        raise _fail(name, f"golden directory {golden_dir} does not exist; {REGENERATE_HINT}")
    count, height, width = clip.shape[:3]
    manifest = _read_manifest(golden_dir, name)
    if manifest is not None:
        problems = []
        if manifest["frames"] != count:
            problems.append(f"frame count {count} vs {manifest['frames']}")
        if (manifest["width"], manifest["height"]) != (width, height):
            problems.append(f"size {width}x{height} vs {manifest['width']}x{manifest['height']}")
        if fps is not None and manifest["fps"] is not None and not math.isclose(fps, manifest["fps"], rel_tol=1e-6):
            problems.append(f"fps {fps:g} vs {manifest['fps']:g}")
        if problems:
            raise _fail(name, f"the clip ({_clip_summary(count, width, height, fps)}) does not match the golden "
                              f"{golden_dir} ({_clip_summary(manifest['frames'], manifest['width'], manifest['height'], manifest['fps'])}): "
                              f"{'; '.join(problems)}. If the change is intended, {REGENERATE_HINT}")
        if tuple(manifest["indices"]) != chosen:
            raise _fail(name, f"compares frames {list(chosen)} but the golden {golden_dir} keeps frames "
                              f"{manifest['indices']}; {REGENERATE_HINT}")
    stored = golden_frame_files(golden_dir)
    missing = [t for t in chosen if t not in stored]
    extra = sorted(t for t in stored if t not in chosen)
    if missing or extra:
        raise _fail(name, f"compares frames {list(chosen)} of a {count}-frame clip but {golden_dir} has golden "
                          f"frames {sorted(stored)} (missing {missing}, extra {extra}); {REGENERATE_HINT}")

    goldens, corrupt, sized = {}, [], []
    for t in chosen:
        try:
            goldens[t] = read_image(stored[t])
        except InputError:
            corrupt.append(stored[t].name)
            continue
        if goldens[t].shape != clip[t].shape:
            sized.append(f"{stored[t].name} is {goldens[t].shape[1]}x{goldens[t].shape[0]}, not {width}x{height}")
    if corrupt or sized:
        parts = ([f"cannot decode {', '.join(corrupt)} (corrupt PNG)"] if corrupt else []) + \
                ([f"size: {'; '.join(sized)}"] if sized else [])
        raise _fail(name, f"bad golden files in {golden_dir}: {'; '.join(parts)}; {REGENERATE_HINT}")

    out = _output_dir(out_dir, name)
    errors: list[float] = []
    failing: list[tuple[int, float]] = []
    for t in chosen:
        err = frame_error(clip[t], goldens[t], metric)
        errors.append(err)
        if err > tolerance:
            failing.append((t, err))
    if failing:
        details = "; ".join(f"frame {t}: {describe_error(metric, err)}" for t, err in failing)
        pictures = _write_failures(out, clip, goldens, failing, metric, tolerance)
        raise _fail(name, f"{len(failing)} of {len(chosen)} compared frames differ from {golden_dir} by more than "
                          f"{metric} tolerance {tolerance:g}: {details}. {pictures} If the change is intended, "
                          f"{REGENERATE_HINT}")
    return GoldenResult(False, tuple(errors), golden_dir, chosen)


def _write_failures(out: Path, clip: np.ndarray, goldens: dict[int, np.ndarray], failing: list[tuple[int, float]],
                    metric: str, tolerance: float) -> str:
    """Write actual_XXX.png and diff_XXX.png (the failure panel) per failing frame, after removing those of an
    earlier run; returns the sentence naming them (or why they could not be written)."""
    try:
        if out.is_dir():
            for old in list(out.glob("actual_*.png")) + list(out.glob("diff_*.png")):
                old.unlink()
        panels = []
        for t, err in failing:
            write_image(out / f"actual_{t:03d}.png", clip[t])
            lines = _panel_lines(t, clip[t], goldens[t], metric, err, tolerance)
            panels.append(str(write_image(out / f"diff_{t:03d}.png", failure_panel(goldens[t], clip[t], lines)).absolute()))
    except (OSError, InputError) as err:
        return f"(could not write the failure images to {out}: {err})."
    return (f"Golden | actual | diff pictures: {', '.join(panels)} (actual frames beside them as "
            f"actual_XXX.png).")


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


def command_peak_rss_mb(argv: list[str], *, env: dict | None = None, cwd: str | None = None) -> float:
    """Peak resident memory, in MB, of ``python -m motion2video.cli ARGV`` run in a fresh process.

    The child reports its own peak (``VmHWM`` of ``/proc/self/status``, which starts afresh at exec, unlike
    ``ru_maxrss``, which inherits the forking parent's peak) plus ``getrusage``'s ``ru_maxrss`` of its own
    children (ffmpeg): an upper bound of the whole command's peak resident memory. Linux only. Raises
    RuntimeError when the command fails.
    """
    import json
    import os
    import subprocess
    import sys

    code = ("import json, resource, sys\n"
            "from motion2video.cli import main\n"
            "rc = main(sys.argv[1:])\n"
            "hwm = [l for l in open('/proc/self/status') if l.startswith('VmHWM:')][0].split()[1]\n"
            "print(json.dumps({'rc': rc, 'self': int(hwm) / 1024.0, "
            "'children': resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0}))\n")
    result = subprocess.run([sys.executable, "-c", code, *map(str, argv)], capture_output=True, text=True,
                            env={**os.environ, **(env or {})}, cwd=cwd, check=False)
    lines = result.stdout.strip().splitlines()
    if result.returncode != 0 or not lines:
        raise RuntimeError(f"motion2video {' '.join(map(str, argv))} failed: {result.stderr.strip()[-500:]}")
    record = json.loads(lines[-1])
    if record["rc"] != 0:
        raise RuntimeError(f"motion2video {' '.join(map(str, argv))} exited {record['rc']}: {result.stderr[-500:]}")
    return float(record["self"] + record["children"])


def repeated_bvh(src, dst, repeat: int, *, declared: int | None = None) -> int:
    """Write the BVH file ``src`` to ``dst`` with its motion lines repeated ``repeat`` times (a long capture for
    memory benchmarks and streaming tests); the header's ``Frames:`` says ``declared`` when given (a truncated
    file), else the true count. Returns the true frame count."""
    lines = src.read_text().splitlines(keepends=True)
    motion = next(i for i, line in enumerate(lines) if line.strip().upper() == "MOTION")
    data = [line for line in lines[motion + 3:] if line.strip()]
    with dst.open("w") as f:
        f.writelines(lines[:motion + 1])
        f.write(f"Frames: {len(data) * repeat if declared is None else declared}\n")
        f.write(lines[motion + 2])
        for _ in range(repeat):
            f.writelines(data)
    return len(data) * repeat


def tiled_motion(motion, times: int):
    """``motion`` played ``times`` times in a row (joints tiled along time): a longer clip of the same
    content, for memory-versus-length measurements."""
    from motion2video.core.motion import Motion

    return Motion(np.tile(motion.joints, (int(times), 1, 1)), motion.fps, motion.skeleton, motion.source,
                  motion.label)
