"""The two motion containers every module passes around.

- :class:`Motion`: body joints ``(T, J, D)`` (D = 3 world metres, z up; D = 2 image pixels, y down), a
  frame rate and a skeleton name.
- :class:`FaceMotion`: ``(T, 58)`` face parameters = 52 ARKit-named expression coefficients in [0, 1]
  (Anny's ``facial_action_labels`` order, :data:`ARKIT_NAMES`) + head pose (3 axis-angle, 3 translation in
  metres), a frame rate and an identity (Anny phenotype values).

Both validate on construction and raise :class:`~motion2video.core.errors.InputError`, so a bad array never
reaches a renderer or a model.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.skeletons import get_skeleton

# The 52 ARKit blendshape names in Anny's facial_action_labels order (camelCase, as Anny spells them).
ARKIT_NAMES: tuple[str, ...] = (
    "browDownLeft", "browDownRight", "browInnerUp", "browOuterUpLeft", "browOuterUpRight",
    "cheekPuff", "cheekSquintLeft", "cheekSquintRight",
    "eyeBlinkLeft", "eyeBlinkRight", "eyeLookDownLeft", "eyeLookDownRight", "eyeLookInLeft",
    "eyeLookInRight", "eyeLookOutLeft", "eyeLookOutRight", "eyeLookUpLeft", "eyeLookUpRight",
    "eyeSquintLeft", "eyeSquintRight", "eyeWideLeft", "eyeWideRight",
    "jawForward", "jawLeft", "jawOpen", "jawRight",
    "mouthClose", "mouthDimpleLeft", "mouthDimpleRight", "mouthFrownLeft", "mouthFrownRight",
    "mouthFunnel", "mouthLeft", "mouthLowerDownLeft", "mouthLowerDownRight", "mouthPressLeft",
    "mouthPressRight", "mouthPucker", "mouthRight", "mouthRollLower", "mouthRollUpper",
    "mouthShrugLower", "mouthShrugUpper", "mouthSmileLeft", "mouthSmileRight", "mouthStretchLeft",
    "mouthStretchRight", "mouthUpperUpLeft", "mouthUpperUpRight",
    "noseSneerLeft", "noseSneerRight", "tongueOut",
)
NUM_EXPRESSIONS = 52
FACE_DIM = NUM_EXPRESSIONS + 6  # + head axis-angle (3) + head translation (3)


def _check_fps(fps: float, source: str | None) -> float:
    fps = float(fps)
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(f"fps must be a positive number, got {fps}", source)
    return fps


@dataclass
class Motion:
    """A body motion clip.

    Attributes:
        joints: (T, J, D) float32, D = 3 (world metres, z up) or 2 (image pixels, x right, y down).
        fps: frames per second, > 0.
        skeleton: skeleton registry name (``"h36m-17"`` for the canonical body).
        source: where the clip came from (a path), used in error messages.
        label: an action label, if known (from a manifest or the procedural module).
    """

    joints: np.ndarray
    fps: float
    skeleton: str = "h36m-17"
    source: str | None = None
    label: str | None = None

    def __post_init__(self) -> None:
        joints = np.asarray(self.joints)
        if joints.ndim != 3 or joints.shape[-1] not in (2, 3):
            raise InputError(f"joints must have shape (T, J, 2|3), got {tuple(joints.shape)}", self.source)
        if joints.shape[0] == 0:
            raise InputError("the motion is empty (0 frames)", self.source)
        try:
            skel = get_skeleton(self.skeleton)
        except KeyError as err:
            raise InputError(str(err.args[0]), self.source) from None
        if joints.shape[1] != skel.num_joints:
            raise InputError(
                f"skeleton {self.skeleton} has {skel.num_joints} joints but the array has {joints.shape[1]}",
                self.source,
            )
        if not np.all(np.isfinite(joints)):
            bad = int(np.argwhere(~np.isfinite(joints))[0, 0])
            raise InputError(f"joints contain NaN or Inf (first at frame {bad})", self.source)
        self.joints = joints.astype(np.float32, copy=False)
        self.fps = _check_fps(self.fps, self.source)

    @property
    def num_frames(self) -> int:
        return int(self.joints.shape[0])

    @property
    def dim(self) -> int:
        return int(self.joints.shape[-1])

    @property
    def duration(self) -> float:
        return self.num_frames / self.fps

    def slice(self, start: int = 0, frames: int | None = None) -> "Motion":
        """Frames ``[start, start + frames)``; raises InputError when the range is empty."""
        if start < 0 or start >= self.num_frames:
            raise InputError(f"start frame {start} is outside the clip (0..{self.num_frames - 1})", self.source)
        stop = self.num_frames if frames is None else start + frames
        if frames is not None and frames <= 0:
            raise InputError(f"--frames must be positive, got {frames}", self.source)
        return Motion(self.joints[start:stop], self.fps, self.skeleton, self.source, self.label)


@dataclass
class FaceMotion:
    """A face motion clip.

    Attributes:
        params: (T, 58) float32: [:, :52] expression coefficients in [0, 1] in :data:`ARKIT_NAMES` order,
            [:, 52:55] head rotation (axis-angle, radians), [:, 55:58] head translation (metres).
        fps: frames per second, > 0.
        identity: Anny phenotype values (e.g. ``{"gender": 0.5, "age": 0.5, ...}``), each in [0, 1].
        source: where the clip came from, used in error messages.
    """

    params: np.ndarray
    fps: float
    identity: dict[str, float] = field(default_factory=dict)
    source: str | None = None
    label: str | None = None

    def __post_init__(self) -> None:
        params = np.asarray(self.params)
        if params.ndim != 2 or params.shape[1] != FACE_DIM:
            raise InputError(f"face params must have shape (T, {FACE_DIM}), got {tuple(params.shape)}",
                             self.source)
        if params.shape[0] == 0:
            raise InputError("the face motion is empty (0 frames)", self.source)
        if not np.all(np.isfinite(params)):
            bad = int(np.argwhere(~np.isfinite(params))[0, 0])
            raise InputError(f"face params contain NaN or Inf (first at frame {bad})", self.source)
        params = params.astype(np.float32, copy=True)
        params[:, :NUM_EXPRESSIONS] = np.clip(params[:, :NUM_EXPRESSIONS], 0.0, 1.0)
        self.params = params
        self.fps = _check_fps(self.fps, self.source)
        self.identity = {str(k): float(v) for k, v in self.identity.items()}

    @property
    def num_frames(self) -> int:
        return int(self.params.shape[0])

    @property
    def expressions(self) -> np.ndarray:
        """(T, 52) expression coefficients."""
        return self.params[:, :NUM_EXPRESSIONS]

    @property
    def head_rotation(self) -> np.ndarray:
        """(T, 3) axis-angle head rotation, radians."""
        return self.params[:, NUM_EXPRESSIONS:NUM_EXPRESSIONS + 3]

    @property
    def head_translation(self) -> np.ndarray:
        """(T, 3) head translation, metres."""
        return self.params[:, NUM_EXPRESSIONS + 3:]

    def slice(self, start: int = 0, frames: int | None = None) -> "FaceMotion":
        if start < 0 or start >= self.num_frames:
            raise InputError(f"start frame {start} is outside the clip (0..{self.num_frames - 1})", self.source)
        if frames is not None and frames <= 0:
            raise InputError(f"--frames must be positive, got {frames}", self.source)
        stop = self.num_frames if frames is None else start + frames
        return FaceMotion(self.params[start:stop], self.fps, dict(self.identity), self.source, self.label)
