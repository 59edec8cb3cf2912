"""A face video -> a face motion: face-mesh tracking, then the Anny head fitted frame by frame.

- :func:`track_faces`: a stream of video frames -> one :class:`~.facemesh.FaceLandmarks` (or None) per frame,
  following one face: the largest in the first frame with a face, then each frame's ROI from the previous
  frame's landmarks; the detector runs again (keeping the face nearest the last one) when the face-presence
  score falls below ``min_presence``.
- :func:`face_track_from_landmarks`: per-frame results -> :class:`FaceTrack`: frames without the face at the
  ends trimmed, the landmarks One-Euro smoothed (the body's image settings, speed in face sizes per second)
  and gaps inside linearly interpolated; then the person's own face measured as offsets from Anny's at the
  landmarks (a pose-only fit of every frame, the median residual: :func:`.face_fit.person_neutral_offsets`),
  and the head's pose and 52 ARKit coefficients fitted to each frame with those offsets
  (:func:`.face_fit.fit_frame`), the next frame starting from the last. The coefficients thus describe the
  expression, not the difference between the person's face and Anny's; the face motion drives Anny's own face.
- :func:`track_face_video`: a video file -> :class:`FaceTrack`, the data of ``motion2video pose --face``.

Head pose in the face motion: the rotation is the fitted one (world axes, as the face renderer turns the head).
The translation (metres) places the head as the video does: sideways and up / down from the fitted image
shift over the fitted scale, towards / away from the camera from the scale under a pinhole of focal length
equal to the frame's long side (:data:`FOCAL_PER_LONG_SIDE`); the clip's median is taken off, so the motion is
about the head's mean position.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.errors import InputError
from motion2video.core.motion import ARKIT_NAMES, FaceMotion
from motion2video.core.rotations import axis_angle_to_matrix
from motion2video.pose.estimate import interpolate_gaps, iter_video_frames, open_video
from motion2video.pose.face_anny import head_basis, head_offset, posed_landmarks
from motion2video.pose.face_fit import PROJECTION, FitConfig, FrameFit, fit_frame, person_neutral_offsets
from motion2video.pose.facemesh import (MIN_PRESENCE, NUM_POINTS, FaceDetection, FaceLandmarks, FaceMesh,
                                        detection_roi, shared_face_mesh)
from motion2video.pose.smoothing import IMAGE_LANDMARKS, one_euro, runs

FOCAL_PER_LONG_SIDE = 1.0  # the assumed pinhole focal length, in frame long sides (about 53 degrees across)
FACE_ESTIMATOR = "facemesh-anny-v1"  # names the face track's cache files; change it when the output changes

def track_faces(frames: Iterable[np.ndarray], *, model: FaceMesh | None = None,
                min_presence: float = MIN_PRESENCE) -> Iterator[FaceLandmarks | None]:
    """Follow one face through a stream of (H, W, 3) uint8 RGB frames (see the module docstring).

    Yields:
        the face's :class:`FaceLandmarks` per frame, or None where it is not found.
    """
    model = model or shared_face_mesh()
    roi = None
    last_centre: np.ndarray | None = None
    for frame in frames:
        lm = model.landmarks(frame, roi) if roi is not None else None
        if lm is None or lm.score < min_presence:
            detections = model.detect(frame)
            if not detections:
                roi = None
                yield None
                continue
            det = _choose_face(detections, last_centre)
            lm = model.landmarks(frame, detection_roi(det))
            if lm.score < min_presence:
                roi = None
                yield None
                continue
        roi = lm.next_roi()
        last_centre = lm.xy.mean(axis=0)
        yield lm


def _choose_face(detections: list[FaceDetection], last_centre: np.ndarray | None) -> FaceDetection:
    if last_centre is None:
        return max(detections, key=lambda d: d.area)
    return min(detections, key=lambda d: float(np.hypot(*(d.centre - last_centre))))


@dataclass(frozen=True)
class FaceTrack:
    """One face's motion in a video, frames without it at the ends trimmed.

    Attributes:
        motion: the :class:`FaceMotion` (52 ARKit coefficients, head rotation and translation per frame).
        landmarks2d: (T, 470, 2) the tracked points in the video's pixels: the face mesh's 468 landmarks, then the
            right and left iris centres (smoothed, gaps interpolated).
        confidence: (T,) face-presence score; 0 on interpolated frames.
        interpolated: (T,) True where the face was not found and the landmarks are interpolated.
        camera: (T, 3) the fitted weak-perspective camera: pixels per metre, then the (x, y) shift in pixels
            (:func:`motion2video.pose.face_fit.project`).
        neutral_offsets: (470, 3) the person's face as offsets from Anny's at the landmarks, metres in the
            head's rest frame (:func:`motion2video.pose.face_fit.person_neutral_offsets`).
        reprojection: (T, 470) distance in pixels between each landmark re-projected from the fitted Anny head
            and the tracked one.
        first_frame: index in the video of the first kept frame.
        width, height: the video's frame size; video_frames: how many frames it has.
    """

    motion: FaceMotion
    landmarks2d: np.ndarray
    confidence: np.ndarray
    interpolated: np.ndarray
    camera: np.ndarray
    neutral_offsets: np.ndarray
    reprojection: np.ndarray
    first_frame: int
    width: int
    height: int
    video_frames: int

    @property
    def num_frames(self) -> int:
        return self.motion.num_frames

    @property
    def gaps(self) -> int:
        return int(self.interpolated.sum())

    def face_size(self) -> np.ndarray:
        """(T,) the face's size in pixels per frame: the long side of its landmarks' bounding box."""
        return np.max(self.landmarks2d.max(axis=1) - self.landmarks2d.min(axis=1), axis=1)

    def relative_error(self) -> np.ndarray:
        """(T, 470) :attr:`reprojection` in face sizes."""
        return self.reprojection / self.face_size()[:, None]


def head_translation(rotations: np.ndarray, camera: np.ndarray, width: int, height: int) -> np.ndarray:
    """(T, 3) face-motion head translation from fitted rotations (T, 3) and cameras (T, 3) (see the module
    docstring): the renderer draws head vertex ``v`` at ``R v + c(R) + T``."""
    scale, shift = camera[:, 0], camera[:, 1:]
    focal = FOCAL_PER_LONG_SIDE * max(width, height)
    side = (shift[:, 0] - width / 2) / scale
    up = -(shift[:, 1] - height / 2) / scale
    depth = focal / scale
    placed = np.stack([side, depth, up], axis=1) - head_offset(rotations)  # (T, 3)
    return placed - np.median(placed, axis=0)


def reprojected_landmarks(motion: FaceMotion, camera: np.ndarray, offsets: np.ndarray | None = None
                          ) -> np.ndarray:
    """(T, 470, 2) pixels of the fitted head's landmark points seen by the fitted camera: the Anny head posed by
    the face motion through Anny's own forward (skinning and blendshapes as the face renderer draws them),
    plus the person's neutral offsets turned with the head.

    Args:
        motion: the fitted face motion; camera: (T, 3) scale and shift.
        offsets: (470, 3) the person's neutral offsets (None: Anny's own face).
    """
    points = posed_landmarks(motion.expressions, motion.head_rotation, motion.head_translation)  # (T, 470, 3)
    # undo what head_translation added, so the camera sees the head as it was fitted: R v + skinning
    points = points - (head_offset(motion.head_rotation) + motion.head_translation)[:, None, :]
    if offsets is not None:
        points = points + np.einsum("tij,lj->tli", axis_angle_to_matrix(motion.head_rotation), offsets)
    return camera[:, None, :1] * points @ PROJECTION.T + camera[:, None, 1:]


def fitted_landmarks2d(track: FaceTrack) -> np.ndarray:
    """(T, 470, 2) the landmarks re-projected from a track's fitted head (:func:`reprojected_landmarks`)."""
    return reprojected_landmarks(track.motion, track.camera, track.neutral_offsets)


