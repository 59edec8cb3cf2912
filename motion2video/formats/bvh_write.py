"""Canonical H36M-17 joints -> a BVH file that animation tools import (Blender, Maya, MotionBuilder).

The hierarchy (rig ``motion2video-h36m`` in :data:`~motion2video.core.skeletons.RIG_JOINT_MAPS`):

```
Hips (pelvis; Xposition Yposition Zposition Zrotation Xrotation Yrotation)
├─ LHipJoint ─ LeftUpLeg (left hip) ─ LeftLeg (knee) ─ LeftFoot (ankle) ─ End Site (toe)
├─ RHipJoint ─ RightUpLeg ─ RightLeg ─ RightFoot ─ End Site
└─ LowerBack ─ Spine (spine) ─ Thorax (thorax)
                               ├─ NeckBase ─ Neck (neck/nose) ─ Head (head) ─ End Site
                               ├─ LeftShoulder ─ LeftArm (shoulder) ─ LeftForeArm (elbow) ─ LeftHand (wrist)
                               │                                                              ─ End Site
                               └─ RightShoulder ─ RightArm ─ RightForeArm ─ RightHand ─ End Site
```

Units and axes: metres, y up, the body facing +z and its left side at +x in the rest pose (a T-pose:
legs down, spine and head up, arms straight out to the sides), 25 fps by default. ``LHipJoint``,
``RHipJoint``, ``LowerBack``, ``NeckBase`` and the two ``Shoulder`` joints sit where their parent sits (zero
offset, as CMU's hip and collar joints): each turns one bone on its own, so that every joint lands exactly
on its position even when the bones from a branching joint do not keep their angles.

Offsets: each bone's median length over the frames (``--rigid-bones`` output has one length per bone, so the
file reproduces its joints to the precision of the numbers written). Rotations (``Zrotation Xrotation
Yrotation``: ``R = Rz @ Rx @ Ry``) are fitted per frame, parents first: a joint with one bone below it
takes the shortest rotation (swing) that turns that bone from where its parent's rotation points it to the
frame's bone direction, so its twist follows its parent's; ``Hips`` and ``Thorax`` take the frame spanned by
the hip (shoulder) axis and the spine (neck) direction.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from motion2video.core.atomic import write_text
from motion2video.core.errors import InputError
from motion2video.core.skeletons import H36M_17
from motion2video.formats.canonical import Y_UP_TO_Z_UP
from motion2video.formats.resample import resample_linear

RIG = "motion2video-h36m"
BVH_FPS = 25.0


@dataclass(frozen=True)
class Node:
    """One BVH joint: its name, parent, the canonical joint it sits on, and its bone's rest direction (file
    axes: x left, y up, z forward; None for a zero-offset joint or the root)."""

    name: str
    parent: str | None
    joint: str
    rest: tuple[float, float, float] | None
    end: tuple[float, float, float] | None = None  # End Site offset, metres


LEFT, RIGHT, UP, DOWN = (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0)
NODES: tuple[Node, ...] = (
    Node("Hips", None, "pelvis", None),
    Node("LHipJoint", "Hips", "pelvis", None),
    Node("LeftUpLeg", "LHipJoint", "left_hip", LEFT),
    Node("LeftLeg", "LeftUpLeg", "left_knee", DOWN),
    Node("LeftFoot", "LeftLeg", "left_ankle", DOWN, end=(0.0, -0.05, 0.14)),
    Node("RHipJoint", "Hips", "pelvis", None),
    Node("RightUpLeg", "RHipJoint", "right_hip", RIGHT),
    Node("RightLeg", "RightUpLeg", "right_knee", DOWN),
    Node("RightFoot", "RightLeg", "right_ankle", DOWN, end=(0.0, -0.05, 0.14)),
    Node("LowerBack", "Hips", "pelvis", None),
    Node("Spine", "LowerBack", "spine", UP),
    Node("Thorax", "Spine", "thorax", UP),
    Node("NeckBase", "Thorax", "thorax", None),
    Node("Neck", "NeckBase", "neck", UP),
    Node("Head", "Neck", "head", UP, end=(0.0, 0.10, 0.0)),
    Node("LeftShoulder", "Thorax", "thorax", None),
    Node("LeftArm", "LeftShoulder", "left_shoulder", LEFT),
    Node("LeftForeArm", "LeftArm", "left_elbow", LEFT),
    Node("LeftHand", "LeftForeArm", "left_wrist", LEFT, end=(0.08, 0.0, 0.0)),
    Node("RightShoulder", "Thorax", "thorax", None),
    Node("RightArm", "RightShoulder", "right_shoulder", RIGHT),
    Node("RightForeArm", "RightArm", "right_elbow", RIGHT),
    Node("RightHand", "RightForeArm", "right_wrist", RIGHT, end=(-0.08, 0.0, 0.0)),
)
# The frame of a branching joint: (x axis from joint a to joint b, second axis towards joint c from d).
FRAMES = {"Hips": ("right_hip", "left_hip", "pelvis", "thorax"),
          "Thorax": ("right_shoulder", "left_shoulder", "thorax", "neck")}


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.maximum(n, 1e-12)


def _swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(T, 3, 3) shortest rotations taking unit vectors a (T, 3) to b (T, 3)."""
    axis = np.cross(a, b)
    sin = np.linalg.norm(axis, axis=-1)
    cos = np.sum(a * b, axis=-1)
    angle = np.arctan2(sin, cos)
    # antiparallel: any axis perpendicular to a
    other = np.where(np.abs(a[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    fallback = _unit(np.cross(a, other))
    axis = np.where((sin < 1e-9)[:, None], fallback, axis / np.maximum(sin, 1e-12)[:, None])
    return Rotation.from_rotvec(axis * angle[:, None]).as_matrix()


def _frame(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotations whose columns are x, y orthogonalised against x, and x cross y."""
    x = _unit(x)
    y = _unit(y - x * np.sum(x * y, axis=-1, keepdims=True))
    return np.stack([x, y, np.cross(x, y)], axis=-1)


def fit_bvh(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit the :data:`NODES` hierarchy to canonical joints.

    Args:
        joints: (T, 17, 3) H36M-17 joints, metres, z up (the project frame).
    Returns:
        offsets (N, 3) metres in file axes (y up), root positions (T, 3) metres in file axes, and local
        rotations (T, N, 3, 3).
    """
    j = np.asarray(joints, dtype=np.float64) @ Y_UP_TO_Z_UP  # (T, 17, 3): p_file = A^T p_proj, row form
    index = {n.name: i for i, n in enumerate(NODES)}
    pos = {n.name: j[:, H36M_17.index(n.joint)] for n in NODES}  # (T, 3) each
    offsets = np.zeros((len(NODES), 3))
    for i, n in enumerate(NODES):
        if n.rest is not None:
            length = float(np.median(np.linalg.norm(pos[n.name] - pos[n.parent], axis=-1)))
            offsets[i] = length * np.asarray(n.rest)
    children = {n.name: [c for c in NODES if c.parent == n.name] for n in NODES}
    num = j.shape[0]
    world = np.empty((num, len(NODES), 3, 3))
    local = np.empty_like(world)
    for i, n in enumerate(NODES):
        parent_world = world[:, index[n.parent]] if n.parent is not None else np.broadcast_to(np.eye(3), (num, 3, 3))
        if n.name in FRAMES:
            a, b, c, d = (j[:, H36M_17.index(k)] for k in FRAMES[n.name])
            w = _frame(b - a, d - c)
        elif len(children[n.name]) == 1 and children[n.name][0].rest is not None:
            child = children[n.name][0]
            rest = parent_world @ np.asarray(child.rest)  # (T, 3) where the parent's rotation points the bone
            w = _swing(rest, _unit(pos[child.name] - pos[n.name])) @ parent_world
        else:
            w = np.array(parent_world)  # an end joint: no bone to fit
        world[:, i] = w
        local[:, i] = np.swapaxes(parent_world, -1, -2) @ w
    return offsets, pos["Hips"], local


def bvh_text(joints: np.ndarray, fps: float, *, target_fps: float | None = BVH_FPS) -> str:
    """The BVH file's text for (T, 17, 3) canonical joints at ``fps`` (resampled to ``target_fps``)."""
    joints = np.asarray(joints, dtype=np.float64)
    if joints.ndim != 3 or joints.shape[1:] != (17, 3) or joints.shape[0] < 1:
        raise ValueError(f"expected (T, 17, 3) joints, got {joints.shape}")
    if target_fps is not None and float(target_fps) != float(fps):
        joints = resample_linear(joints, float(fps), float(target_fps))
        fps = float(target_fps)
    offsets, root, local = fit_bvh(joints)
    euler = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_euler("ZXY", degrees=True).reshape(len(root), -1, 3)
    lines = ["HIERARCHY"]
    index = {n.name: i for i, n in enumerate(NODES)}

    def block(node: Node, depth: int) -> None:
        pad = "  " * depth
        kind = "ROOT" if node.parent is None else "JOINT"
        lines.append(f"{pad}{kind} {node.name}")
        lines.append(f"{pad}{{")
        off = offsets[index[node.name]]
        lines.append(f"{pad}  OFFSET {off[0]:.6f} {off[1]:.6f} {off[2]:.6f}")
        chans = "Zrotation Xrotation Yrotation"
        lines.append(f"{pad}  CHANNELS 6 Xposition Yposition Zposition {chans}" if node.parent is None
                     else f"{pad}  CHANNELS 3 {chans}")
        for child in NODES:
            if child.parent == node.name:
                block(child, depth + 1)
        if node.end is not None:
            lines.extend([f"{pad}  End Site", f"{pad}  {{",
                          f"{pad}    OFFSET {node.end[0]:.6f} {node.end[1]:.6f} {node.end[2]:.6f}", f"{pad}  }}"])
        lines.append(f"{pad}}}")

    block(NODES[0], 0)
    lines += ["MOTION", f"Frames: {len(root)}", f"Frame Time: {1.0 / fps:.8f}"]
    for t in range(len(root)):
        values = np.concatenate([root[t], euler[t].reshape(-1)])
        lines.append(" ".join(f"{v:.6f}" for v in values))
    return "\n".join(lines) + "\n"


def write_bvh(path: str | Path, joints: np.ndarray, fps: float, *, target_fps: float | None = BVH_FPS) -> Path:
    """Write (T, 17, 3) canonical joints (metres, z up) at ``fps`` as a BVH file (atomic; see the module)."""
    return write_text(Path(path), bvh_text(joints, fps, target_fps=target_fps))


def check_bvh_dir(path: str | Path | None) -> Path | None:
    """``--bvh DIR``: None, or a folder that exists or can be created (its parent exists). InputError else."""
    if path is None:
        return None
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise InputError("--bvh needs a folder, this is a file", folder)
    if not folder.exists() and not folder.parent.is_dir():
        raise InputError("--bvh: the folder's parent does not exist", folder)
    return folder


def write_bvh_files(folder: str | Path, stem: str, clips: np.ndarray, fps: float) -> list[Path]:
    """Write ``FOLDER/STEM_1.bvh`` ... one per clip of (K, T, 17, 3) joints; returns the paths."""
    folder = Path(folder)
    clips = np.asarray(clips)
    texts = [bvh_text(c, fps) for c in clips]  # fit every clip before writing any
    folder.mkdir(exist_ok=True)
    return [write_text(folder / f"{stem}_{k + 1}.bvh", text) for k, text in enumerate(texts)]
