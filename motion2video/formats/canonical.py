"""What every motion-capture reader shares once it has joint positions: the project frame, the floor,
trimming and resampling into a canonical ``h36m-17`` :class:`~motion2video.motion.Motion`.

A reader (BVH, DeepMimic, exp-map text) does its own forward kinematics and hands a
:class:`CanonicalClip` (every node and the 17 canonical joints, metres, z up, floor not yet placed) to
:func:`canonical_motion`, which trims, puts the floor at z = 0 and resamples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2video.errors import InputError
from motion2video.formats.resample import resample_linear
from motion2video.motion import Motion
from motion2video.core.skeletons import H36M_17, h36m_body_points

# Height of the ankle joint centre above the floor with the foot flat, metres. Anny's default body (the mesh
# the renderers pose from these joints) has its ankle (bone ``foot.R``) 0.071 m above its soles; adults
# measure 6-8 cm. The floor is put this far below the lowest ankle (:func:`floor_height`).
ANKLE_HEIGHT = 0.07

# BVH (and most mocap) is y-up; the project is z-up. (x, y, z)_file -> (x, -z, y): a +90 degree rotation
# about x (determinant +1), so left and right are preserved.
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def to_project_frame(points: np.ndarray, unit: float, axes: np.ndarray = Y_UP_TO_Z_UP) -> np.ndarray:
    """File units and axes -> metres, z up: ``unit * axes @ p`` (default ``(x, y, z) -> unit * (x, -z, y)``).

    Args:
        points: (..., 3) positions in file units.
        unit: metres per file unit.
        axes: (3, 3) matrix taking file axes to project axes (default: y up -> z up).
    Returns:
        (..., 3) float64 positions in metres.
    """
    return unit * (np.asarray(points, dtype=np.float64) @ np.asarray(axes, dtype=np.float64).T)


def floor_height(joints: np.ndarray, *, ankle_height: float = ANKLE_HEIGHT) -> float:
    """Height of the floor under a z-up canonical clip.

    The floor is put ``ankle_height`` below the lowest ankle of the clip. "Lowest" is the 1st percentile
    (not the minimum) of the per-frame lower ankle, so that a glitch of a few frames cannot drag the floor
    down; in a clip where the body stands or walks, the lowest ankle is a flat stance foot. A clip that
    never touches the ground (none in the shared data) would get a floor under its lowest ankle.

    The floor is a level plane: it is not fitted for tilt. In several CMU walks the stance ankle rises by
    up to ~6 cm over a 4 m walk (the capture floor is ~1 degree off the file's horizontal), so feet float
    that much at the far end of those clips.

    Args:
        joints: (T, 17, 3) canonical joints, metres, z up.
    Returns:
        the floor height (the value to subtract from z).
    """
    ankles = joints[:, [H36M_17.index("right_ankle"), H36M_17.index("left_ankle")], 2]  # (T, 2)
    return float(np.percentile(ankles.min(axis=1), 1.0)) - ankle_height


@dataclass(frozen=True)
class CanonicalClip:
    """A whole clip in the project frame (metres, z up), before trimming and floor placement.

    Attributes:
        joints: (T, 17, 3) canonical H36M-17 joints.
        nodes: (T, N, 3) every node of the source skeleton (joints, end sites, extra points) in the
            same frame.
        names: (N,) node names.
        rig: the source skeleton's name (a BVH rig, ``"deepmimic-humanoid-txt"``, ``"cmu-bench-expmap"``).
        unit: metres per file unit used.
        fps: the frame rate the file itself states (BVH header, DeepMimic frame duration, exp-map layout).
    """

    joints: np.ndarray
    nodes: np.ndarray
    names: tuple[str, ...]
    rig: str
    unit: float
    fps: float

    @property
    def num_frames(self) -> int:
        return int(self.joints.shape[0])

    def index(self, name: str) -> int:
        return self.names.index(name)


def canonical_motion(
    joints: np.ndarray,
    *,
    fps: float,
    source: str,
    start: int = 0,
    frames: int | None = None,
    target_fps: float | None = None,
    label: str | None = None,
) -> Motion:
    """Trim, place the floor and resample canonical joints into a ``h36m-17`` Motion.

    Order: trim to ``[start, start + frames)``; floor from the kept frames (:func:`floor_height`) moved to
    z = 0; linear resampling of positions to ``target_fps`` (:func:`resample_linear`).

    Args:
        joints: (T, 17, 3) canonical joints, metres, z up, any floor.
        fps: the true frame rate of ``joints``.
        source: the file (messages, Motion.source).
    Raises:
        InputError: non-positive rates, a start outside the clip or a non-positive frame count.
    """
    num = int(joints.shape[0])
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(f"fps must be a positive number, got {fps}", source)
    if target_fps is not None and (not np.isfinite(target_fps) or target_fps <= 0):
        raise InputError(f"target fps must be a positive number, got {target_fps}", source)
    if start < 0 or start >= num:
        raise InputError(f"start frame {start} is outside the clip (0..{num - 1})", source)
    if frames is not None and frames <= 0:
        raise InputError(f"frames must be positive, got {frames}", source)
    stop = num if frames is None else min(start + frames, num)
    out = np.array(joints[start:stop], dtype=np.float64)  # (T', 17, 3)
    out[..., 2] -= floor_height(out)
    rate = float(fps)
    if target_fps is not None and float(target_fps) != rate:
        out = resample_linear(out, rate, float(target_fps))
        rate = float(target_fps)
    return Motion(out.astype(np.float32), rate, "h36m-17", source, label)


def canonical_from_map(nodes: np.ndarray, names: tuple[str, ...],
                       mapping: dict[str, str | tuple[str, ...]]) -> np.ndarray:
    """Pick the canonical H36M-17 joints out of per-node positions.

    Args:
        nodes: (T, N, 3) node positions (any units and axes).
        names: (N,) node names.
        mapping: canonical joint -> node name, or a tuple of node names whose mean is the joint.
    Returns:
        (T, 17, 3) positions in :data:`~motion2video.skeletons.H36M_17` order.
    """
    index = {n: i for i, n in enumerate(names)}
    out = []
    for joint in H36M_17.joints:
        target = mapping[joint]
        if isinstance(target, tuple):
            out.append(nodes[:, [index[t] for t in target]].mean(axis=1))
        else:
            out.append(nodes[:, index[target]])
    return h36m_body_points(np.stack(out, axis=1))  # (T, 17, 3) on Human3.6M's body points
