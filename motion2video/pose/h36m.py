"""BlazePose's 33 landmarks -> the project's canonical H36M-17 joints (2D image pixels and 3D metres).

Direct joints: hips, knees, ankles, shoulders, elbows, wrists. Built joints (BlazePose has no landmark
there), from Human3.6M's own proportions (subject S1, see docs/architecture.md):

- pelvis = hip midpoint; thorax = shoulder midpoint;
- spine on the pelvis -> thorax segment, 233 / (233 + 257) of the way up;
- neck/nose = thorax + 0.135 leg along thorax -> ear midpoint; head = neck/nose + 0.128 leg further on
  (121 mm and 115 mm over a 897 mm thigh + shin), where ``leg`` is the mean of the two hip -> knee -> ankle
  lengths of the same frame.

Confidence of a built joint is the least confidence of the landmarks it is built from. These are the
canonical skeleton's (version 2) definitions; the 3D joints then go through
:func:`motion2video.core.skeletons.h36m_body_points` (fixed-length spine chain, clip-level leg).
"""

from __future__ import annotations

import numpy as np

from motion2video.core.skeletons import H36M_17, H36M_BONES_MM, H36M_LEG_MM

# BlazePose landmark indices.
NOSE, L_EAR, R_EAR = 0, 7, 8
L_SHOULDER, R_SHOULDER, L_ELBOW, R_ELBOW, L_WRIST, R_WRIST = 11, 12, 13, 14, 15, 16
L_HIP, R_HIP, L_KNEE, R_KNEE, L_ANKLE, R_ANKLE = 23, 24, 25, 26, 27, 28

# Canonical joint -> BlazePose landmark, for the joints BlazePose has.
DIRECT = {
    "right_hip": R_HIP, "right_knee": R_KNEE, "right_ankle": R_ANKLE,
    "left_hip": L_HIP, "left_knee": L_KNEE, "left_ankle": L_ANKLE,
    "left_shoulder": L_SHOULDER, "left_elbow": L_ELBOW, "left_wrist": L_WRIST,
    "right_shoulder": R_SHOULDER, "right_elbow": R_ELBOW, "right_wrist": R_WRIST,
}
SPINE_FRACTION = 233.0 / (233.0 + 257.0)
NECK_PER_LEG = H36M_BONES_MM["thorax_nose"] / H36M_LEG_MM  # 0.135
HEAD_PER_LEG = H36M_BONES_MM["nose_head"] / H36M_LEG_MM  # 0.128


def leg_length(points: np.ndarray) -> np.ndarray:
    """(...,) mean of the two hip -> knee -> ankle lengths of (..., 33, D) landmarks."""
    def chain(a: int, b: int, c: int) -> np.ndarray:
        return (np.linalg.norm(points[..., b, :] - points[..., a, :], axis=-1)
                + np.linalg.norm(points[..., c, :] - points[..., b, :], axis=-1))
    return 0.5 * (chain(L_HIP, L_KNEE, L_ANKLE) + chain(R_HIP, R_KNEE, R_ANKLE))


