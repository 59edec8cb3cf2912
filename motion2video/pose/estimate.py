"""Pose of a person in a photo or a video: BlazePose landmarks -> canonical H36M-17 joints.

- :func:`estimate_image`: one photo -> :class:`PersonPose` (2D joints in its pixels, 3D joints in metres).
- :func:`track_frames`: a stream of video frames -> a :class:`Tracked` per frame (the person's BlazePose
  :class:`~.blazepose.Landmarks` or None, and whether the frame was unsure), following ONE person by appearance
  and motion (:mod:`motion2video.pose.follow`): the ROI of each frame comes from the previous frame's landmarks,
  and when that result fails a check (presence, a jump from the predicted position, a torso of other colours)
  the detector runs again and the candidate that matches the person's look and predicted position is taken.
- :func:`estimate_video`: a video file -> :class:`VideoPose` (frames without a person at the ends trimmed,
  landmarks smoothed as MediaPipe smooths them, gaps inside linearly interpolated, unsure frames flagged), the
  data of ``motion2video pose VIDEO``.

3D joints: BlazePose's world landmarks (hip-centred, metres) turned z up, on the canonical body points
(:func:`motion2video.core.skeletons.h36m_body_points`, skeleton version 2); the body's position in 3D comes from
the pelvis's pixel and the body's apparent size (:mod:`motion2video.pose.depth`): its distance from the camera
changes as the person walks towards or away from it.
The floor is put at z = 0, :data:`~motion2video.formats.canonical.ANKLE_HEIGHT` below the lowest ankle.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from motion2video.core.errors import InputError
from motion2video.core.skeletons import h36m_body_points
from motion2video.formats.canonical import floor_height
from motion2video.pose.blazepose import (NUM_BODY_LANDMARKS, BlazePose, Detection, Landmarks, Roi, box_iou,
                                          detection_roi)
from motion2video.pose.follow import Candidate, FollowConfig, MotionState, check_candidate, torso_histogram
from motion2video.pose.depth import default_focal, pixels_per_metre, root_path
from motion2video.pose.h36m import blazepose_to_h36m, world_to_project
from motion2video.pose.smoothing import smooth_landmarks

MIN_PRESENCE = 0.5
# A picture where BlazePose's person detector finds no one at its threshold (0.5) gets a second look
# (:func:`second_chance`): its detections from SECOND_CHANCE_SCORE up, each kept only when the landmark model is sure
# of a whole person there: presence >= SECOND_CHANCE_PRESENCE on the detection's region and again on the region its
# landmarks give (MediaPipe's tracking step), the 33 body landmarks' mean visibility >= SECOND_CHANCE_VISIBILITY, and
# all of them inside the picture. The detector keys on a face and upper body: a generated picture of a woman
# meditating cross-legged over a starry background, eyes closed, scored 0.43 (presence 0.999, visibility 0.79), and
# the tracksuit woman with her face and neck under a black square 0.49 (visibility 0.86). On 130 squares cut from the
# shared photos beside their person, presence alone took 10 for a person (visibility 0.32-0.71), these tests none
# (``git show dfbb875:scripts/measure_second_look.py``; docs/results.md, "A person the detector misses").
SECOND_CHANCE_SCORE = 0.3
SECOND_CHANCE_PRESENCE = 0.9
SECOND_CHANCE_VISIBILITY = 0.75
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".webp", ".tif", ".tiff")

_MODEL: BlazePose | None = None


def default_model() -> BlazePose:
    """One shared :class:`BlazePose` per process (the interpreters take ~50 ms to build)."""
    global _MODEL
    if _MODEL is None:
        _MODEL = BlazePose()
    return _MODEL


def order_people(detections: list[Detection]) -> list[Detection]:
    """Detections ordered left to right by hip centre (the index ``--person N`` counts in)."""
    return sorted(detections, key=lambda d: float(d.keypoints[0, 0]))


def landmark_extent(lm: Landmarks) -> float:
    """Size of a landmark result: the diagonal (pixels) of the 33 body landmarks' bounding box."""
    xy = lm.xy[:NUM_BODY_LANDMARKS]
    return float(np.hypot(*(xy.max(axis=0) - xy.min(axis=0))))


