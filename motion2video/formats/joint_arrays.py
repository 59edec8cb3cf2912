"""Plain joint arrays, as the motion-generation field writes them: ``.npy``, or ``.npz`` holding one array.

==========================  ================================================================================
shape                       read as
==========================  ================================================================================
``(T, 22, 3)``              SMPL / HumanML3D joints (HumanML3D, MDM, T2M-GPT, MoMask): SMPL joint order
                            (:data:`SMPL_22`), y up, metres, 20 fps unless the caller says otherwise
``(T, 17, 3)``              canonical H36M-17 joints (the project's order and frame: metres, z up), 50 fps
                            (Human3.6M's rate, which DLow / BeLFusion / HumanMAC predict at) unless told
``(K, T, J, 3)``, J 17/22   K futures of a stochastic predictor (DLow, BeLFusion, HumanMAC), each as above
==========================  ================================================================================

SMPL joints go to the canonical skeleton the way every mocap reader's joints do: the nearest SMPL joints
(:data:`SMPL_CANONICAL`), y up -> z up, then :func:`~motion2video.core.skeletons.h36m_body_points` (the head
direction is SMPL's neck -> head). Every clip gets its floor at z = 0
(:func:`~motion2video.formats.canonical.canonical_motion`); K futures share one floor.

Pickles are refused: arrays are read with ``allow_pickle=False`` only. MDM's ``results.npy`` is a pickled
dict; the message says how to save its joint array.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.motion import Motion
from motion2video.core.skeletons import H36M_17
from motion2video.formats.canonical import canonical_from_map, canonical_motion, floor_height, to_project_frame

# SMPL's first 22 joints (the body without hands), HumanML3D's order.
SMPL_22 = ("pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
           "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
           "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist")
# The nearest SMPL joint per canonical joint (h36m_body_points then rebuilds pelvis, spine, thorax, neck
# and head: the spine only gives the bend's side, the thorax is the shoulders' midpoint).
SMPL_CANONICAL: dict[str, str] = {
    "pelvis": "pelvis", "right_hip": "right_hip", "right_knee": "right_knee", "right_ankle": "right_ankle",
    "left_hip": "left_hip", "left_knee": "left_knee", "left_ankle": "left_ankle",
    "spine": "spine2", "thorax": "spine3", "neck": "neck", "head": "head",
    "left_shoulder": "left_shoulder", "left_elbow": "left_elbow", "left_wrist": "left_wrist",
    "right_shoulder": "right_shoulder", "right_elbow": "right_elbow", "right_wrist": "right_wrist",
}
SMPL_FPS = 20.0  # HumanML3D and the text-to-motion models built on it
H36M_FPS = 50.0  # Human3.6M, and the stochastic predictors trained on it
ARRAY_SUFFIXES = (".npy", ".npz")
KNOWN_JOINTS = {22: "SMPL-22 (y up)", 17: "H36M-17 (z up)"}
SAVE_HINT = ("save the joint array itself: np.save(path, joints) with joints of shape (T, 22, 3) or "
             "(K, T, J, 3) (MDM's results.npy: np.save(path, results['motion'][i].transpose(2, 0, 1)), one "
             "(T, 22, 3) clip)")


def read_joint_array(path: str | Path) -> np.ndarray:
    """The one array of a ``.npy`` or single-array ``.npz`` file, as float64, checked for shape and values.

    Returns:
        (T, J, 3) or (K, T, J, 3) with J in :data:`KNOWN_JOINTS`.
    Raises:
        InputError: a pickle, several arrays, another shape, NaN/Inf, no frames.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    try:
        if path.suffix.lower() == ".npz":
            with np.load(path, allow_pickle=False) as data:
                keys = list(data.files)
                if len(keys) != 1:
                    raise InputError(f"a joint-array .npz holds exactly one array, this one holds {len(keys)} "
                                     f"({', '.join(keys)})", path)
                array = data[keys[0]]
        else:
            array = np.load(path, allow_pickle=False)
    except InputError:
        raise
    except ValueError as err:
        if "pickle" in str(err):
            raise InputError(f"holds a pickled Python object, which is never loaded; {SAVE_HINT}", path) from None
        raise InputError(f"not a readable NumPy file ({err})", path) from None
    except (OSError, EOFError, zipfile.BadZipFile) as err:
        raise InputError(f"not a readable NumPy file ({type(err).__name__})", path) from None
    if not isinstance(array, np.ndarray) or array.dtype.kind not in "iuf":
        raise InputError(f"expected a numeric joint array, got dtype {getattr(array, 'dtype', type(array))}", path)
    if array.ndim not in (3, 4) or array.shape[-1] != 3 or array.shape[-2] not in KNOWN_JOINTS:
        raise InputError(f"expected joints of shape (T, J, 3) or (K, T, J, 3) with J = 22 (SMPL) or 17 "
                         f"(H36M), got {array.shape}", path)
    if array.shape[-3] == 0 or (array.ndim == 4 and array.shape[0] == 0):
        raise InputError(f"the joint array is empty, shape {array.shape}", path)
    if not np.all(np.isfinite(array)):
        raise InputError("joint values contain NaN or Inf", path)
    return array.astype(np.float64)


