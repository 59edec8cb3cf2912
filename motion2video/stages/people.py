"""Real people in: the pose of a photo or a video, ready for the applications.

- :func:`photo_pose`: a photo -> :class:`~motion2video.pose.estimate.PersonPose` and the reference pose
  (``IMAGE.pose.npz`` content) the frame generator reads;
- :func:`video_pose`: a video -> :class:`~motion2video.pose.estimate.VideoPose`, cached by the file's
  sha256 (next to an output, or in ``~/.cache/motion2video/pose``), so that running two commands on the
  same video estimates it once;
- :func:`video_track`: a video -> :class:`~motion2video.pose.track.VideoTrack` (every frame's raw landmarks
  and person segmentation: the reconstruction protocol and fine-tuning on a video), cached in the same folder;
  :func:`video_pose` derives its pose from a cached track instead of tracking the video again;
- :func:`face_video_track`: a face video -> :class:`~motion2video.pose.face_track.FaceTrack` (the face motion
  fitted to the tracked face mesh), cached in the same folder;
- :func:`write_photo_overlay` / :func:`write_video_overlay`: the keypoints drawn on the input.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable, TypeVar

import numpy as np

from motion2video.core.errors import InputError
from motion2video.pose.estimate import (IMAGE_SUFFIXES, VIDEO_SUFFIXES, PersonPose, VideoPose, estimate_image,
                                        estimate_video, iter_video_frames, poses_from_landmarks, read_image_rgb)
from motion2video.pose.files import ESTIMATOR, POSE_VERSION, load_video_pose, save_video_pose
from motion2video.pose.track import VideoTrack, load_video_track, save_video_track, track_video

if TYPE_CHECKING:  # the face track module loads Anny and the face renderer: imported when a face is tracked
    from motion2video.pose.face_track import FaceTrack

T = TypeVar("T")  # what a cache entry holds


def is_video(path: str | Path) -> bool:
    """A video file by its extension (``.mp4``, ``.avi``, ``.mov``, ...)."""
    return Path(path).suffix.lower() in VIDEO_SUFFIXES


def is_image(path: str | Path) -> bool:
    """A photo by its extension (``.png``, ``.jpg``, ...)."""
    return Path(path).suffix.lower() in IMAGE_SUFFIXES


def file_sha256(path: str | Path) -> str:
    """Hex sha256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def frame_ranges(flags: np.ndarray, first: int = 0, most: int = 6) -> str:
    """The runs of True in (T,) ``flags`` as video frame numbers (row 0 = frame ``first``): ``"159-182, 200"``;
    after ``most`` runs, how many more."""
    flags = np.asarray(flags, bool)
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    runs = [f"{a + first}" if a == b else f"{a + first}-{b + first}" for a, b in zip(starts, ends)]
    more = f" and {len(runs) - most} more runs" if len(runs) > most else ""
    return ", ".join(runs[:most]) + more


def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/motion2video/pose`` (default ``~/.cache/motion2video/pose``)."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "motion2video" / "pose"


def cache_path(video: str | Path, person: str | int, folder: str | Path | None = None) -> Path:
    """Where the pose of ``video`` (for ``person``) is cached: ``<sha256[:16]>-<person>.<estimator>.v<version>.npz``
    (the version of :mod:`motion2video.pose.files`: a cache of an older tracker is never read)."""
    folder = Path(folder) if folder is not None else cache_dir()
    return folder / f"{file_sha256(video)[:16]}-{person}.{ESTIMATOR}.v{POSE_VERSION}.npz"


def track_cache_path(video: str | Path, person: str | int, folder: str | Path | None = None) -> Path:
    """Where the track of ``video`` (for ``person``) is cached: ``<sha256[:16]>-<person>.<estimator>.v<version>.track.npz``
    beside the pose cache."""
    pose = cache_path(video, person, folder)
    return pose.with_name(pose.name.removesuffix(".npz") + ".track.npz")