def choose_person(model: BlazePose, image: np.ndarray, detections: list[Detection], person: str | int,
                  source: str | Path | None = None) -> Landmarks:
    """The landmarks of the person ``person`` names among ``detections`` of ``image``: ``"largest"`` (the
    largest landmark bounding box of those with a pose) or an index counted left to right (by hip centre).

    Raises:
        InputError: no detection, or an index beyond the people found.
    """
    if not detections:
        raise InputError("no person found", source)
    if person == "largest":
        found = [model.landmarks(image, detection_roi(d)) for d in detections]
        present = [lm for lm in found if lm.score >= MIN_PRESENCE] or found
        return max(present, key=landmark_extent)
    people = order_people(detections)
    index = int(person)
    if not 0 <= index < len(people):
        raise InputError(f"--person {index}: {len(people)} people found (0..{len(people) - 1} left to right)",
                         source)
    return model.landmarks(image, detection_roi(people[index]))


def parse_person(value: str) -> str | int:
    """``--person`` argument: ``largest`` or a non-negative integer."""
    if value == "largest":
        return value
    try:
        index = int(value)
    except ValueError:
        raise ValueError(f"--person must be 'largest' or an index (0 = leftmost), got {value!r}") from None
    if index < 0:
        raise ValueError(f"--person must be 'largest' or an index >= 0, got {index}")
    return index


# --- joints from landmarks ----------------------------------------------------------------------------------