def face_track_from_landmarks(results: list[FaceLandmarks | None], *, fps: float, width: int, height: int,
                              source: str | Path | None = None, smooth: bool = True,
                              config: FitConfig = FitConfig()) -> FaceTrack:
    """Per-frame tracking results -> :class:`FaceTrack` (trim, smooth, interpolate, fit).

    Raises:
        InputError: no face in any frame, or in only one.
    """
    found = np.array([r is not None for r in results])
    if not found.any():
        raise InputError("no face found in any frame", source)
    first, last = int(np.argmax(found)), len(found) - 1 - int(np.argmax(found[::-1]))
    if last == first:
        raise InputError("a face is found in only one frame; a motion needs at least two", source)
    kept, ok = results[first:last + 1], found[first:last + 1]
    blank = np.zeros((NUM_POINTS, 2))
    xy = np.stack([r.points() if r is not None else blank for r in kept])  # (T, 470, 2)
    score = np.array([r.score if r is not None else 0.0 for r in kept])
    if smooth:
        size = np.array([r.size if r is not None else 1.0 for r in kept])
        for start, stop in runs(ok):
            xy[start:stop] = one_euro(xy[start:stop], fps, IMAGE_LANDMARKS, scale=size[start:stop])
    xy = interpolate_gaps(xy, ok)
    basis = head_basis()
    rigid = _fit_frames(basis.neutral, basis.basis, xy, replace(config, unfitted=ARKIT_NAMES))
    offsets = person_neutral_offsets(basis.neutral, xy, rigid)  # (470, 3)
    fits = _fit_frames(basis.neutral + offsets, basis.basis, xy, config)
    rotations = np.stack([f.rotation for f in fits])
    camera = np.array([[f.scale, *f.shift] for f in fits])
    params = np.concatenate([np.stack([f.expressions for f in fits]), rotations,
                             head_translation(rotations, camera, width, height)], axis=1)
    motion = FaceMotion(params, float(fps), {}, None if source is None else str(source))
    error = np.linalg.norm(reprojected_landmarks(motion, camera, offsets) - xy, axis=2)  # (T, 470)
    return FaceTrack(motion, xy, np.where(ok, score, 0.0), ~ok, camera, offsets, error, first, width, height,
                     len(results))


