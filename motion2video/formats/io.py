"""One entry point for reading and writing motion files, dispatching on the path.

======================================  ==============================================================
path                                    read as
======================================  ==============================================================
``*.bvh``, ``*.bvh.xz``                 :func:`~motion2video.formats.bvh.load_bvh` (canonical h36m-17, metres,
                                        z up; any humanoid rig, ``rig_map`` naming joints); a ``manifest.csv`` in its folder or up to three folders above
                                        that lists the file supplies fps, label and the rig's default trim
``*.txt``, or ``*.json`` holding        DeepMimic motion file (:mod:`~motion2video.formats.deepmimic`, the
``"Frames"``                            character file found beside it), same manifest rules
other ``*.txt``                         exp-map text file (:mod:`~motion2video.formats.expmap`, with the
                                        ``skeleton.json`` layout found beside or above it), same manifest rules
``*.npy``, or ``*.npz`` with one array  joint array (:mod:`~motion2video.formats.joint_arrays`): ``(T, 22, 3)``
                                        SMPL/HumanML3D joints (y up, 20 fps unless ``fps``) or ``(T, 17, 3)``
                                        H36M-17; never unpickled
``*.npz`` with ``joints``               body :class:`~motion2video.core.motion.Motion`
``*.npz`` with ``face``                 :class:`~motion2video.core.motion.FaceMotion`
``*.npz`` with ``positions_3d``         VideoPose3D Human3.6M file holding exactly one clip (else use
                                        :func:`~motion2video.formats.videopose3d.load_videopose3d`)
a directory, or another ``*.json``      OpenPose keypoints (2D, image pixels)
``*.csv``                               Live Link Face ARKit capture -> FaceMotion
======================================  ==============================================================
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.formats.face_csv import load_face_csv
from motion2video.formats.joint_arrays import is_joint_array, load_joint_array
from motion2video.formats.mocap import is_deepmimic_file, load_mocap
from motion2video.formats.npz import (
    load_face_npz,
    load_motion_npz,
    npz_keys,
    npz_kind,
    save_face_npz,
    save_motion_npz,
)
from motion2video.formats.openpose import load_openpose_folder
from motion2video.formats.resample import resample_linear
from motion2video.formats.videopose3d import load_videopose3d
from motion2video.core.motion import NUM_EXPRESSIONS, FaceMotion, Motion

MOTION_SUFFIXES = (".bvh", ".bvh.xz", ".txt", ".npz", ".npy", ".json", ".csv")


def _check_rate(value: float | None, name: str, path: Path) -> None:
    if value is not None and (not np.isfinite(value) or value <= 0):
        raise InputError(f"{name} must be a positive number, got {value}", path)


def resample_motion(motion: Motion | FaceMotion, target_fps: float) -> Motion | FaceMotion:
    """A copy of ``motion`` at ``target_fps`` by linear interpolation (positions / blendshape weights;
    for the small head rotations of face captures, interpolating axis-angle components is adequate)."""
    if target_fps == motion.fps:
        return motion
    if isinstance(motion, Motion):
        joints = resample_linear(motion.joints, motion.fps, target_fps)
        return Motion(joints.astype(np.float32), target_fps, motion.skeleton, motion.source, motion.label)
    params = resample_linear(motion.params, motion.fps, target_fps)
    params[:, :NUM_EXPRESSIONS] = np.clip(params[:, :NUM_EXPRESSIONS], 0.0, 1.0)
    return FaceMotion(params.astype(np.float32), target_fps, dict(motion.identity), motion.source, motion.label)


def load_motion(
    path: str | Path, *, fps: float | None = None, target_fps: float | None = None,
    character: str | Path | None = None, rig_map: str | Path | None = None,
) -> Motion | FaceMotion:
    """Read any supported motion file (see the module table).

    Args:
        path: file or OpenPose directory.
        fps: the true frame rate of the data, overriding what the file or manifest says.
        target_fps: resample the result to this rate (linear interpolation).
        character: the character file of DeepMimic motion files (default: found beside the motion, else
            the standard humanoid3d); other files ignore it.
        rig_map: BVH files only: a rig map file naming the joints of the body points where the rig's joint
            names do not tell (:func:`~motion2video.formats.bvh.read_rig_map`); other files ignore it.
    Raises:
        InputError: missing path, unknown extension, or a malformed file (one line naming the file).
    """
    path = Path(path)
    _check_rate(fps, "fps", path)
    _check_rate(target_fps, "target fps", path)
    if not path.exists():
        raise InputError("no such file or directory", path)
    suffix = path.suffix.lower()
    if (suffix in (".bvh", ".txt") or path.name.lower().endswith(".bvh.xz")
            or (suffix == ".json" and path.is_file() and is_deepmimic_file(path))):
        from motion2video.formats.bvh import read_rig_map

        return load_mocap(path, fps=fps, target_fps=target_fps, manifest=True, character=character,
                          rig_map=None if rig_map is None else read_rig_map(rig_map))
    if path.is_dir() or suffix == ".json":
        motion: Motion | FaceMotion = load_openpose_folder(path, fps=25.0 if fps is None else fps)
    elif suffix == ".csv":
        motion = load_face_csv(path, fps=fps)
    elif suffix == ".npy":
        motion = load_joint_array(path, fps=fps)
    elif suffix == ".npz":
        keys = npz_keys(path)
        kind = npz_kind(keys)
        if kind not in ("face", "videopose3d") and is_joint_array(path, keys):
            motion = load_joint_array(path, fps=fps)
        elif kind == "body":
            motion = load_motion_npz(path)
        elif kind == "face":
            motion = load_face_npz(path)
        elif kind == "videopose3d":
            clips = load_videopose3d(path)
            if len(clips) != 1:
                raise InputError(f"VideoPose3D file holds {len(clips)} clips; choose one with "
                                 "motion2video.formats.videopose3d.load_videopose3d(path, subject, action)", path)
            motion = clips[0]
        else:
            raise InputError("unknown .npz layout: expected key 'joints' (body), 'face' (face), "
                             "'positions_3d' (VideoPose3D), or exactly one joint array", path)
        if fps is not None:
            motion = _with_fps(motion, fps)
    else:
        raise InputError(f"unknown motion file extension {path.suffix!r}; expected one of "
                         f"{', '.join(MOTION_SUFFIXES)} or an OpenPose JSON directory", path)
    if target_fps is not None:
        motion = resample_motion(motion, target_fps)
    return motion


def _with_fps(motion: Motion | FaceMotion, fps: float) -> Motion | FaceMotion:
    if isinstance(motion, Motion):
        return Motion(motion.joints, fps, motion.skeleton, motion.source, motion.label)
    return FaceMotion(motion.params, fps, dict(motion.identity), motion.source, motion.label)


def save_motion(motion: Motion | FaceMotion, path: str | Path) -> Path:
    """Write a Motion or FaceMotion as ``.npz`` (atomic). Raises InputError for another extension."""
    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise InputError(f"motion files are written as .npz, got {path.suffix!r}", path)
    if isinstance(motion, FaceMotion):
        return save_face_npz(motion, path)
    return save_motion_npz(motion, path)
