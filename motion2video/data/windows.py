"""Pure array functions of the motion data pipeline: resampling, canonical window frames, the feature
encoding the models see, normalisation and augmentation.

Feature layouts (per frame, ``F`` numbers; the models only ever see normalised ``(B, T, F)`` features):

- ``body3d``: the 16 non-root joints relative to the root (pelvis), in metres, in the window's canonical
  frame (``16 * 3`` numbers, joint-major), then the root position ``(x, y, z)``: ``x, y`` relative to the
  window's anchor (the root at the last observed frame), ``z`` the height above the floor. ``F = 51``.
- ``body2d``: the same for joints projected with a fixed virtual camera to normalised image coordinates
  (``u = (px - W/2) / H``, ``v = (py - H/2) / H``, y down): ``16 * 2`` relative coordinates, then the root
  ``(u, v)``. ``F = 34``.
- ``face``: the 58 face parameters as they are (52 ARKit coefficients, 3 axis-angle, 3 translation).

Canonical window frame (body layouts): a rotation about the vertical axis through the anchor, chosen so
that at the last observed frame the hips point along +x (the body faces -y, towards the default camera).
It is computed from the observed frames only, so sampling from a bare observation uses the same frame.

Given a window's frame (fixed by its observed part), every feature encoding here is affine in the joints
of its layout (world joints, virtual-camera image joints, face parameters), and normalisation is affine per
feature, so linear extrapolation in normalised feature space is the same extrapolation in joint space (the
baselines rely on this).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2video.core.camera import PinholeCamera, project
from motion2video.core.rotations import rotation_z
from motion2video.formats.resample import resample_linear

LAYOUTS = ("body3d", "body2d", "face")
NUM_BODY_JOINTS = 17
FACE_FEATURES = 58
# The fixed virtual camera of the body2d layout: 6 m in front of the canonical body, 256 x 256 pixels.
VIRTUAL_CAMERA = PinholeCamera(position=(0.0, -6.0, 1.0), target=(0.0, 0.0, 0.9), yfov=float(np.deg2rad(35.0)),
                               width=256, height=256)


@dataclass(frozen=True)
class FeatureLayout:
    """What the ``F`` feature numbers of a frame mean.

    Attributes:
        kind: ``"body3d"``, ``"body2d"`` or ``"face"``.
    """

    kind: str = "body3d"

    def __post_init__(self) -> None:
        if self.kind not in LAYOUTS:
            raise ValueError(f"unknown feature layout {self.kind!r}; known: {', '.join(LAYOUTS)}")

    @property
    def is_body(self) -> bool:
        return self.kind != "face"

    @property
    def dim(self) -> int:
        """Coordinates per joint (3 or 2); 0 for the face layout."""
        return {"body3d": 3, "body2d": 2, "face": 0}[self.kind]

    @property
    def num_features(self) -> int:
        if self.kind == "face":
            return FACE_FEATURES
        return NUM_BODY_JOINTS * self.dim  # 16 relative joints + the root

    @property
    def metric_dim(self) -> int:
        """Length of the per-frame vector the metrics compare (see :func:`metric_vectors`)."""
        if self.kind == "face":
            return FACE_FEATURES
        return (NUM_BODY_JOINTS - 1) * self.dim

    @property
    def metric_units(self) -> str:
        return {
            "body3d": "metres (root-relative joints, L2 over the 16 non-root joints x 3 as one vector)",
            "body2d": "image heights of the virtual camera (root-relative joints, L2 over 16 x 2 as one vector)",
            "face": "face-parameter units (L2 over the 52 ARKit coefficients + 6 head-pose numbers)",
        }[self.kind]


# --- resampling ---------------------------------------------------------------------------------------


def resample(x: np.ndarray, src_fps: float, dst_fps: float) -> np.ndarray:
    """Linear resampling along time: (T, ...) at ``src_fps`` -> (T', ...) at ``dst_fps`` (a copy when the
    rates are equal); see :func:`motion2video.formats.resample.resample_linear`."""
    if abs(src_fps - dst_fps) < 1e-9 * dst_fps:
        return np.array(x, copy=True)
    return resample_linear(x, src_fps, dst_fps).astype(np.asarray(x).dtype, copy=False)


def sample_frames(x: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Linear interpolation of ``x`` (T, ...) at fractional frame ``positions`` (L,) in [0, T - 1]."""
    x = np.asarray(x)
    positions = np.clip(np.asarray(positions, np.float64), 0.0, x.shape[0] - 1)
    lo = np.floor(positions).astype(np.int64)
    hi = np.minimum(lo + 1, x.shape[0] - 1)
    w = (positions - lo).reshape((-1,) + (1,) * (x.ndim - 1))
    return ((1.0 - w) * x[lo] + w * x[hi]).astype(x.dtype, copy=False)