def landmarks_to_joints(xy: np.ndarray, world: np.ndarray, visibility: np.ndarray, *, width: int, height: int,
                        fps: float = 25.0, focal: float | None = None
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """BlazePose landmarks of T frames -> canonical joints with a root trajectory and the floor at 0.

    The root moves in 3D: its distance from the camera from the body's apparent size, its sideways and vertical
    position from its pixel at that distance (:mod:`motion2video.pose.depth`), relative to the first frame.

    Args:
        xy: (T, 33, 2) image pixels.
        world: (T, 33, 3) world landmarks (BlazePose axes: y down, metres, hip-centred).
        visibility: (T, 33) in [0, 1].
        width, height: the image size (the principal point is its centre).
        fps: frames per second (the apparent size is smoothed over
            :data:`~motion2video.pose.depth.DEPTH_WINDOW_S`).
        focal: the camera's focal length in pixels (default :func:`~motion2video.pose.depth.default_focal`).
    Returns:
        points2d (T, 17, 2) pixels, joints3d (T, 17, 3) metres z up floor at 0, confidence (T, 17).
    """
    points2d, confidence = blazepose_to_h36m(xy, visibility)
    raw, _ = blazepose_to_h36m(world_to_project(world))  # (T, 17, 3), pelvis at the origin
    # canonical skeleton v2: spine, neck/nose and head at Human3.6M's lengths scaled by the clip's leg, the
    # head along the thorax -> ears direction (the raw neck -> head direction)
    local = h36m_body_points(raw)
    local -= local[:, :1]
    focal = default_focal(width, height) if focal is None else float(focal)
    root = root_path(points2d[:, 0], pixels_per_metre(xy, world, visibility), focal=focal,
                     centre=np.array([0.5 * width, 0.5 * height]), fps=fps)  # (T, 3)
    root[:, :2] -= root[:1, :2]
    joints3d = local + root[:, None, :]
    joints3d[..., 2] -= floor_height(joints3d)
    return points2d, joints3d, confidence


@dataclass(frozen=True)
class PersonPose:
    """One person's pose in one image.

    Attributes:
        points2d: (17, 2) canonical H36M-17 joints in image pixels.
        joints3d: (17, 3) canonical joints, metres, z up, floor at 0.
        confidence: (17,) per-joint visibility in [0, 1].
        landmarks: the raw BlazePose result.
        width, height: image size in pixels.
        people: how many people the detector found.
    """

    points2d: np.ndarray
    joints3d: np.ndarray
    confidence: np.ndarray
    landmarks: Landmarks
    width: int
    height: int
    people: int

    def bounding_box(self) -> np.ndarray:
        """(4,) x_min, y_min, x_max, y_max of the 33 body landmarks, pixels."""
        return body_box(self.landmarks)


def estimate_image(image: np.ndarray, *, person: str | int = "largest", model: BlazePose | None = None,
                   source: str | Path | None = None, second_look: bool = True) -> PersonPose:
    """The pose of one person in an (H, W, 3) uint8 RGB image. When the detector finds no one and ``person`` is
    ``"largest"``, the detections under its threshold get a second look (:func:`second_chance`; off with
    ``second_look=False``, as the reconstruction protocol scores generated frames by the detector's own threshold).

    Raises:
        InputError: no person found (naming ``source``), or ``person`` beyond the people found.
    """
    model = model or default_model()
    detections = model.detect(image)
    people = len(detections)
    if not detections and person == "largest" and second_look:
        sure = second_chance(model, image)
        if not sure:
            raise InputError("no person found", source)
        lm, people = max(sure, key=landmark_extent), len(sure)
    else:
        lm = choose_person(model, image, detections, person, source)
    if lm.score < MIN_PRESENCE:
        raise InputError(f"no person found (pose presence {lm.score:.2f})", source)
    body = slice(0, NUM_BODY_LANDMARKS)
    p2, j3, conf = landmarks_to_joints(lm.xy[None, body], lm.world[None, body], lm.visibility[None, body],
                                       width=image.shape[1], height=image.shape[0])
    return PersonPose(p2[0], j3[0], conf[0], lm, image.shape[1], image.shape[0], people)


def second_chance(model: BlazePose, image: np.ndarray) -> list[Landmarks]:
    """The people of ``image`` (H, W, 3) uint8 RGB among its detections scoring :data:`SECOND_CHANCE_SCORE` or more,
    for a picture where no detection reaches the detector's own threshold: a detection counts when the landmark model
    is sure of a whole person there (:func:`whole_person`), on its region and on the region its landmarks give. Two
    detections of one person give poses whose body boxes overlap by more than half: the surer is kept.

    Returns:
        The landmarks (the second region's) of each person, surest first; empty when there is none.
    """
    h, w = image.shape[:2]
    sure = []
    for detection in model.detect(image, min_score=SECOND_CHANCE_SCORE):
        first = model.landmarks(image, detection_roi(detection))
        if first.score < SECOND_CHANCE_PRESENCE:
            continue
        lm = model.landmarks(image, first.next_roi())
        if whole_person(lm, w, h):
            sure.append(lm)
    people: list[Landmarks] = []
    for lm in sorted(sure, key=lambda lm: -lm.score):
        if not people or box_iou(body_box(lm), np.stack([body_box(p) for p in people])).max() <= 0.5:
            people.append(lm)
    return people


def whole_person(lm: Landmarks, width: int, height: int) -> bool:
    """Presence :data:`SECOND_CHANCE_PRESENCE` or more, the 33 body landmarks' mean visibility
    :data:`SECOND_CHANCE_VISIBILITY` or more, and all of them inside the ``width`` x ``height`` picture."""
    xy = lm.xy[:NUM_BODY_LANDMARKS]
    inside = bool(((xy >= 0) & (xy <= [width, height])).all())
    return (lm.score >= SECOND_CHANCE_PRESENCE and inside
            and float(lm.visibility[:NUM_BODY_LANDMARKS].mean()) >= SECOND_CHANCE_VISIBILITY)


def body_box(lm: Landmarks) -> np.ndarray:
    """(4,) x_min, y_min, x_max, y_max of the 33 body landmarks, pixels."""
    xy = lm.xy[:NUM_BODY_LANDMARKS]
    return np.concatenate([xy.min(axis=0), xy.max(axis=0)])


def read_image_rgb(path: str | Path) -> np.ndarray:
    """(H, W, 3) uint8 RGB of an image file (grey replicated, alpha dropped, 16-bit scaled to 8-bit).

    Raises:
        InputError: naming the file when it is missing, a folder or not a decodable image.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such image file" if not path.is_dir() else "a folder, not an image file", path)
    data = np.fromfile(path, np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if image is None:
        raise InputError("cannot decode the image (not a PNG/JPEG/... image file)", path)
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


# --- video -------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Tracked:
    """One video frame's result of :func:`track_frames`.

    Attributes:
        landmarks: the followed person's landmarks, None where they are not found.
        unsure: the landmarks from the person's last position failed a check (presence under the threshold, a
            jump from the predicted position, a torso of other colours): the detector was asked again, and the
            frame has the candidate that matches the person (or none).
    """

    landmarks: Landmarks | None
    unsure: bool


def track_frames(frames: Iterable[np.ndarray], *, person: str | int = "largest",
                 model: BlazePose | None = None, config: FollowConfig = FollowConfig(),
                 source: str | Path | None = None) -> Iterator[Tracked]:
    """Follow one person through a stream of (H, W, 3) uint8 RGB frames, by appearance and motion.

    The person is chosen (``person``) in the first frame where the detector finds anyone; their torso's colour
    histogram and pelvis motion are followed from then on (:mod:`motion2video.pose.follow`). Each frame's ROI
    comes from the previous frame's landmarks; when its result fails a check (presence, a jump from the
    pelvis's predicted position, a torso of other colours), the detector runs again and, of the people it finds
    (and that result), the one that passes the checks at the least cost is taken, else the one near the predicted
    position whose look is only somewhat different (a hand across the torso, a change of light); when none is,
    the frame has no person (a passer-by in front, the person out of view) and the ROI moves on with the
    predicted motion. Such frames are unsure.

    Yields:
        a :class:`Tracked` per frame.
    """
    model = model or default_model()
    roi: Roi | None = None
    state: MotionState | None = None
    for frame in frames:
        if state is None:
            detections = model.detect(frame)
            lm = choose_person(model, frame, detections, person, source) if detections else None
            if lm is None or lm.score < config.min_presence:
                yield Tracked(None, False)
                continue
            state = MotionState.start(lm.xy, torso_histogram(frame, lm.xy))
            roi = lm.next_roi()
            yield Tracked(lm, False)
            continue
        best: tuple[Landmarks, Candidate] | None = None
        if roi is not None:
            lm = model.landmarks(frame, roi)
            found = check_candidate(frame, lm.xy, lm.score, state, config)
            if found.matches:
                best = (lm, found)
        unsure = best is None
        if best is None:
            candidates = [model.landmarks(frame, detection_roi(d)) for d in model.detect(frame)]
            scored = [(c, check_candidate(frame, c.xy, c.score, state, config)) for c in candidates]
            if roi is not None:
                scored.append((lm, found))
            matching = [pair for pair in scored if pair[1].matches] or [pair for pair in scored if pair[1].plausible]
            best = min(matching, key=lambda pair: pair[1].cost) if matching else None
        if best is None:
            step = state.velocity
            state = state.lost()
            if roi is not None:
                roi = Roi(roi.centre + step, roi.size, roi.rotation)
            yield Tracked(None, True)
            continue
        lm, found = best
        state = state.seen(lm.xy, found, config)
        roi = lm.next_roi()
        yield Tracked(lm, unsure)


@dataclass(frozen=True)
class VideoInfo:
    """What a video file says about itself: fps, frame size, frame count (None when unknown)."""

    fps: float
    width: int
    height: int
    frames: int | None


def quiet_libav() -> None:
    """Keep OpenCV's FFmpeg backend from printing libav's own messages ("moov atom not found") on stderr before
    the one-line InputError that says the same. The backend reads the level when it first opens a file, so this
    runs before every open; a user's ``OPENCV_FFMPEG_LOGLEVEL`` or ``OPENCV_FFMPEG_DEBUG`` is left as it is."""
    if "OPENCV_FFMPEG_LOGLEVEL" not in os.environ and "OPENCV_FFMPEG_DEBUG" not in os.environ:
        os.environ["OPENCV_FFMPEG_LOGLEVEL"] = "-8"  # AV_LOG_QUIET