def blazepose_to_h36m(points: np.ndarray, confidence: np.ndarray | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Map BlazePose landmarks to canonical H36M-17 joints (any number of coordinates).

    Args:
        points: (..., 33+, D) landmarks (D = 2 image pixels or 3 metres); extra landmarks are ignored.
        confidence: (..., 33+) per-landmark confidence (default ones).
    Returns:
        (..., 17, D) joints in :data:`~motion2video.core.skeletons.H36M_17` order and (..., 17) confidence.
    """
    p = np.asarray(points, np.float64)
    c = np.ones(p.shape[:-1]) if confidence is None else np.asarray(confidence, np.float64)
    out = np.zeros(p.shape[:-2] + (17, p.shape[-1]))
    conf = np.zeros(p.shape[:-2] + (17,))
    for name, src in DIRECT.items():
        out[..., H36M_17.index(name), :] = p[..., src, :]
        conf[..., H36M_17.index(name)] = c[..., src]
    pelvis = 0.5 * (p[..., L_HIP, :] + p[..., R_HIP, :])
    thorax = 0.5 * (p[..., L_SHOULDER, :] + p[..., R_SHOULDER, :])
    ears = 0.5 * (p[..., L_EAR, :] + p[..., R_EAR, :])
    direction = ears - thorax
    direction /= np.maximum(np.linalg.norm(direction, axis=-1, keepdims=True), 1e-9)
    leg = leg_length(p)[..., None]
    neck = thorax + NECK_PER_LEG * leg * direction
    head = neck + HEAD_PER_LEG * leg * direction
    out[..., 0, :] = pelvis
    out[..., 7, :] = pelvis + SPINE_FRACTION * (thorax - pelvis)
    out[..., 8, :] = thorax
    out[..., 9, :] = neck
    out[..., 10, :] = head
    hips = np.minimum(c[..., L_HIP], c[..., R_HIP])
    shoulders = np.minimum(c[..., L_SHOULDER], c[..., R_SHOULDER])
    legs = np.min(c[..., [L_HIP, R_HIP, L_KNEE, R_KNEE, L_ANKLE, R_ANKLE]], axis=-1)
    conf[..., 0] = hips
    conf[..., 7] = np.minimum(hips, shoulders)
    conf[..., 8] = shoulders
    conf[..., 9] = conf[..., 10] = np.minimum(np.minimum(shoulders, legs), np.minimum(c[..., L_EAR], c[..., R_EAR]))
    return out, conf


# BlazePose world landmarks: x right, y down, z away from the camera (metres, hip-centred). The project:
# z up. (x, y, z) -> (x, z, -y) is a rotation (determinant +1): the camera looks along +y, a person facing
# the camera faces -y with their left side at +x, as Anny's rest pose.
CAMERA_TO_PROJECT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def world_to_project(world: np.ndarray) -> np.ndarray:
    """(..., 3) BlazePose world landmarks (y down) -> project axes (metres, z up), origin unchanged."""
    return np.asarray(world, np.float64) @ CAMERA_TO_PROJECT.T


# Canonical thigh + shin (Human3.6M S1), metres: the scale of a 2D body lifted onto a plane.
LEG_METRES = 0.897


def image_to_plane(points2d: np.ndarray, *, leg_metres: float = LEG_METRES) -> np.ndarray:
    """2D joints in image pixels -> 3D joints on the vertical plane y = 0 (metres, z up), as a camera in front
    of the plane would see them: a similarity (uniform scale, flip of the y-down axis), no depth.

    The scale makes the clip's 90th-percentile 2D leg (hip -> knee -> ankle, both sides' mean) ``leg_metres``
    long; x follows the image's x from the first frame's pelvis, z the image's up; the lowest ankle is
    put on the floor (z = 0, as :func:`motion2video.formats.canonical.floor_height` places it). A 2D body
    model's virtual camera (in front of the plane, looking along +y) then sees the keypoints as the image
    showed them, up to scale and position.

    Args:
        points2d: (T, 17, 2) canonical H36M-17 joints, pixels, x right, y down.
    Returns:
        (T, 17, 3) float64 joints.
    """
    from motion2video.formats.canonical import floor_height

    p = np.asarray(points2d, np.float64)
    r_hip, r_knee, r_ankle, l_hip, l_knee, l_ankle = (H36M_17.index(n) for n in (
        "right_hip", "right_knee", "right_ankle", "left_hip", "left_knee", "left_ankle"))

    def chain(a: int, b: int, c: int) -> np.ndarray:
        return np.linalg.norm(p[:, b] - p[:, a], axis=-1) + np.linalg.norm(p[:, c] - p[:, b], axis=-1)

    leg_px = float(np.percentile(0.5 * (chain(r_hip, r_knee, r_ankle) + chain(l_hip, l_knee, l_ankle)), 90))
    scale = leg_metres / max(leg_px, 1e-6)
    rel = (p - p[:1, :1]) * scale  # (T, 17, 2), origin at the first pelvis
    out = np.stack([rel[..., 0], np.zeros(rel.shape[:-1]), -rel[..., 1]], axis=-1)
    out[..., 2] -= floor_height(out)
    return out
