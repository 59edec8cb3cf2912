"""OpenPose JSON output (one ``*_keypoints.json`` per frame) -> 2D canonical Motion.

Each file holds ``{"people": [{"pose_keypoints_2d": [x0, y0, c0, x1, y1, c1, ...]}, ...]}`` with 18
(COCO / OpenPose-18) or 25 (BODY_25) keypoints in image pixels (x right, y down). Only ``people[0]`` is
read. A keypoint with confidence 0 (OpenPose writes 0, 0, 0 for an undetected joint) and every keypoint of
a frame without people are missing; missing values are filled by linear interpolation over time from the
nearest detections of the same keypoint (held constant before the first and after the last detection).
A keypoint the canonical mapping needs that is never detected raises :class:`InputError`.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.motion import Motion
from motion2video.core.skeletons import BODY_25, OPENPOSE_18, OPENPOSE_TO_H36M, Skeleton, convert_openpose_to_h36m

_LAYOUTS = {18 * 3: OPENPOSE_18, 25 * 3: BODY_25}


def _natural_key(path: Path) -> list:
    """Sort key so that ``frame_2`` comes before ``frame_10``."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def openpose_files(folder: str | Path) -> list[Path]:
    """The ``*_keypoints.json`` files of a folder in frame order (natural sort); ``*.json`` if none."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError("no such directory", folder)
    files = sorted(folder.glob("*_keypoints.json"), key=_natural_key)
    if not files:
        files = sorted(folder.glob("*.json"), key=_natural_key)
    if not files:
        raise InputError("no OpenPose *_keypoints.json files in the directory", folder)
    return files


def read_openpose_frame(path: Path) -> np.ndarray | None:
    """One frame's ``people[0].pose_keypoints_2d`` as (K, 3) float64 (x, y, confidence); None if no people."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"not valid JSON ({type(err).__name__})", path) from None
    except RecursionError:  # json's decoder recurses once per nesting level (found by the fuzz tests)
        raise InputError("not valid JSON (nested too deeply)", path) from None
    if not isinstance(data, dict) or not isinstance(data.get("people"), list):
        raise InputError("not an OpenPose keypoints file (no 'people' list)", path)
    if not data["people"]:
        return None
    person = data["people"][0]
    values = person.get("pose_keypoints_2d") if isinstance(person, dict) else None
    if not isinstance(values, list):
        raise InputError("people[0] has no 'pose_keypoints_2d' list", path)
    if len(values) not in _LAYOUTS:
        raise InputError(f"pose_keypoints_2d has {len(values)} values; expected 54 (COCO-18) or 75 (BODY_25)",
                         path)
    try:
        array = np.asarray(values, dtype=np.float64).reshape(-1, 3)  # (K, 3)
    except (TypeError, ValueError):
        raise InputError("pose_keypoints_2d holds non-numbers", path) from None
    if not np.all(np.isfinite(array)):
        raise InputError("pose_keypoints_2d holds NaN or Inf", path)
    return array


def interpolate_missing(values: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """Fill unseen samples of each channel by linear interpolation over time (edges held).

    Args:
        values: (T, K, D) samples.
        seen: (T, K) bool, True where a sample is valid; every column must have one True.
    Returns:
        (T, K, D) float64 with the unseen samples replaced.
    """
    out = np.array(values, dtype=np.float64)
    t = np.arange(values.shape[0])
    for k in range(values.shape[1]):
        ok = seen[:, k]
        if ok.all():
            continue
        for d in range(values.shape[2]):
            out[~ok, k, d] = np.interp(t[~ok], t[ok], values[ok, k, d])
    return out


def load_openpose_folder(folder: str | Path, *, fps: float = 25.0, label: str | None = None) -> Motion:
    """Read an OpenPose JSON folder (or one JSON file) as a 2D ``h36m-17`` Motion in image pixels.

    Args:
        folder: a directory of per-frame ``*_keypoints.json`` files, or a single such file (one frame).
        fps: frame rate of the video the keypoints came from.
        label: optional action label.
    Returns:
        Motion with joints (T, 17, 2), x right / y down pixels.
    """
    folder = Path(folder)
    if folder.is_file():
        files = [folder]
    elif folder.is_dir():
        files = openpose_files(folder)
    else:
        raise InputError("no such file or directory", folder)
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(f"fps must be a positive number, got {fps}", folder)

    frames = [read_openpose_frame(f) for f in files]
    layouts = {len(f) for f in frames if f is not None}
    if not layouts:
        raise InputError(f"no person detected in any of the {len(files)} frames", folder)
    if len(layouts) > 1:
        raise InputError("frames mix COCO-18 and BODY_25 keypoints", folder)
    skeleton: Skeleton = _LAYOUTS[layouts.pop() * 3]
    num_keypoints = skeleton.num_joints
    raw = np.zeros((len(frames), num_keypoints, 3))  # (T, K, 3)
    for t, f in enumerate(frames):
        if f is not None:
            raw[t] = f
    seen = raw[..., 2] > 0  # (T, K)

    needed = sorted({skeleton.index(s) for sources in OPENPOSE_TO_H36M.values() for s in sources})
    never = [skeleton.joints[k] for k in needed if not seen[:, k].any()]
    if never:
        raise InputError(f"keypoint(s) never detected: {', '.join(never)}", folder)
    # Keypoints the mapping does not use (ears, toes) may stay unseen: give them a harmless value.
    for k in range(num_keypoints):
        if not seen[:, k].any():
            seen[:, k] = True
    xy = interpolate_missing(raw[..., :2], seen)  # (T, K, 2)
    joints = convert_openpose_to_h36m(xy, skeleton)  # (T, 17, 2)
    return Motion(joints.astype(np.float32), float(fps), "h36m-17", str(folder), label)