def video_track(path: str | Path, *, person: str | int = "largest", cache: str | Path | None | bool = None,
                note: Callable[[str], None] | None = None, model=None) -> VideoTrack:
    """Every frame's landmarks and person segmentation of one person in a video, read from the cache when it
    was tracked before.

    Args:
        path: the video.
        person: ``"largest"`` or an index left to right.
        cache: a folder to cache in; None: the user cache (:func:`cache_dir`); False: no cache.
        note: called with one line when the video is tracked or read from the cache.
        model: the :class:`~motion2video.pose.blazepose.BlazePose` to track with (default: the shared one).
    Raises:
        InputError: unreadable video, no person in any frame.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such video file", path)
    cached = None if cache is False else track_cache_path(path, person, None if cache is None else cache)
    track = _read_cache(cached, load_video_track)
    if track is not None:
        if note:
            note(f"track of {path.name} read from the cache {cached}")
        return track
    track = track_video(path, person=person, model=model)
    if note:
        unsure = (f"; unsure of the person in {int(track.unsure.sum())} (frames {frame_ranges(track.unsure)})"
                  if track.unsure.any() else "")
        note(f"tracked {path.name} (BlazePose full): the person in {int(track.found.sum())} of "
             f"{track.num_frames} frames{unsure}")
    _write_cache(cached, save_video_track, track)
    return track


def video_pose(path: str | Path, *, person: str | int = "largest", cache: str | Path | None | bool = None,
               note: Callable[[str], None] | None = None) -> VideoPose:
    """The pose of one person in a video, read from the cache when it was estimated before.

    Args:
        path: the video.
        person: ``"largest"`` or an index left to right.
        cache: a folder to cache in; None: the user cache (:func:`cache_dir`); False: no cache.
        note: called with one line when the pose is estimated or read from the cache.
    Raises:
        InputError: unreadable video, no person, a person in fewer than two frames.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such video file", path)
    cached = None if cache is False else cache_path(path, person, None if cache is None else cache)
    pose = _read_cache(cached, load_video_pose)
    if pose is not None:
        if note:
            note(f"pose of {path.name} read from the cache {cached}" + _unsure_note(pose))
        return pose
    track = None if cache is False else _read_cache(track_cache_path(path, person, cache or None), load_video_track)
    if track is not None:  # tracked before by evaluate-frames / train-frames --video: the same landmarks
        pose = poses_from_landmarks([track.landmarks(i) for i in range(track.num_frames)], fps=track.fps,
                                    width=track.width, height=track.height, unsure=track.unsure, source=path)
    else:
        pose = estimate_video(path, person=person)
    if note:
        how = "from its cached track" if track is not None else "BlazePose full"
        note(f"estimated the pose of {path.name} ({how}): {pose.num_frames} frames at {pose.fps:g} fps"
             + (f", {pose.gaps} gap frames interpolated" if pose.gaps else "") + _unsure_note(pose))
    _write_cache(cached, save_video_pose, pose)
    return pose


def _read_cache(cached: Path | None, load: Callable[[Path], T]) -> T | None:
    """What ``load`` reads from the cache entry ``cached``, or None when there is none or it is damaged or of an
    older version (it is then computed again and overwritten)."""
    if cached is None or not cached.is_file():
        return None
    try:
        return load(cached)
    except InputError:
        return None


def _write_cache(cached: Path | None, save: Callable[[Path, T], object], value: T) -> None:
    """Save ``value`` to the cache entry ``cached`` (None: no cache); a read-only cache only costs the next run
    the computation."""
    if cached is None:
        return
    try:
        save(cached, value)
    except OSError:
        pass


def _unsure_note(pose: VideoPose) -> str:
    if not pose.unsure_frames:
        return ""
    return (f", the tracker unsure of the person in {pose.unsure_frames} frames "
            f"({frame_ranges(pose.unsure, pose.first_frame)})")


def face_cache_path(video: str | Path, folder: str | Path | None = None) -> Path:
    """Where the face track of ``video`` is cached: ``<sha256[:16]>-face.<face estimator>.npz`` beside the pose
    cache."""
    from motion2video.pose.face_track import FACE_ESTIMATOR

    folder = Path(folder) if folder is not None else cache_dir()
    return folder / f"{file_sha256(video)[:16]}-face.{FACE_ESTIMATOR}.npz"


