"""Behaviour signatures: one number per body sequence that says how much of a behaviour it holds.

Every function takes world joints ``(T, 17, 3)`` (H36M-17, metres, z up, the floor at z = 0) at ``fps`` and
returns a float. They are invariant to where the body stands and which way it faces (a rigid motion about
the vertical axis), so a re-enactment placed at another start position and heading is compared with its
source directly: the ratio ``signature(re-enactment) / signature(source)`` is 1.0 when the behaviour came
across in full.

- jump: :func:`pelvis_excursion`, the pelvis's vertical range (max - min height), metres;
- kick: :func:`kick_height`, the highest an ankle gets above its own knee, measured from where it hangs
  when the shin points straight down (ankle height - knee height + shin length, metres: 0 for a hanging
  shin, about 0.1-0.2 in walking, the shin length for a horizontal shin, more when the ankle is above the
  knee), so it is positive and ratios of it mean something;
- walk / run: :func:`root_speed`, the mean horizontal speed of the pelvis, m/s;
- turn: :func:`heading_change`, the absolute net change of the hips' heading, radians (unwrapped);
- dance / martial arts: :func:`limb_speed`, the mean speed of wrists and ankles relative to the pelvis, m/s.

Root-relative signatures: a re-enactment that follows the source's root path carries the
pelvis excursion of a jump exactly even when the legs and arms do nothing, so these measure the motion
relative to the body. Each is the range (max - min over the frames) of a per-frame distance, metres: the
amplitude of that movement, 0 for a body holding one posture.

- :func:`leg_extension`: the pelvis's height above the ankles (their mean height) - crouching and
  extending the legs;
- :func:`arm_swing`: a wrist's height relative to the thorax (the larger range of the two wrists) - arms
  swung up and down;
- :func:`knee_bend`: the hip-to-ankle distance of a leg (the larger range of the two legs) - the knee
  bending and straightening;
- :func:`ankle_lift`: an ankle's height relative to the pelvis (the larger range of the two legs) - the
  height of a kick measured from the body, not the floor.

:func:`bone_lengths` and :func:`bone_length_spread` check that a generated body stays rigid, and
:func:`posture_error` how far a re-enactment's start is from the posture it should start from.
"""

from __future__ import annotations

import numpy as np

from motion2video.core.skeletons import (
    H36M_17,
    L_ANKLE,
    L_HIP,
    L_KNEE,
    L_WRIST,
    PELVIS,
    R_ANKLE,
    R_HIP,
    R_KNEE,
    R_WRIST,
    THORAX,
)

ROOT_PATH_SIGNATURES = ("pelvis_excursion", "kick_height", "root_speed", "heading_change", "limb_speed")
ROOT_RELATIVE_SIGNATURES = ("leg_extension", "arm_swing", "knee_bend", "ankle_lift")
SIGNATURES = ROOT_PATH_SIGNATURES + ROOT_RELATIVE_SIGNATURES


def _joints(joints: np.ndarray, *, min_frames: int = 2) -> np.ndarray:
    j = np.asarray(joints, np.float64)
    if j.ndim != 3 or j.shape[1:] != (17, 3):
        raise ValueError(f"expected (T, 17, 3) world joints, got {j.shape}")
    if j.shape[0] < min_frames:
        raise ValueError(f"a signature needs >= {min_frames} frames, got {j.shape[0]}")
    return j


def pelvis_excursion(joints: np.ndarray) -> float:
    """Vertical range of the pelvis (max - min height) over (T, 17, 3) joints, metres."""
    z = _joints(joints, min_frames=1)[:, PELVIS, 2]
    return float(z.max() - z.min())


def kick_height(joints: np.ndarray) -> float:
    """The highest an ankle rises over its straight-down position below its own knee (ankle z - knee z + shin
    length, the shin length its median over time) over (T, 17, 3) joints, metres (max over both legs)."""
    j = _joints(joints, min_frames=1)
    best = -np.inf
    for ankle, knee in ((R_ANKLE, R_KNEE), (L_ANKLE, L_KNEE)):
        shin = float(np.median(np.linalg.norm(j[:, ankle] - j[:, knee], axis=-1)))
        best = max(best, float((j[:, ankle, 2] - j[:, knee, 2]).max()) + shin)
    return float(best)


def root_speed(joints: np.ndarray, fps: float) -> float:
    """Mean horizontal speed of the pelvis over (T, 17, 3) joints at ``fps``, m/s."""
    xy = _joints(joints)[:, PELVIS, :2]
    return float(np.linalg.norm(np.diff(xy, axis=0), axis=-1).mean() * fps)


def headings(joints: np.ndarray) -> np.ndarray:
    """(T,) unwrapped heading of the hips (angle of right hip -> left hip about +z), radians."""
    j = _joints(joints, min_frames=1)
    hips = j[:, L_HIP, :2] - j[:, R_HIP, :2]
    return np.unwrap(np.arctan2(hips[:, 1], hips[:, 0]))


def heading_change(joints: np.ndarray) -> float:
    """Absolute net heading change (last frame - first frame, unwrapped) over (T, 17, 3) joints, radians."""
    h = headings(joints)
    return float(abs(h[-1] - h[0]))