# --- canonical window frame -----------------------------------------------------------------------------


@dataclass(frozen=True)
class WindowFrame:
    """The rigid motion about z that takes world joints of a batch of windows to their canonical frames:
    ``canonical = R(angle) @ (world - origin)``, with ``origin`` on the floor (z = 0).

    Attributes:
        origin: (B, 3) world anchor (root x, y at the anchor frame; z = 0).
        angle: (B,) rotation about +z in radians.
    """

    origin: np.ndarray
    angle: np.ndarray


def canonical_frame(joints: np.ndarray, *, anchor: int, right_hip: int = 1, left_hip: int = 4) -> WindowFrame:
    """The canonical frame of each window from its anchor frame.

    Args:
        joints: (B, T, J, 3) world joints, metres, z up (root = joint 0).
        anchor: frame index whose root becomes the origin and whose hips set the heading.
    Returns:
        A :class:`WindowFrame` whose rotation maps the anchor's hip vector (right hip -> left hip) to +x.
    """
    j = np.asarray(joints, np.float64)
    root = j[:, anchor, 0]  # (B, 3)
    hips = j[:, anchor, left_hip, :2] - j[:, anchor, right_hip, :2]  # (B, 2)
    heading = np.arctan2(hips[:, 1], hips[:, 0])  # (B,) angle of the hip vector from +x
    origin = np.concatenate([root[:, :2], np.zeros((len(root), 1))], axis=1)  # (B, 3)
    return WindowFrame(origin=origin, angle=-heading)


def to_canonical(joints: np.ndarray, frame: WindowFrame) -> np.ndarray:
    """(B, T, J, 3) world -> canonical coordinates (float64)."""
    rot = rotation_z(frame.angle)  # (B, 3, 3)
    rel = np.asarray(joints, np.float64) - frame.origin[:, None, None, :]
    return np.einsum("bij,btkj->btki", rot, rel)


def from_canonical(joints: np.ndarray, frame: WindowFrame) -> np.ndarray:
    """(B, [K,] T, J, 3) canonical -> world coordinates (float64); the inverse of :func:`to_canonical`."""
    rot_t = np.swapaxes(rotation_z(frame.angle), -1, -2)  # (B, 3, 3) inverse rotations
    j = np.asarray(joints, np.float64)
    extra = j.ndim - 4  # 1 when there is a samples axis
    rot_t = rot_t.reshape(rot_t.shape[:1] + (1,) * extra + (1, 1, 3, 3))
    world = (rot_t @ j[..., None])[..., 0]
    return world + frame.origin.reshape(frame.origin.shape[:1] + (1,) * (extra + 2) + (3,))


def project_virtual(joints: np.ndarray, camera: PinholeCamera = VIRTUAL_CAMERA) -> np.ndarray:
    """(..., J, 3) canonical joints -> (..., J, 2) normalised image coordinates of ``camera``:
    ``u = (px - W/2) / H``, ``v = (py - H/2) / H`` (y down)."""
    px = project(joints, camera)[..., :2]
    centre = np.array([camera.width / 2, camera.height / 2])
    return (px - centre) / camera.height


def virtual_to_pixels(uv: np.ndarray, camera: PinholeCamera = VIRTUAL_CAMERA) -> np.ndarray:
    """Normalised image coordinates (..., 2) -> pixels of ``camera`` (..., 2)."""
    return np.asarray(uv, np.float64) * camera.height + np.array([camera.width / 2, camera.height / 2])


# --- features -------------------------------------------------------------------------------------------


def joints_to_features(joints: np.ndarray) -> np.ndarray:
    """Body joints in a window's canonical frame -> features.

    Args:
        joints: (..., T, 17, D) canonical joints (D = 3 metres, or D = 2 normalised image coordinates).
    Returns:
        (..., T, 17 * D): the 16 non-root joints minus the root (joint-major), then the root.
    """
    j = np.asarray(joints)
    root = j[..., :1, :]  # (..., T, 1, D)
    rel = j[..., 1:, :] - root  # (..., T, 16, D)
    lead = j.shape[:-2]
    return np.concatenate([rel.reshape(lead + (-1,)), root.reshape(lead + (-1,))], axis=-1)


def features_to_joints(features: np.ndarray, *, dim: int) -> np.ndarray:
    """The inverse of :func:`joints_to_features`: (..., T, 17 * dim) -> (..., T, 17, dim)."""
    f = np.asarray(features)
    lead = f.shape[:-1]
    rel = f[..., : (NUM_BODY_JOINTS - 1) * dim].reshape(lead + (NUM_BODY_JOINTS - 1, dim))
    root = f[..., (NUM_BODY_JOINTS - 1) * dim:].reshape(lead + (1, dim))
    return np.concatenate([root, rel + root], axis=-2)


