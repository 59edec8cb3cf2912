"""Retarget a body motion onto another body and posture: the source's root-relative limb motion, performed with
the target's bone lengths, starting exactly at the target's posture.

A behaviour is the motion of the limbs relative to the body (a crouch, a jump's arm swing, a wave), plus the
root's path. :func:`retarget_motion` carries both onto a target posture:

- **limbs**: every bone's direction over time is the source's, turned to the target's heading. At the first
  frame each bone points where the target's does: the rotation taking the source's start direction of that bone
  to the target's (the shortest one) is applied in full at frame 0 and fades out over ``blend_frames``
  (a smoothstep), so the re-enactment starts in the target's posture and moves into the source's limb motion;
- **bones**: the target's lengths, placed from the pelvis down the tree (forward kinematics on directions);
- **root**: the source's path relative to its start, turned to the target's heading and scaled by the ratio of
  the legs (a shorter body takes shorter steps and jumps less high). The pelvis height is the source's height
  above the floor (z = 0), scaled the same way, plus the difference of the two start heights, which fades out
  with the limbs' blend: a source that starts in mid-air re-enacted from a standing target still lands on the
  floor.

World joints: (T, 17, 3) H36M-17, metres, z up, the floor at z = 0 (as every reader of the project puts it).
"""

from __future__ import annotations

import numpy as np

from motion2video.core.rotations import heading_of, rotation_z, slerp_rotations, swing_rotation
from motion2video.core.skeletons import H36M_17, PELVIS, bone_lengths, leg_length

BONES = tuple((j, p) for j, p in enumerate(H36M_17.parents) if p >= 0)  # (child, parent), parents first


def blend_weights(frames: int, blend_frames: int) -> np.ndarray:
    """(frames,) weight of the source's own limb directions: 0 at frame 0, rising as a smoothstep to 1 at
    frame ``blend_frames`` and after (``blend_frames`` 0: 1 from frame 1 on)."""
    t = np.arange(int(frames), dtype=np.float64) / max(int(blend_frames), 1)
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def retarget_motion(source: np.ndarray, start: np.ndarray, *, blend_frames: int) -> np.ndarray:
    """The source's motion performed by the body of ``start``, from ``start``.

    Args:
        source: (T, 17, 3) world joints, its start posture first.
        start: (17, 3) the target's posture (where the result starts) and body (its bone lengths).
        blend_frames: frames over which the target's posture gives way to the source's limb directions.
    Returns:
        (T, 17, 3) float64: frame 0 equals ``start``; every frame has ``start``'s bone lengths; from frame
        ``blend_frames`` on, every bone points as the source's does (turned to the target's heading).
    """
    src = np.asarray(source, np.float64)
    tgt = np.asarray(start, np.float64)
    if src.ndim != 3 or src.shape[1:] != (17, 3) or tgt.shape != (17, 3):
        raise ValueError(f"expected (T, 17, 3) source and (17, 3) start joints, got {src.shape} and {tgt.shape}")
    frames = src.shape[0]
    turn = rotation_z(heading_of(tgt) - heading_of(src[0]))  # (3, 3) source heading -> target heading
    scale = leg_length(tgt[None]) / max(leg_length(src), 1e-9)
    child = np.array([b[0] for b in BONES])
    parent = np.array([b[1] for b in BONES])
    directions = (src[:, child] - src[:, parent]) @ turn.T  # (T, 16, 3)
    offset = swing_rotation(directions[0], tgt[child] - tgt[parent])  # (16, 3, 3) source start -> target start
    w = blend_weights(frames, blend_frames)  # (T,)
    fading = slerp_rotations(np.broadcast_to(offset, (frames,) + offset.shape),
                             np.broadcast_to(np.eye(3), (frames,) + offset.shape), w[:, None])  # (T, 16, 3, 3)
    moved = np.einsum("tbij,tbj->tbi", fading, directions)
    unit = moved / np.maximum(np.linalg.norm(moved, axis=-1, keepdims=True), 1e-12)
    lengths = bone_lengths(tgt)  # (17,) indexed by the child joint

    out = np.empty_like(src)
    path = (src[:, PELVIS] - src[0, PELVIS]) @ turn.T * scale  # (T, 3) root displacement
    out[:, PELVIS, :2] = tgt[PELVIS, :2] + path[:, :2]
    out[:, PELVIS, 2] = scale * src[:, PELVIS, 2] + (1.0 - w) * (tgt[PELVIS, 2] - scale * src[0, PELVIS, 2])
    for k, (c, p) in enumerate(BONES):
        out[:, c] = out[:, p] + unit[:, k] * lengths[c]
    out[0] = tgt  # exact, not to rounding
    return out
