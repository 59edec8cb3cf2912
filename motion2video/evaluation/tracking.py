"""How steadily a video's person was followed, and how far their root travelled: the measures of one person
tracked through a video (``scripts/measure_tracking.py``).

- pelvis jump: the largest pixel distance of the 2D pelvis between consecutive frames (a switch to another
  person shows as a jump of a body width or more);
- root path: the length of the 3D pelvis's path over the ground (metres), its extent along its main direction
  (the first principal axis of the ground positions), and its travel in depth (the range along the camera's
  line of sight, the y axis of the pose's 3D joints).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class TrackMeasures:
    """Measures of one tracked person (see the module docstring).

    Attributes:
        frames: frames in the pose.
        pelvis_max_jump_px: the largest step of the 2D pelvis between consecutive frames, pixels.
        jump_frame: the row where it lands (0-based, in the pose's rows).
        root_path_m: the ground path length of the 3D pelvis, metres.
        main_direction_m: its extent along its main direction, metres.
        depth_travel_m: its range along the camera's line of sight, metres.
        unsure_frames: frames the tracker was unsure of.
    """

    frames: int
    pelvis_max_jump_px: float
    jump_frame: int
    root_path_m: float
    main_direction_m: float
    depth_travel_m: float
    unsure_frames: int

    def as_dict(self) -> dict:
        return asdict(self)


def track_measures(pelvis2d: np.ndarray, root3d: np.ndarray, unsure: np.ndarray) -> TrackMeasures:
    """Measures of a tracked person.

    Args:
        pelvis2d: (T, 2) the pelvis in pixels, T >= 2.
        root3d: (T, 3) the pelvis in metres (x right, y away from the camera, z up).
        unsure: (T,) bool.
    """
    pelvis2d, root3d = np.asarray(pelvis2d, np.float64), np.asarray(root3d, np.float64)
    steps = np.linalg.norm(np.diff(pelvis2d, axis=0), axis=1)  # (T-1,)
    ground = root3d[:, :2]
    centred = ground - ground.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    along = centred @ axes[0]
    return TrackMeasures(frames=len(pelvis2d), pelvis_max_jump_px=float(steps.max()), jump_frame=int(steps.argmax()) + 1,
                         root_path_m=float(np.linalg.norm(np.diff(ground, axis=0), axis=1).sum()),
                         main_direction_m=float(np.ptp(along)), depth_travel_m=float(np.ptp(root3d[:, 1])),
                         unsure_frames=int(np.sum(unsure)))