def body_window_features(joints: np.ndarray, *, layout: FeatureLayout, anchor: int,
                         canonical_heading: bool = True) -> tuple[np.ndarray, WindowFrame]:
    """World joints of a batch of windows -> un-normalised features and the frames used.

    Args:
        joints: (B, T, 17, 3) world joints (metres, z up).
        layout: ``body3d`` or ``body2d``.
        anchor: the last observed frame index (the frame the canonical frame is taken from).
        canonical_heading: rotate to the anchor's heading (else only translate to the anchor).
    Returns:
        features (B, T, F) float64 and the :class:`WindowFrame`.
    """
    frame = canonical_frame(joints, anchor=anchor)
    if not canonical_heading:
        frame = WindowFrame(origin=frame.origin, angle=np.zeros_like(frame.angle))
    canon = to_canonical(joints, frame)  # (B, T, 17, 3)
    if layout.kind == "body2d":
        canon = project_virtual(canon)  # (B, T, 17, 2)
    elif layout.kind != "body3d":
        raise ValueError(f"layout {layout.kind} is not a body layout")
    return joints_to_features(canon), frame


def metric_vectors(features: np.ndarray, layout: FeatureLayout) -> np.ndarray:
    """Un-normalised features (..., F) -> the per-frame vectors the metrics compare (..., M):
    the root-relative non-root joints for body layouts (the DLow protocol), all 58 numbers for faces."""
    f = np.asarray(features, np.float64)
    if layout.kind == "face":
        return f
    return f[..., : layout.metric_dim]


# --- normalisation --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class NormStats:
    """Per-feature mean and standard deviation, computed on the training split.

    Attributes:
        mean: (F,) float32.
        std: (F,) float32, floored at ``min_std`` when computed.
    """

    mean: np.ndarray
    std: np.ndarray

    def normalize(self, x: np.ndarray) -> np.ndarray:
        return ((np.asarray(x, np.float64) - self.mean) / self.std).astype(np.float32)

    def denormalize(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x, np.float64) * self.std + self.mean

    def same_as(self, other: "NormStats") -> bool:
        """Whether ``other`` holds exactly the same means and standard deviations (the same normalisation)."""
        return self is other or (np.array_equal(self.mean, other.mean) and np.array_equal(self.std, other.std))

    def to_dict(self) -> dict:
        return {"mean": [float(v) for v in self.mean], "std": [float(v) for v in self.std]}

    @staticmethod
    def from_dict(d: dict) -> "NormStats":
        return NormStats(np.asarray(d["mean"], np.float32), np.asarray(d["std"], np.float32))

    @staticmethod
    def identity(num_features: int) -> "NormStats":
        return NormStats(np.zeros(num_features, np.float32), np.ones(num_features, np.float32))


def compute_stats(features: np.ndarray, *, min_std: float = 1e-3) -> NormStats:
    """Mean and std over every axis but the last of (..., F) features (float64 accumulation)."""
    f = np.asarray(features, np.float64).reshape(-1, np.shape(features)[-1])
    return NormStats(f.mean(0).astype(np.float32), np.maximum(f.std(0), min_std).astype(np.float32))


# --- augmentation ---------------------------------------------------------------------------------------


def mirror_joints(joints: np.ndarray, permutation: np.ndarray) -> np.ndarray:
    """Left/right mirror of (..., J, 3) world joints: negate x and swap left/right joint names."""
    j = np.asarray(joints)[..., permutation, :].copy()
    j[..., 0] = -j[..., 0]
    return j


def rotate_about_z(joints: np.ndarray, angle: float, centre: np.ndarray) -> np.ndarray:
    """Rotate (T, J, 3) world joints by ``angle`` radians about the vertical axis through ``centre`` (3,)."""
    rot = rotation_z(np.asarray(angle))  # (3, 3)
    c = np.array([centre[0], centre[1], 0.0])
    return ((np.asarray(joints, np.float64) - c) @ rot.T + c).astype(np.float32)


def speed_window(clip: np.ndarray, *, start: float, length: int, speed: float) -> np.ndarray:
    """A window of ``length`` frames read from ``clip`` (T, ...) at ``speed`` times the normal rate
    (speed 1.2 plays 20% faster), starting at fractional frame ``start``; linear interpolation."""
    return sample_frames(clip, start + np.arange(length) * speed)


def sliding_starts(num_frames: int, *, length: int, stride: int) -> np.ndarray:
    """Start frames of every full window of ``length`` frames, ``stride`` apart (empty if too short)."""
    if num_frames < length:
        return np.zeros(0, np.int64)
    return np.arange(0, num_frames - length + 1, stride, dtype=np.int64)
