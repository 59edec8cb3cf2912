"""A person's pose in a photo or a video, written as a file (the ``pose`` command's work): a photo gives its
reference pose file (the canonical H36M-17 joints in its pixels), a video a motion ``.npz`` at its own rate;
either optionally with the joints drawn on the input."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from motion2video.core.atomic import check_output_path
from motion2video.core.errors import InputError
from motion2video.pose.estimate import VideoPose
from motion2video.pose.face_track import FaceTrack, save_face_track
from motion2video.pose.files import save_video_pose
from motion2video.stages import people
from motion2video.stages.reference import reference_pose_path, save_reference_pose


@dataclass(frozen=True)
class PoseSettings:
    """One pose estimate.

    Attributes:
        input: a photo (.png, .jpg, ...) or a video (.mp4, .avi, .mov, .mkv, .webm).
        output: the ``.npz`` to write: a photo's reference pose file or a video's motion file.
        person: ``largest`` or an index counted left to right (0 = leftmost) in the first frame with people.
        overlay: also draw the joints on the input here (a .png for a photo, an .mp4 for a video), or None.
        face: the input is a face video: track its largest face and write its face motion instead of a body.
    """

    input: str | Path
    output: str | Path
    person: str | int = "largest"
    overlay: str | Path | None = None
    face: bool = False


@dataclass(frozen=True)
class PhotoPoseFile:
    """A photo's reference pose file: the estimate (:class:`motion2video.stages.people.PhotoPose`), the file
    written, the overlay written (or None) and the name ``synthesize`` looks for beside the photo."""

    photo: people.PhotoPose
    output: Path
    overlay: Path | None
    expected: Path


@dataclass(frozen=True)
class VideoPoseFile:
    """A video's motion file: the tracked pose, the file written and the overlay written (or None)."""

    pose: VideoPose
    output: Path
    overlay: Path | None


@dataclass(frozen=True)
class FacePoseFile:
    """A face video's face motion file: the track (:class:`motion2video.pose.face_track.FaceTrack`), the file
    written and the overlay written (or None)."""

    track: FaceTrack
    output: Path
    overlay: Path | None


def estimate_pose_file(settings: PoseSettings, *, note: Callable[[str], None] | None = None
                       ) -> PhotoPoseFile | VideoPoseFile | FacePoseFile:
    """Estimate the pose of ``settings.input``'s person and write it (and the overlay). A video's track is read
    from the user cache when any command tracked the same file before (and cached for the next one); ``note``
    hears which. InputError for a missing input, an unknown extension or an output of the wrong kind, before any
    estimate."""
    src = Path(settings.input)
    if not src.exists():
        raise InputError("no such file", src)
    video = people.is_video(src)
    if not video and not people.is_image(src):
        raise InputError(f"unsupported input extension {src.suffix or '(none)'!r}: a photo (.png, .jpg, ...) or a "
                         "video (.mp4, .avi, .mov, ...)", src)
    if settings.face and not video:
        raise InputError("--face takes a video (.mp4, .avi, .mov, ...)", src)
    if settings.face and settings.person != "largest":
        raise InputError("--person picks a body; --face follows the largest face")
    out = check_output_path(settings.output, (".npz",))
    if settings.overlay is not None:
        check_output_path(settings.overlay, (".mp4",) if video else (".png",))
    if settings.face:
        track = people.face_video_track(src, note=note)
        save_face_track(out, track)
        overlay = None if settings.overlay is None else people.write_face_overlay(settings.overlay, src, track)
        return FacePoseFile(track, out, overlay)
    if video:
        pose = people.video_pose(src, person=settings.person, note=note)
        save_video_pose(out, pose)
        overlay = None if settings.overlay is None else people.write_video_overlay(settings.overlay, src, pose)
        return VideoPoseFile(pose, out, overlay)
    photo = people.photo_pose(src, person=settings.person)
    save_reference_pose(out, people.reference_pose_of(photo.pose))
    overlay = None if settings.overlay is None else people.write_photo_overlay(settings.overlay, photo)
    return PhotoPoseFile(photo, out, overlay, reference_pose_path(src))
