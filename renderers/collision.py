"""Arms kept out of the torso when Anny is posed on someone else's joints.

Mocap joints come from a body of other proportions than the reference person's fitted Anny. An arm that hangs
close beside the actor's waist lies inside a wider Anny's waist, and a forearm held against the belly sinks into
it: the renders then show a hole of skin in the shirt, or the forearm's pixels interleaved with the shirt's. The
pose solver (:func:`renderers.body.pose_anny_from_joints`) follows bone directions and has no collision, so the
joints are moved first: each elbow and wrist that falls inside the torso, modelled as Anny's own cross-sections
(an ellipse per height between the pelvis and the thorax, grown by the forearm's radius), is moved out along the
cross-section's radius to its outline. Then the forearm, continued by the hand past the wrist (the pose solver has
no hand joint), turns about the elbow, a few times, towards where its deepest point inside is pushed out.
Everything else is left as it is; an arm outside the torso never moves.

Pure functions of arrays; the shape comes from the rest mesh of the phenotype (:func:`torso_shape`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2video.core.rotations import frame_from_axes
from motion2video.core.skeletons import L_ELBOW, L_HIP, L_WRIST, PELVIS, R_ELBOW, R_HIP, R_WRIST, THORAX
from renderers import anny_model

TORSO_BONES = ("root", "pelvis.L", "pelvis.R", "spine05", "spine04", "spine03", "spine02", "spine01")
TORSO_BANDS = 10  # cross-sections between the pelvis (s = 0) and the thorax (s = 1)
ARM_RADIUS_M = 0.04  # Anny's forearm radius at rest (90th percentile of its vertices' distance from the bone: 4.0 cm)
HAND_LENGTH_M = 0.16  # how far Anny's hand reaches past the wrist along the forearm (90th percentile of its vertices)
HAND_STEPS = 8  # turns of the forearm about the elbow that bring its deepest point out of the torso
ARM_SAMPLES = (0.25, 0.5, 0.75, 1.0)  # points on elbow -> the hand's end (fractions of that reach) kept out
ARM_JOINTS = ((L_ELBOW, L_WRIST), (R_ELBOW, R_WRIST))


@dataclass(frozen=True)
class TorsoShape:
    """Anny's torso as ellipses across the pelvis -> thorax line, in the rest pose, metres at Anny's own size.

    Attributes:
        s: (K,) band centres along the line, 0 at the pelvis and 1 at the thorax.
        half_width: (K,) the ellipse's half-axis along the hips (left hip minus right hip).
        centre: (K,) the ellipse's centre along the front-back axis (the spine line is 0).
        half_depth: (K,) its half-axis along the front-back axis.
    """

    s: np.ndarray
    half_width: np.ndarray
    centre: np.ndarray
    half_depth: np.ndarray


def body_axes(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The torso's frame of (..., 17, 3) canonical joints: the pelvis (..., 3), the pelvis -> thorax vector
    (..., 3), and the unit lateral (left hip minus right hip, made orthogonal to the spine) and front-back
    (spine x lateral) axes (..., 3)."""
    j = np.asarray(joints, np.float64)
    pelvis = j[..., PELVIS, :]
    spine = j[..., THORAX, :] - pelvis
    frame = frame_from_axes(spine, j[..., L_HIP, :] - j[..., R_HIP, :])  # columns: spine, lateral x spine, lateral
    return pelvis, spine, frame[..., 2], -frame[..., 1]


def torso_shape(rest: anny_model.AnnyRest) -> TorsoShape:
    """The cross-sections of the vertices that the pelvis and spine bones carry, in ``rest`` (a phenotype's rest
    pose): per band the largest lateral distance and the front-most and back-most points."""
    names = anny_model.bone_names()
    torso = np.isin(anny_model.dominant_bones(), [names.index(n) for n in TORSO_BONES])
    pelvis, spine, lateral, front = body_axes(rest.joints17)
    d = rest.vertices[torso] - pelvis
    s = d @ spine / float(spine @ spine)
    x, z = np.abs(d @ lateral), d @ front
    edges = np.linspace(0.0, 1.0, TORSO_BANDS + 1)
    centres = 0.5 * (edges[:-1] + edges[1:])
    width, middle, depth = np.zeros(TORSO_BANDS), np.zeros(TORSO_BANDS), np.zeros(TORSO_BANDS)
    for k in range(TORSO_BANDS):
        band = (s >= edges[k]) & (s < edges[k + 1])
        width[k] = x[band].max()
        middle[k] = 0.5 * (z[band].max() + z[band].min())
        depth[k] = 0.5 * (z[band].max() - z[band].min())
    return TorsoShape(centres, width, middle, depth)


