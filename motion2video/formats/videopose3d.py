"""VideoPose3D's Human3.6M file (``data_3d_h36m.npz``) -> canonical ``h36m-17`` Motions.

Layout: ``np.savez(path, positions_3d=positions)`` with ``positions = {subject: {action: (T, 32, 3)}}``,
so the one key holds a pickled dict. This loader is the only place in the project that reads with
``allow_pickle=True``, and only for this explicitly named format: a pickle can run code, so load such a file
only from a source you trust. Positions are Human3.6M world coordinates in metres, z up (the project's
frame); the capture rate is 50 fps. The 32 joints are reduced to 17 with
:data:`~motion2video.core.skeletons.H36M_32_TO_17`, as DLow and VideoPose3D do.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.motion import Motion
from motion2video.core.skeletons import H36M_32, H36M_32_TO_17

H36M_FPS = 50.0


def read_videopose3d(path: str | Path) -> dict[str, dict[str, np.ndarray]]:
    """The ``positions_3d`` dict of a VideoPose3D file: ``{subject: {action: (T, 32, 3) float64}}``."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    if not zipfile.is_zipfile(path):  # np.load would unpickle a bare pickle file: refuse anything but .npz
        raise InputError("not an .npz archive", path)
    try:
        # allow_pickle: required by this format (a dict saved with np.savez), see the module docstring.
        with np.load(path, allow_pickle=True) as data:
            keys = list(data.files)
            positions = data["positions_3d"] if "positions_3d" in keys else None
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as err:
        raise InputError(f"not a readable .npz archive ({type(err).__name__})", path) from None
    if positions is None:
        raise InputError(f"no 'positions_3d' key (keys: {', '.join(keys)}); not a VideoPose3D data_3d file",
                         path)
    if positions.dtype != object or positions.shape != ():
        raise InputError("'positions_3d' must hold a dict {subject: {action: array}}", path)
    positions = positions.item()
    if not isinstance(positions, dict) or not positions:
        raise InputError("'positions_3d' must hold a non-empty dict {subject: {action: array}}", path)
    out: dict[str, dict[str, np.ndarray]] = {}
    for subject, actions in positions.items():
        if not isinstance(actions, dict):
            raise InputError(f"subject {subject!r} must map action names to arrays", path)
        out[str(subject)] = {}
        for action, array in actions.items():
            array = np.asarray(array)
            if array.dtype.kind not in "iuf" or array.ndim != 3 or array.shape[1:] != (H36M_32.num_joints, 3):
                raise InputError(f"{subject}/{action}: expected a (T, 32, 3) numeric array, got "
                                 f"{array.dtype} {array.shape}", path)
            out[str(subject)][str(action)] = array.astype(np.float64)
    return out


def load_videopose3d(
    path: str | Path, subject: str | None = None, action: str | None = None
) -> list[Motion]:
    """Load clips of a VideoPose3D ``data_3d_h36m.npz`` as canonical 17-joint Motions at 50 fps.

    Args:
        path: the .npz file.
        subject: keep only this subject (e.g. ``"S1"``); None keeps all.
        action: keep only this action (e.g. ``"Walking 1"``); None keeps all.
    Returns:
        Motions sorted by (subject, action); ``label`` is the action, ``source`` is ``path#subject/action``.
        Raises InputError when nothing matches.
    """
    data = read_videopose3d(path)
    motions = []
    for subj in sorted(data):
        if subject is not None and subj != subject:
            continue
        for act in sorted(data[subj]):
            if action is not None and act != action:
                continue
            joints = data[subj][act][:, list(H36M_32_TO_17)]  # (T, 17, 3)
            motions.append(Motion(joints.astype(np.float32), H36M_FPS, "h36m-17", f"{path}#{subj}/{act}", act))
    if not motions:
        wanted = "/".join(x for x in (subject, action) if x is not None)
        raise InputError(f"no clip matches {wanted!r} (subjects: {', '.join(sorted(data))})", path)
    return motions