def open_video(path: str | Path) -> tuple[cv2.VideoCapture, VideoInfo]:
    """Open a video for reading; InputError naming it when it is missing or cannot be decoded."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such video file", path)
    quiet_libav()
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise InputError("cannot read the video (not a video file, or an unsupported codec)", path)
    fps = float(cap.get(cv2.CAP_PROP_FPS))
    count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    width, height = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
    if not np.isfinite(fps) or fps <= 0 or fps > 1000:
        cap.release()
        raise InputError(f"the video does not say its frame rate (got {fps})", path)
    if width <= 0 or height <= 0:
        cap.release()
        raise InputError("cannot read the video's frame size", path)
    return cap, VideoInfo(fps, width, height, count if count > 0 else None)


def iter_video_frames(path: str | Path) -> Iterator[np.ndarray]:
    """(H, W, 3) uint8 RGB frames of a video file, streamed; InputError when it has none."""
    cap, _ = open_video(path)
    try:
        n = 0
        while True:
            ok, frame = cap.read()
            if not ok:
                break
            n += 1
            yield cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)
        if n == 0:
            raise InputError("the video has no readable frames", path)
    finally:
        cap.release()


@dataclass(frozen=True)
class VideoPose:
    """One person's motion in a video, frames without them at the ends trimmed.

    Attributes:
        points2d: (T, 17, 2) canonical joints in the video's pixels.
        joints3d: (T, 17, 3) canonical joints, metres, z up, floor at 0.
        confidence: (T, 17) per-joint visibility; 0 on interpolated frames.
        interpolated: (T,) True where the person was not found and the joints are interpolated.
        landmarks2d: (T, 33, 2) BlazePose's image landmarks (interpolated likewise).
        fps: the video's frame rate.
        first_frame: index in the video of the first kept frame.
        width, height: the video's frame size.
        video_frames: how many frames the video has.
        unsure: (T,) True where the tracker was unsure of the person (see :class:`Tracked`); every
            interpolated frame is unsure too.
    """

    points2d: np.ndarray
    joints3d: np.ndarray
    confidence: np.ndarray
    interpolated: np.ndarray
    landmarks2d: np.ndarray
    fps: float
    first_frame: int
    width: int
    height: int
    video_frames: int
    unsure: np.ndarray

    @property
    def num_frames(self) -> int:
        return len(self.points2d)

    @property
    def unsure_frames(self) -> int:
        """Number of frames the tracker was unsure of."""
        return int(self.unsure.sum())

    @property
    def gaps(self) -> int:
        """Number of interpolated frames."""
        return int(self.interpolated.sum())


def interpolate_gaps(values: np.ndarray, found: np.ndarray) -> np.ndarray:
    """Fill the frames where ``found`` is False by linear interpolation in time.

    Args:
        values: (T, ...) per-frame arrays (anything on missing frames).
        found: (T,) bool, True at least at the first and last frame.
    Returns:
        (T, ...) float64 with the missing frames filled.
    """
    t = np.arange(len(found))
    flat = np.asarray(values, np.float64).reshape(len(found), -1)
    out = np.empty_like(flat)
    for k in range(flat.shape[1]):
        out[:, k] = np.interp(t, t[found], flat[found, k])
    return out.reshape(np.shape(values))


def poses_from_landmarks(results: list[Landmarks | None], *, fps: float, width: int, height: int,
                         unsure: np.ndarray | None = None, source: str | Path | None = None,
                         smooth: bool = True) -> VideoPose:
    """Per-frame tracking results -> :class:`VideoPose` (trim the ends, smooth, interpolate the gaps).

    ``unsure``: (len(results),) the tracker's unsure flags (default: the frames without a person). ``smooth``:
    MediaPipe's One-Euro smoothing of the landmarks (:mod:`motion2video.pose.smoothing`), each run of frames with
    the person on its own.

    Raises:
        InputError: no person in any frame, or in fewer than 2 frames (a motion needs two).
    """
    found = np.array([r is not None for r in results])
    if not found.any():
        raise InputError("no person found in any frame", source)
    first, last = int(np.argmax(found)), len(found) - 1 - int(np.argmax(found[::-1]))
    if last == first:
        raise InputError("a person is found in only one frame; a motion needs at least two", source)
    kept = results[first:last + 1]
    ok = found[first:last + 1]
    doubt = ~ok if unsure is None else np.asarray(unsure, bool)[first:last + 1] | ~ok
    body = slice(0, NUM_BODY_LANDMARKS)
    blank = np.zeros((NUM_BODY_LANDMARKS, 1))
    xy = np.stack([r.xy[body] if r is not None else blank.repeat(2, 1) for r in kept])  # (T, 33, 2)
    world = np.stack([r.world[body] if r is not None else blank.repeat(3, 1) for r in kept])  # (T, 33, 3)
    vis = np.stack([r.visibility[body] if r is not None else blank[:, 0] for r in kept])  # (T, 33)
    if smooth:
        size = np.array([r.roi.size if r is not None else 1.0 for r in kept])
        xy, world, vis = smooth_landmarks(xy, world, vis, size, ok, fps)
    xy, world = interpolate_gaps(xy, ok), interpolate_gaps(world, ok)
    points2d, joints3d, confidence = landmarks_to_joints(xy, world, vis, width=width, height=height, fps=fps)
    confidence[~ok] = 0.0
    return VideoPose(points2d, joints3d, confidence, ~ok, xy, float(fps), first, width, height, len(results), doubt)


def estimate_video(path: str | Path, *, person: str | int = "largest", model: BlazePose | None = None,
                   smooth: bool = True) -> VideoPose:
    """The motion of one person in a video file (see the module docstring).

    Raises:
        InputError: unreadable video, no person, a person in fewer than two frames.
    """
    cap, info = open_video(path)
    cap.release()
    tracked = list(track_frames(iter_video_frames(path), person=person, model=model, source=path))
    # the segmentation (256 KB a frame) is not kept: a long video's landmarks stay a few MB
    results = [None if t.landmarks is None else replace(t.landmarks, segmentation=None) for t in tracked]
    if len(results) < 2:
        raise InputError(f"the video has {len(results)} frame; a motion needs at least two", path)
    return poses_from_landmarks(results, fps=info.fps, width=info.width, height=info.height,
                                unsure=np.array([t.unsure for t in tracked]), source=path, smooth=smooth)
