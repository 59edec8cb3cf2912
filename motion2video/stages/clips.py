"""Load a user's clip for a model: the one loader every application (sample, synthesize, transfer, analogy)
feeds its model with.

One loader per input kind, chosen by the model's layout: body models take 3D h36m-17 motion (BVH of any rig,
DeepMimic / exp-map text, motion npz, ..., or a video of a person, whose pose is estimated and cached), face models
take face captures (Live Link Face CSV, FaceMotion npz) or a video of a face, whose face motion is tracked and
cached. The clip is resampled to the model's rate exactly as its training data was
(:mod:`motion2video.data.dataset`); a face capture with no head pose gets the same procedural head track the
training captures got (``DatasetConfig.face_head_pose``).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion, Motion


@dataclass
class LoadedClip:
    """A user clip at the model's frame rate.

    Attributes:
        data: (T, 17, 3) world joints (body models) or (T, 58) face parameters (face models), float32.
        fps: the model's frame rate (the rate of ``data``).
        source_fps: the file's own rate; source_frames: its number of frames.
        path: the file.
        identity: the face identity recorded in the file (empty for bodies and plain captures).
    """

    data: np.ndarray
    fps: float
    source_fps: float
    source_frames: int
    path: str
    identity: dict = field(default_factory=dict)

    @property
    def num_frames(self) -> int:
        return int(self.data.shape[0])


def _body_data(bundle, motion, path: Path) -> np.ndarray:
    """(T, 17, 3) joints at the model's rate; InputError for face motion or another skeleton."""
    from motion2video.data.dataset import _body_clip_from_motion

    if isinstance(motion, FaceMotion):
        raise InputError(f"{bundle.label} is a body model, but this file holds face motion", path)
    if (isinstance(motion, Motion) and motion.skeleton == "h36m-17" and motion.dim == 2
            and bundle.data_config.layout == "body2d"):
        # A 2D model sees the keypoints through its virtual camera: put them on a plane facing that camera.
        from motion2video.pose.h36m import image_to_plane

        motion = Motion(image_to_plane(motion.joints).astype(np.float32), motion.fps, "h36m-17", motion.source)
    if not isinstance(motion, Motion) or motion.skeleton != "h36m-17" or motion.dim != 3:
        hint = " (2D keypoints: use a 2D model such as mtvae-add-2d, or a video, whose 3D pose is estimated)" \
            if isinstance(motion, Motion) and motion.dim == 2 else ""
        raise InputError(f"body models need 3D h36m-17 joints (BVH, motion npz, a video, ...), got skeleton "
                         f"{motion.skeleton} with D={motion.dim}{hint}", path)
    return _body_clip_from_motion(motion, name=path.name, fps=bundle.data_config.fps).data


def _face_data(bundle, motion, path: Path) -> np.ndarray:
    """(T, 58) face parameters at the model's rate (expressions clipped to [0, 1]); InputError for body motion."""
    from motion2video.data.dataset import _face_clip_from_motion

    if not isinstance(motion, FaceMotion):
        raise InputError(f"{bundle.label} is a face model, but this file holds body motion", path)
    cfg = bundle.data_config
    data = _face_clip_from_motion(motion, name=path.name, fps=cfg.fps, head_pose=cfg.face_head_pose).data
    data[:, :52] = np.clip(data[:, :52], 0.0, 1.0)
    return data


LOADERS = {"body3d": _body_data, "body2d": _body_data, "face": _face_data}


def is_video_path(path: str | Path) -> bool:
    """A video file (``.mp4``, ``.avi``, ``.mov``, ...) by its extension."""
    from motion2video.stages.people import is_video

    return is_video(path)


def _note(line: str) -> None:
    print(f"note: {line}", file=sys.stderr)


def video_motion(bundle, path: Path, *, person: str | int = "largest") -> Motion | FaceMotion:
    """The motion in a video for ``bundle``'s model, at the video's frame rate. Body models: the person's
    estimated pose (:func:`motion2video.stages.people.video_pose`, cached in the user cache by the file's hash):
    3D joints (metres, z up) for 3D body models, the 2D image keypoints for 2D body models (which see them
    through their virtual camera, :func:`motion2video.pose.h36m.image_to_plane`). Face models: the face
    motion tracked and fitted to the largest face (:func:`motion2video.stages.people.face_video_track`, cached
    likewise)."""
    from motion2video.pose.files import pose_motion_2d, pose_motion_3d
    from motion2video.stages.people import face_video_track, video_pose

    layout = bundle.data_config.layout
    if layout == "face":
        return face_video_track(path, note=_note).motion
    pose = video_pose(path, person=person, note=_note)
    return pose_motion_2d(pose, path) if layout == "body2d" else pose_motion_3d(pose, path)


def load_clip(bundle, path: str | Path, *, character: str | Path | None = None,
              fps: float | None = None, rig_map: str | Path | None = None) -> LoadedClip:
    """Read ``path`` for ``bundle``'s model (a :class:`~motion2video.models.checkpoint.ModelBundle`).

    Args:
        character: the character file of a DeepMimic motion file (default: found beside it, else the
            standard humanoid3d).
        rig_map: a BVH rig's rig map file (:func:`motion2video.formats.bvh.read_rig_map`).
        fps: the file's true frame rate, for files that state none or a wrong one (joint arrays: 20 fps
            for SMPL-22 by default).

    ``fps``: the clip's true frame rate, overriding what the file says (an OpenPose folder has none: 25
    without it); not for videos, whose rate is their own.

    Returns:
        A :class:`LoadedClip` at the model's rate.
    Raises:
        InputError: a folder, a missing or malformed file, body motion for a face model or the reverse, a body
        clip of another skeleton or 2D joints.
    """
    from motion2video.formats.io import load_motion

    path = Path(path)
    if path.is_dir() and bundle.data_config.layout != "body2d":
        raise InputError("a model takes one clip file, not a folder (OpenPose folders: 2D body models only)", path)
    if is_video_path(path):
        if fps is not None:
            raise InputError("a video has its own frame rate; --input-fps is for files without one (OpenPose, "
                             "joint arrays)", path)
        motion = video_motion(bundle, path)
    else:
        motion = load_motion(path, fps=fps, character=character, rig_map=rig_map)
    data = LOADERS[bundle.data_config.layout](bundle, motion, path)
    identity = dict(motion.identity) if isinstance(motion, FaceMotion) else {}
    source_frames = motion.num_frames
    return LoadedClip(data=data.astype(np.float32), fps=bundle.data_config.fps, source_fps=float(motion.fps),
                      source_frames=int(source_frames), path=str(path), identity=identity)


def model_frame(clip: LoadedClip, index: int, *, what: str) -> int:
    """Frame ``index`` of the file -> the nearest frame of the resampled clip; InputError when outside."""
    if not 0 <= index < clip.source_frames:
        raise InputError(f"{what} {index} is outside the clip (frames 0..{clip.source_frames - 1} at "
                         f"{clip.source_fps:g} fps)", clip.path)
    return min(int(np.floor(index * clip.fps / clip.source_fps + 0.5)), clip.num_frames - 1)  # half up