def _fit_frames(neutral: np.ndarray, basis: np.ndarray, xy: np.ndarray, config: FitConfig) -> list[FrameFit]:
    """:func:`fit_frame` on (T, 470, 2) landmarks in order, each frame starting from the last one's fit."""
    fits: list[FrameFit] = []
    weights = config.weights()
    for frame in xy:
        fits.append(fit_frame(neutral, basis, frame, config, fits[-1] if fits else None, weights))
    return fits


def track_face_video(path: str | Path, *, model: FaceMesh | None = None, smooth: bool = True,
                     config: FitConfig = FitConfig()) -> FaceTrack:
    """The face motion of the one (largest) face in a video file (see the module docstring).

    Raises:
        InputError: unreadable video, no face, a face in fewer than two frames.
    """
    cap, info = open_video(path)
    cap.release()
    results = list(track_faces(iter_video_frames(path), model=model))
    if len(results) < 2:
        raise InputError(f"the video has {len(results)} frame; a motion needs at least two", path)
    return face_track_from_landmarks(results, fps=info.fps, width=info.width, height=info.height, source=path,
                                     smooth=smooth, config=config)


# --- the face motion file ----------------------------------------------------------------------------------

def save_face_track(path: str | Path, track: FaceTrack) -> Path:
    """Write a :class:`FaceTrack` as a face motion ``.npz`` (atomic): the keys every face reader takes
    (``face``, ``fps``, ``identity``; :func:`motion2video.formats.npz.load_face_npz`) plus ``landmarks_2d``,
    ``confidence``, ``interpolated``, ``camera``, ``neutral_offsets``, ``reprojection``, ``first_frame``,
    ``width``, ``height``, ``video_frames`` and ``estimator``."""

    return save_npz(path, {
        "face": track.motion.params.astype(np.float32),
        "fps": np.float64(track.motion.fps),
        "identity": np.str_(json.dumps(track.motion.identity, sort_keys=True)),
        "landmarks_2d": track.landmarks2d.astype(np.float32),
        "confidence": track.confidence.astype(np.float32),
        "interpolated": track.interpolated.astype(bool),
        "camera": track.camera.astype(np.float64),
        "neutral_offsets": track.neutral_offsets.astype(np.float64),
        "reprojection": track.reprojection.astype(np.float32),
        "first_frame": np.int64(track.first_frame),
        "width": np.int64(track.width),
        "height": np.int64(track.height),
        "video_frames": np.int64(track.video_frames),
        "estimator": np.str_(FACE_ESTIMATOR),
    })


def load_face_track(path: str | Path) -> FaceTrack:
    """Read a file :func:`save_face_track` wrote.

    Raises:
        InputError: not such a file (naming it).
    """
    from motion2video.formats.npz import load_face_npz, read_npz_arrays

    arrays = read_npz_arrays(path)
    keys = ("landmarks_2d", "confidence", "interpolated", "camera", "neutral_offsets", "reprojection", "first_frame",
            "width", "height", "video_frames")
    missing = [k for k in keys if k not in arrays]
    if missing:
        raise InputError(f"not a tracked face motion file (lacks {', '.join(missing)})", path)
    return FaceTrack(load_face_npz(path), arrays["landmarks_2d"].astype(np.float64),
                     arrays["confidence"].astype(np.float64), arrays["interpolated"].astype(bool),
                     arrays["camera"].astype(np.float64), arrays["neutral_offsets"].astype(np.float64),
                     arrays["reprojection"].astype(np.float64),
                     int(arrays["first_frame"]), int(arrays["width"]), int(arrays["height"]),
                     int(arrays["video_frames"]))
