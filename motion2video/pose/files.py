"""A video's estimated pose as a motion ``.npz`` that :func:`motion2video.formats.io.load_motion` reads.

Keys (the body Motion keys first, so every motion reader takes the file as a 3D ``h36m-17`` clip):

- ``joints`` (T, 17, 3) float32: canonical joints, metres, z up, floor at 0;
- ``fps``: the video's own frame rate; ``skeleton``: ``"h36m-17"``;
- ``joints_2d`` (T, 17, 2) float32: the same joints in the video's pixels (x right, y down);
- ``confidence`` (T, 17) float32: per-joint visibility in [0, 1], 0 on interpolated frames;
- ``interpolated`` (T,) bool: frames where the person was not found (joints interpolated);
- ``unsure`` (T,) bool: frames where the tracker was unsure of the person (a low presence, a jump from the
  predicted position or a torso of other colours made it ask the detector again; every interpolated frame);
- ``landmarks_2d`` (T, 33, 2) float32: BlazePose's own image landmarks;
- ``image_size`` (2,) int: width, height; ``first_frame``: the video frame of row 0;
  ``video_frames``: the video's frame count; ``estimator``: ``"blazepose-full"``; ``version``:
  :data:`POSE_VERSION`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.errors import InputError
from motion2video.core.motion import Motion
from motion2video.pose.estimate import VideoPose

ESTIMATOR = "blazepose-full"
# 2: one person followed by appearance and motion, unsure frames flagged, the root's depth from the body's size
POSE_VERSION = 2
POSE_KEYS = ("joints", "fps", "skeleton", "joints_2d", "confidence", "interpolated", "unsure", "landmarks_2d",
             "image_size", "first_frame", "video_frames", "estimator", "version")


def save_video_pose(path: str | Path, pose: VideoPose) -> Path:
    """Write a :class:`VideoPose` as a motion ``.npz`` (atomically). Returns the path."""
    return save_npz(path, {
        "joints": pose.joints3d.astype(np.float32),
        "fps": np.float64(pose.fps),
        "skeleton": np.str_("h36m-17"),
        "joints_2d": pose.points2d.astype(np.float32),
        "confidence": pose.confidence.astype(np.float32),
        "interpolated": pose.interpolated.astype(bool),
        "unsure": pose.unsure.astype(bool),
        "landmarks_2d": pose.landmarks2d.astype(np.float32),
        "image_size": np.array([pose.width, pose.height], np.int64),
        "first_frame": np.int64(pose.first_frame),
        "video_frames": np.int64(pose.video_frames),
        "estimator": np.str_(ESTIMATOR),
        "version": np.int64(POSE_VERSION),
    })


def load_video_pose(path: str | Path) -> VideoPose:
    """Read a file written by :func:`save_video_pose`; InputError naming it when keys are missing or it is of
    another version."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError) as err:
        raise InputError(f"not a readable pose .npz ({type(err).__name__})", path) from None
    missing = [k for k in POSE_KEYS if k not in data]
    if missing:
        raise InputError(f"not a pose file of `motion2video pose` version {POSE_VERSION} (lacks "
                         f"{', '.join(missing)})", path)
    if int(data["version"]) != POSE_VERSION:
        raise InputError(f"pose file version {int(data['version'])}, expected {POSE_VERSION}", path)
    w, h = (int(v) for v in data["image_size"])
    return VideoPose(data["joints_2d"].astype(np.float64), data["joints"].astype(np.float64),
                     data["confidence"].astype(np.float64), data["interpolated"].astype(bool),
                     data["landmarks_2d"].astype(np.float64), float(data["fps"]), int(data["first_frame"]),
                     w, h, int(data["video_frames"]), data["unsure"].astype(bool))


def pose_motion_3d(pose: VideoPose, source: str | Path | None = None) -> Motion:
    """The 3D joints as an ``h36m-17`` Motion (metres, z up) at the video's rate."""
    return Motion(pose.joints3d.astype(np.float32), pose.fps, "h36m-17", None if source is None else str(source))


def pose_motion_2d(pose: VideoPose, source: str | Path | None = None) -> Motion:
    """The 2D joints as an ``h36m-17`` Motion of image pixels (x right, y down) at the video's rate."""
    return Motion(pose.points2d.astype(np.float32), pose.fps, "h36m-17", None if source is None else str(source))
