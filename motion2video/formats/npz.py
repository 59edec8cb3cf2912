"""Motion and FaceMotion as ``.npz`` files (no pickles).

Body motion keys: ``joints`` (T, J, 2|3) float32, ``fps`` (scalar), ``skeleton`` (string), optional
``label`` (string). Face motion keys: ``face`` (T, 58) float32, ``fps``, ``identity`` (a JSON object as a
string, Anny phenotype values), optional ``label``. Strings are stored as numpy unicode scalars so that
reading never needs ``allow_pickle``.

Writing is atomic (:mod:`motion2video.core.atomic`).
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.errors import InputError
from motion2video.core.motion import FACE_DIM, FaceMotion, Motion

BODY_KEYS = ("joints", "fps", "skeleton")
FACE_KEYS = ("face", "fps", "identity")


def save_motion_npz(motion: Motion, path: str | Path) -> Path:
    """Write a body Motion to ``path`` (.npz) atomically. Returns the path."""
    path = Path(path)
    arrays = {
        "joints": np.asarray(motion.joints, dtype=np.float32),
        "fps": np.float64(motion.fps),
        "skeleton": np.str_(motion.skeleton),
    }
    if motion.label is not None:
        arrays["label"] = np.str_(motion.label)
    save_npz(path, arrays)
    return path


def save_face_npz(face: FaceMotion, path: str | Path) -> Path:
    """Write a FaceMotion to ``path`` (.npz) atomically. Returns the path."""
    path = Path(path)
    arrays = {
        "face": np.asarray(face.params, dtype=np.float32),
        "fps": np.float64(face.fps),
        "identity": np.str_(json.dumps(face.identity, sort_keys=True)),
    }
    if face.label is not None:
        arrays["label"] = np.str_(face.label)
    save_npz(path, arrays)
    return path


def read_npz_arrays(path: str | Path) -> dict[str, np.ndarray]:
    """All arrays of an .npz file, loaded without pickles. Raises InputError for a missing or bad file."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    if not zipfile.is_zipfile(path):
        raise InputError("not an .npz archive", path)
    try:
        with np.load(path, allow_pickle=False) as data:
            return {k: data[k] for k in data.files}
    except ValueError as err:  # an object array needs pickles: not this format
        raise InputError(f"cannot read without pickles ({' '.join(str(err).split())[:80]})", path) from None
    except (zipfile.BadZipFile, OSError, EOFError) as err:
        raise InputError(f"not a readable .npz archive ({type(err).__name__})", path) from None


def npz_keys(path: str | Path) -> list[str]:
    """The array names in an .npz archive, read from its index without loading (or unpickling) anything."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    if not zipfile.is_zipfile(path):
        raise InputError("not an .npz archive", path)
    try:
        with np.load(path, allow_pickle=False) as data:
            return list(data.files)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as err:
        raise InputError(f"not a readable .npz archive ({type(err).__name__})", path) from None


def npz_kind(keys: list[str] | dict[str, np.ndarray]) -> str | None:
    """``"body"``, ``"face"`` or ``"videopose3d"`` from an archive's keys; None when none fits."""
    if "joints" in keys:
        return "body"
    if "face" in keys:
        return "face"
    if "positions_3d" in keys:
        return "videopose3d"
    return None


def _string(arrays: dict[str, np.ndarray], key: str, path: Path) -> str:
    value = arrays[key]
    if value.ndim != 0 or value.dtype.kind not in "US":
        raise InputError(f"key {key!r} must be a string, got dtype {value.dtype} shape {value.shape}", path)
    return str(value)


def _fps(arrays: dict[str, np.ndarray], path: Path) -> float:
    value = arrays["fps"]
    if value.size != 1 or value.dtype.kind not in "iuf":
        raise InputError(f"key 'fps' must be one number, got dtype {value.dtype} shape {value.shape}", path)
    fps = float(value.reshape(()))
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(f"fps must be a positive number, got {fps}", path)
    return fps


def _numeric(arrays: dict[str, np.ndarray], key: str, path: Path) -> np.ndarray:
    value = arrays[key]
    if value.dtype.kind not in "iuf":
        raise InputError(f"key {key!r} must be numeric, got dtype {value.dtype}", path)
    return value


def load_motion_npz(path: str | Path) -> Motion:
    """Read a body Motion .npz (keys ``joints``, ``fps``, ``skeleton``, optional ``label``); validates it."""
    path = Path(path)
    arrays = read_npz_arrays(path)
    missing = [k for k in BODY_KEYS if k not in arrays]
    if missing:
        raise InputError(f"body motion .npz lacks key(s) {', '.join(missing)} (has {', '.join(arrays)})", path)
    joints = _numeric(arrays, "joints", path)
    label = _string(arrays, "label", path) if "label" in arrays else None
    # Motion checks the shape against the skeleton, NaN/Inf and empty clips, raising InputError.
    return Motion(joints, _fps(arrays, path), _string(arrays, "skeleton", path), str(path), label)


def load_face_npz(path: str | Path) -> FaceMotion:
    """Read a FaceMotion .npz (keys ``face`` (T, 58), ``fps``, ``identity`` JSON, optional ``label``)."""
    path = Path(path)
    arrays = read_npz_arrays(path)
    missing = [k for k in FACE_KEYS if k not in arrays]
    if missing:
        raise InputError(f"face motion .npz lacks key(s) {', '.join(missing)} (has {', '.join(arrays)})", path)
    face = _numeric(arrays, "face", path)
    if face.ndim != 2 or face.shape[1] != FACE_DIM:
        raise InputError(f"'face' must have shape (T, {FACE_DIM}), got {face.shape}", path)
    try:
        identity = json.loads(_string(arrays, "identity", path))
    except json.JSONDecodeError as err:
        raise InputError(f"'identity' is not valid JSON ({err.msg})", path) from None
    except RecursionError:  # json's decoder recurses once per nesting level
        raise InputError("'identity' is not valid JSON (nested too deeply)", path) from None
    if not isinstance(identity, dict) or not all(isinstance(v, (int, float)) for v in identity.values()):
        raise InputError("'identity' must be a JSON object of numbers", path)
    label = _string(arrays, "label", path) if "label" in arrays else None
    return FaceMotion(face, _fps(arrays, path), identity, str(path), label)