def limb_speed(joints: np.ndarray, fps: float) -> float:
    """Mean speed of the wrists and ankles relative to the pelvis over (T, 17, 3) joints at ``fps``, m/s."""
    j = _joints(joints)
    rel = j[:, [L_WRIST, R_WRIST, L_ANKLE, R_ANKLE]] - j[:, PELVIS:PELVIS + 1]  # (T, 4, 3)
    return float(np.linalg.norm(np.diff(rel, axis=0), axis=-1).mean() * fps)


def _range(x: np.ndarray) -> np.ndarray:
    """max - min over the first (time) axis: (T, ...) -> (...)."""
    return x.max(axis=0) - x.min(axis=0)


def leg_extension(joints: np.ndarray) -> float:
    """Range over time of the pelvis's height above the mean height of the two ankles, (T, 17, 3) joints ->
    metres (0 for a fixed posture; a crouch-and-extend of 0.3 m gives 0.3)."""
    j = _joints(joints, min_frames=1)
    height = j[:, PELVIS, 2] - 0.5 * (j[:, L_ANKLE, 2] + j[:, R_ANKLE, 2])  # (T,)
    return float(_range(height))


def arm_swing(joints: np.ndarray) -> float:
    """Range over time of a wrist's height relative to the thorax, the larger of the two wrists, (T, 17, 3)
    joints -> metres (arms raised from the sides to overhead: about 1 m)."""
    j = _joints(joints, min_frames=1)
    rel = j[:, [L_WRIST, R_WRIST], 2] - j[:, THORAX:THORAX + 1, 2]  # (T, 2)
    return float(_range(rel).max())


def knee_bend(joints: np.ndarray) -> float:
    """Range over time of the hip-to-ankle distance of a leg, the larger of the two legs, (T, 17, 3) joints ->
    metres (a straight leg that bends until hip and ankle are 0.2 m closer gives 0.2)."""
    j = _joints(joints, min_frames=1)
    dist = np.linalg.norm(j[:, [L_HIP, R_HIP]] - j[:, [L_ANKLE, R_ANKLE]], axis=-1)  # (T, 2)
    return float(_range(dist).max())


def ankle_lift(joints: np.ndarray) -> float:
    """Range over time of an ankle's height relative to the pelvis, the larger of the two legs, (T, 17, 3)
    joints -> metres (a kick that brings an ankle from 0.9 m below the pelvis to its height: 0.9)."""
    j = _joints(joints, min_frames=1)
    rel = j[:, [L_ANKLE, R_ANKLE], 2] - j[:, PELVIS:PELVIS + 1, 2]  # (T, 2)
    return float(_range(rel).max())


def signature(name: str, joints: np.ndarray, fps: float) -> float:
    """The signature ``name`` (one of :data:`SIGNATURES`) of (T, 17, 3) joints at ``fps``."""
    if name == "pelvis_excursion":
        return pelvis_excursion(joints)
    if name == "kick_height":
        return kick_height(joints)
    if name == "root_speed":
        return root_speed(joints, fps)
    if name == "heading_change":
        return heading_change(joints)
    if name == "limb_speed":
        return limb_speed(joints, fps)
    if name in ROOT_RELATIVE_SIGNATURES:
        return {"leg_extension": leg_extension, "arm_swing": arm_swing, "knee_bend": knee_bend,
                "ankle_lift": ankle_lift}[name](joints)
    raise ValueError(f"unknown signature {name!r}; known: {', '.join(SIGNATURES)}")


BONES = tuple((j, p) for j, p in enumerate(H36M_17.parents) if p >= 0)


def bone_lengths(joints: np.ndarray) -> np.ndarray:
    """(T, 16) length of every bone (joint to parent) over (T, 17, 3) joints, metres."""
    j = _joints(joints, min_frames=1)
    child = np.array([b[0] for b in BONES])
    parent = np.array([b[1] for b in BONES])
    return np.linalg.norm(j[:, child] - j[:, parent], axis=-1)


def bone_length_spread(joints: np.ndarray) -> float:
    """How much the bones stretch over time: the largest per-bone standard deviation over time divided by
    that bone's mean length (a rigid body gives 0; 0.05 = a bone varies by 5% of its length)."""
    lengths = bone_lengths(joints)  # (T, 16)
    return float((lengths.std(axis=0) / np.maximum(lengths.mean(axis=0), 1e-6)).max())


def posture_error(joints: np.ndarray, start: np.ndarray) -> float:
    """Mean per-joint distance (metres) between the root-relative posture of ``joints[0]`` (17, 3) and that of
    ``start`` (17, 3) after turning both to face the same way (hips along +x)."""
    a = _joints(np.asarray(joints)[:1], min_frames=1)[0]
    b = _joints(np.asarray(start)[None], min_frames=1)[0]

    def canonical(p: np.ndarray) -> np.ndarray:
        rel = p - p[PELVIS]
        hips = p[L_HIP, :2] - p[R_HIP, :2]
        angle = -np.arctan2(hips[1], hips[0])
        c, s = np.cos(angle), np.sin(angle)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return rel @ rot.T

    return float(np.linalg.norm(canonical(a) - canonical(b), axis=-1).mean())