def push_out_of_torso(points: np.ndarray, joints: np.ndarray, torso: TorsoShape, *, scale: float,
                      radius: float) -> np.ndarray:
    """``points`` (T, 3) moved out of the torso of ``joints`` (T, 17, 3), each frame's at the same frame.

    A point between the pelvis and the thorax heights (0 <= s <= 1 along that line) whose offset from the line lies
    inside the band's ellipse (half-axes grown by ``radius``; the shape scaled by ``scale``, the joints' size over
    Anny's rest size) is moved radially from the ellipse's centre onto its outline; others are returned as they
    are. Returns (T, 3)."""
    p = np.asarray(points, np.float64)
    pelvis, spine, lateral, front = body_axes(joints)
    d = p - pelvis
    s = np.sum(d * spine, axis=-1) / np.sum(spine * spine, axis=-1)
    x, z = np.sum(d * lateral, axis=-1), np.sum(d * front, axis=-1)
    a = np.interp(s, torso.s, torso.half_width) * scale + radius
    b = np.interp(s, torso.s, torso.half_depth) * scale + radius
    c = np.interp(s, torso.s, torso.centre) * scale
    r = np.sqrt((x / a) ** 2 + ((z - c) / b) ** 2)
    inside = (s >= 0.0) & (s <= 1.0) & (r < 1.0)
    if not inside.any():
        return p.copy()
    # radially onto the outline; a point at the very centre goes out sideways
    r_safe = np.where(r > 1e-6, r, 1.0)
    new_x = np.where(r > 1e-6, x / r_safe, a)
    new_z = np.where(r > 1e-6, c + (z - c) / r_safe, c)
    moved = p + lateral * (new_x - x)[:, None] + front * (new_z - z)[:, None]
    return np.where(inside[:, None], moved, p)


def arms_clear_of_torso(joints: np.ndarray, rest: anny_model.AnnyRest, *, scale: float,
                        radius: float = ARM_RADIUS_M) -> np.ndarray:
    """(T, 17, 3) canonical joints with every elbow and wrist moved out of the torso of Anny's ``rest`` shape
    (:func:`push_out_of_torso`; ``scale`` the joints' size over Anny's rest size, ``radius`` the arm's at rest).
    The elbow first, then the wrist, then the forearm turned about the elbow (its length kept) while a point of
    it or of the hand (:data:`ARM_SAMPLES` of the reach to :data:`HAND_LENGTH_M` past the wrist) is inside.
    Shoulders, legs and the spine never move."""
    out = np.array(joints, np.float64, copy=True)
    torso = torso_shape(rest)
    grown = radius * scale
    for e, w in ARM_JOINTS:
        for i in (e, w):
            out[:, i] = push_out_of_torso(out[:, i], out, torso, scale=scale, radius=grown)
        forearm = np.linalg.norm(out[:, w] - out[:, e], axis=-1, keepdims=True)  # (T, 1)
        reach = forearm + HAND_LENGTH_M * scale  # elbow -> the hand's end
        for _ in range(HAND_STEPS):  # the deepest point of forearm and hand out: the forearm turned about the elbow
            direction = (out[:, w] - out[:, e]) / np.maximum(forearm, 1e-9)
            worst, target = None, None
            for f in ARM_SAMPLES:
                point = out[:, e] + direction * (f * reach)
                pushed = push_out_of_torso(point, out, torso, scale=scale, radius=grown)
                depth = np.linalg.norm(pushed - point, axis=-1)
                if worst is None:
                    worst, target = depth, pushed
                else:
                    deeper = depth > worst
                    worst, target = np.where(deeper, depth, worst), np.where(deeper[:, None], pushed, target)
            moved = worst > 1e-9
            if not moved.any():
                break
            turned = target - out[:, e]
            turned /= np.maximum(np.linalg.norm(turned, axis=-1, keepdims=True), 1e-9)
            out[moved, w] = out[moved, e] + turned[moved] * forearm[moved]
    return out