def smpl_to_canonical(joints: np.ndarray) -> np.ndarray:
    """SMPL-22 joints (y up, metres) -> canonical H36M-17 (z up, metres, floor not placed).

    Args:
        joints: (T, 22, 3) in :data:`SMPL_22` order.
    Returns:
        (T, 17, 3) on Human3.6M's body points.
    """
    nodes = to_project_frame(joints, 1.0)  # (T, 22, 3) z up
    return canonical_from_map(nodes, SMPL_22, SMPL_CANONICAL)


def _canonical(array: np.ndarray) -> np.ndarray:
    """(..., T, J, 3) known joints -> (..., T, 17, 3) canonical, z up, floor not placed."""
    if array.shape[-2] == 17:
        return array
    if array.ndim == 3:
        return smpl_to_canonical(array)
    return np.stack([smpl_to_canonical(a) for a in array])


def _fps(array: np.ndarray, fps: float | None, path: Path) -> float:
    rate = (SMPL_FPS if array.shape[-2] == 22 else H36M_FPS) if fps is None else float(fps)
    if not np.isfinite(rate) or rate <= 0:
        raise InputError(f"fps must be a positive number, got {rate}", path)
    return rate


def load_joint_array(path: str | Path, *, fps: float | None = None) -> Motion:
    """A ``(T, J, 3)`` joint array as a canonical ``h36m-17`` Motion (metres, z up, floor at z = 0).

    Args:
        path: ``.npy`` / single-array ``.npz``.
        fps: the data's rate (default 20 fps for SMPL-22 arrays, 50 for H36M-17 ones).
    Raises:
        InputError: as :func:`read_joint_array`, and for K futures (use :func:`load_joint_futures`).
    """
    path = Path(path)
    array = read_joint_array(path)
    if array.ndim == 4:
        raise InputError(f"holds {array.shape[0]} futures (K, T, J, 3) = {array.shape}; `motion2video render` "
                         "draws them as a grid, a model takes one (T, J, 3) clip", path)
    return canonical_motion(_canonical(array), fps=_fps(array, fps, path), source=str(path))


def load_joint_futures(path: str | Path, *, fps: float | None = None) -> list[Motion]:
    """Every clip of a joint array as canonical Motions: K for ``(K, T, J, 3)``, one for ``(T, J, 3)``.

    The K futures share one floor (the lowest ankle over all of them), so their heights compare.
    """
    path = Path(path)
    array = read_joint_array(path)
    rate = _fps(array, fps, path)
    canon = _canonical(array if array.ndim == 4 else array[None])  # (K, T, 17, 3)
    floor = floor_height(canon.reshape(-1, len(H36M_17.joints), 3))
    out = canon.copy()
    out[..., 2] -= floor
    return [Motion(c.astype(np.float32), rate, "h36m-17", str(path)) for c in out]


def is_joint_array(path: str | Path, keys: list[str] | None = None) -> bool:
    """Whether ``path`` is read by this module: any ``.npy``, or an ``.npz`` with exactly one array (``keys``:
    its array names, when the caller has them)."""
    suffix = Path(path).suffix.lower()
    return suffix == ".npy" or (suffix == ".npz" and keys is not None and len(keys) == 1)
