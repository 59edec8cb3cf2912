"""Face-motion data for the face models: loading captures, resampling, head pose, mirroring.

Expression comes from the real ARKit captures (``../shared/data/face``: Live Link Face CSV takes and
FaceMotion ``.npz`` files). Head pose: the ``livelinkface/`` takes have no head rotation (streaming was
off: all zeros). By default (``DatasetConfig.face_head_pose = "procedural"``) such a clip gets a smooth
head-pose track from :func:`motion2video.data.face_dynamics.head_pose_track`, seeded by the clip name, so
face models also learn (synthetic, expression-independent) head motion; captures with real head pose
(``llv/dao.csv``, FaceMotion npz files) keep theirs. ``face_head_pose = "zero"`` keeps the zeros.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.motion import ARKIT_NAMES, FACE_DIM, NUM_EXPRESSIONS, FaceMotion

FACE_SUFFIXES = (".csv", ".npz")


def face_mirror_permutation() -> np.ndarray:
    """(58,) index array that swaps every ``...Left`` coefficient with its ``...Right`` twin."""
    perm = np.arange(FACE_DIM)
    index = {name: i for i, name in enumerate(ARKIT_NAMES)}
    for i, name in enumerate(ARKIT_NAMES):
        if name.endswith("Left"):
            perm[i] = index[name[: -len("Left")] + "Right"]
        elif name.endswith("Right"):
            perm[i] = index[name[: -len("Right")] + "Left"]
    return perm


def mirror_face(params: np.ndarray) -> np.ndarray:
    """Left/right mirror of (..., 58) face parameters (mirror plane x = 0): swap Left/Right coefficients,
    negate the y and z components of the head axis-angle and the x head translation."""
    p = np.asarray(params)[..., face_mirror_permutation()].copy()
    p[..., NUM_EXPRESSIONS + 1] *= -1.0  # rotation about y
    p[..., NUM_EXPRESSIONS + 2] *= -1.0  # rotation about z
    p[..., NUM_EXPRESSIONS + 3] *= -1.0  # translation along x
    return p


def face_files(path: str | Path) -> list[Path]:
    """Face capture files under ``path`` (a ``.csv`` / ``.npz`` file, or a folder searched recursively;
    a folder's ``manifest.csv`` is not a capture)."""
    path = Path(path)
    if not path.exists():
        raise InputError("no such file or directory", path)
    if path.is_file():
        if path.suffix.lower() not in FACE_SUFFIXES:
            raise InputError("a face model needs a face capture (.csv or FaceMotion .npz)", path)
        return [path]
    files = sorted(p for p in path.rglob("*")
                   if p.suffix.lower() in FACE_SUFFIXES and p.is_file() and p.name.lower() != "manifest.csv")
    if not files:
        raise InputError("the folder holds no face captures (.csv or FaceMotion .npz)", path)
    return files


def load_face_clip(path: str | Path) -> FaceMotion:
    """One face capture as a :class:`FaceMotion` (Live Link Face CSV or FaceMotion npz)."""
    from motion2video.formats.io import load_motion

    motion = load_motion(path)
    if not isinstance(motion, FaceMotion):
        raise InputError("this file holds body motion, but the model is a face model", path)
    return motion