def face_video_track(path: str | Path, *, cache: str | Path | None | bool = None,
                     note: Callable[[str], None] | None = None) -> FaceTrack:
    """The face motion of the (largest) face in a video, read from the cache when it was tracked before.

    Args:
        path: the video.
        cache: a folder to cache in; None: the user cache (:func:`cache_dir`); False: no cache.
        note: called with one line when the face is tracked or read from the cache.
    Raises:
        InputError: unreadable video, no face, a face in fewer than two frames.
    """
    from motion2video.pose.face_track import load_face_track, save_face_track, track_face_video

    path = Path(path)
    if not path.is_file():
        raise InputError("no such video file", path)
    cached = None if cache is False else face_cache_path(path, None if cache is None else cache)
    track = _read_cache(cached, load_face_track)
    if track is not None:
        if note:
            note(f"face track of {path.name} read from the cache {cached}")
        return track
    track = track_face_video(path)
    if note:
        note(f"tracked the face in {path.name} (face mesh + Anny head): {track.num_frames} frames at "
             f"{track.motion.fps:g} fps" + (f", {track.gaps} gap frames interpolated" if track.gaps else ""))
    _write_cache(cached, save_face_track, track)
    return track


@dataclass(frozen=True)
class PhotoPose:
    """A photo, its person's pose and what the generator needs of it.

    Attributes:
        image: (H, W, 3) uint8 RGB (cropped when a crop was asked for).
        pose: the estimated pose, in ``image``'s pixels.
        people: how many people were found.
    """

    image: np.ndarray
    pose: PersonPose
    people: int


def photo_pose(path: str | Path, *, person: str | int = "largest") -> PhotoPose:
    """The pose of one person in a photo file; InputError when it cannot be read or shows nobody."""
    image = read_image_rgb(path)
    pose = estimate_image(image, person=person, source=path)
    return PhotoPose(image, pose, pose.people)


def reference_pose_of(pose: PersonPose):
    """The body :class:`~motion2video.stages.reference.ReferencePose` of an estimated photo pose."""
    from motion2video.stages.reference import ReferencePose, person_camera_joints

    return ReferencePose("body", pose.width, pose.height, points=pose.points2d.astype(np.float64),
                         camera_joints=person_camera_joints(pose))


# --- overlays ------------------------------------------------------------------------------------------------

def write_photo_overlay(path: str | Path, photo: PhotoPose) -> Path:
    """The photo with its person's joints drawn, as a PNG (atomically)."""
    from motion2video.pose.overlay import draw_pose
    from motion2video.formats.video import write_image

    return write_image(path, draw_pose(photo.image, photo.pose.points2d))


def write_video_overlay(path: str | Path, video: str | Path, pose: VideoPose) -> Path:
    """The video with the tracked person's joints drawn on every kept frame (mp4 at the video's rate);
    interpolated frames are drawn with thinner lines."""
    from motion2video.pose.overlay import draw_pose, overlay_style
    from motion2video.formats.video import write_video

    style = overlay_style(pose.width, pose.height)
    thin = overlay_style(pose.width // 2, pose.height // 2)

    def frames():
        for i, frame in enumerate(iter_video_frames(video)):
            t = i - pose.first_frame
            if 0 <= t < pose.num_frames:
                yield draw_pose(frame, pose.points2d[t], style=thin if pose.interpolated[t] else style)
            elif t >= pose.num_frames:
                break

    return write_video(path, frames(), pose.fps, n_frames=pose.num_frames, preset="veryfast")


def write_face_overlay(path: str | Path, video: str | Path, track: "FaceTrack") -> Path:
    """The video with the tracked face landmarks (green) and those re-projected from the fitted head (red) drawn
    on every kept frame (mp4 at the video's rate)."""
    import cv2

    from motion2video.formats.video import write_video
    from motion2video.pose.face_track import fitted_landmarks2d

    fitted = fitted_landmarks2d(track)  # (T, 468, 2)
    radius = max(1, round(max(track.width, track.height) / 600))

    def frames():
        for i, frame in enumerate(iter_video_frames(video)):
            t = i - track.first_frame
            if not 0 <= t < track.num_frames:
                continue
            frame = frame.copy()
            for points, colour in ((track.landmarks2d[t], (0, 200, 0)), (fitted[t], (230, 0, 0))):
                for x, y in points:
                    cv2.circle(frame, (int(x), int(y)), radius, colour, -1)
            yield frame[None]

    return write_video(path, frames(), track.motion.fps)
