"""One person followed through a whole video as the tracker saw them, frame by frame, with BlazePose's
person segmentation: what the reconstruction protocol (:mod:`motion2video.evaluation.reconstruction`) and
fine-tuning a frame generator on a video read.

Unlike :class:`~motion2video.pose.estimate.VideoPose` (smoothed, gaps interpolated, ends trimmed, no
segmentation), a :class:`VideoTrack` keeps every frame's raw landmarks, a flag for the frames where the person
was not found, and the segmentation over each frame's ROI as 8-bit probabilities (64 KB a frame in memory: 100
MB for a 1571-frame video). :func:`save_video_track` / :func:`load_video_track` write and read it as a
compressed ``.npz`` (the cache of :func:`motion2video.stages.people.video_track`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.errors import InputError
from motion2video.pose.blazepose import (LANDMARK_SIZE, NUM_BODY_LANDMARKS, NUM_LANDMARKS, BlazePose, Landmarks,
                                         Roi, roi_map_to_image)
from motion2video.pose.estimate import iter_video_frames, open_video, track_frames

TRACK_VERSION = 2  # 2: followed by appearance and motion, with the unsure flags
TRACK_KEYS = ("found", "unsure", "xy", "z", "world", "visibility", "presence", "score", "roi", "segmentation", "fps",
              "image_size", "version")


@dataclass(frozen=True)
class VideoTrack:
    """Per-frame tracking results of one person in a video (T = the frames the video decodes to).

    Attributes:
        found: (T,) bool, the person was found in the frame.
        unsure: (T,) bool, the tracker was unsure of the person there
            (:class:`~motion2video.pose.estimate.Tracked`).
        xy: (T, 39, 2) BlazePose image landmarks, pixels (zeros where not found).
        z: (T, 39); visibility, presence: (T, 39) in [0, 1]; world: (T, 39, 3) metres (see
            :class:`~motion2video.pose.blazepose.Landmarks`).
        score: (T,) pose presence score.
        roi: (T, 4) the landmark model's region: centre x, centre y, side, rotation (radians).
        segmentation: (T, 256, 256) uint8 person probability x 255 over each ROI crop.
        fps: the video's rate; width, height: its frame size.
    """

    found: np.ndarray
    unsure: np.ndarray
    xy: np.ndarray
    z: np.ndarray
    world: np.ndarray
    visibility: np.ndarray
    presence: np.ndarray
    score: np.ndarray
    roi: np.ndarray
    segmentation: np.ndarray
    fps: float
    width: int
    height: int

    @property
    def num_frames(self) -> int:
        return int(len(self.found))

    def body_landmarks(self, i: int) -> np.ndarray:
        """(33, 2) body landmarks of frame ``i`` in the video's pixels."""
        return self.xy[i, :NUM_BODY_LANDMARKS]

    def roi_of(self, i: int) -> Roi:
        cx, cy, size, rotation = (float(v) for v in self.roi[i])
        return Roi(np.array([cx, cy]), size, rotation)

    def landmarks(self, i: int) -> Landmarks | None:
        """Frame ``i``'s :class:`Landmarks` (without segmentation), None where the person was not found."""
        if not self.found[i]:
            return None
        return Landmarks(self.xy[i], self.z[i], self.visibility[i], self.presence[i], self.world[i],
                         float(self.score[i]), self.roi_of(i))

    def person_mask(self, i: int) -> np.ndarray:
        """(height, width) float32 person probability of frame ``i`` (zeros where not found), as
        :meth:`Landmarks.person_mask` draws it."""
        if not self.found[i]:
            return np.zeros((self.height, self.width), np.float32)
        prob = self.segmentation[i].astype(np.float32) * (1.0 / 255.0)
        return roi_map_to_image(prob, self.roi_of(i), self.width, self.height)


def track_video(path: str | Path, *, person: str | int = "largest", model: BlazePose | None = None) -> VideoTrack:
    """Follow one person through every frame of a video (:func:`~motion2video.pose.estimate.track_frames`).

    Raises:
        InputError: unreadable video, a video without frames, no person in any frame.
    """
    cap, info = open_video(path)
    cap.release()
    rows: list[Landmarks | None] = []
    unsure: list[bool] = []
    seg: list[np.ndarray] = []
    blank = np.zeros((LANDMARK_SIZE, LANDMARK_SIZE), np.uint8)
    for tracked in track_frames(iter_video_frames(path), person=person, model=model, source=path):
        lm = tracked.landmarks
        unsure.append(tracked.unsure)
        rows.append(None if lm is None else Landmarks(lm.xy, lm.z, lm.visibility, lm.presence, lm.world, lm.score,
                                                      lm.roi))
        if lm is None or lm.segmentation is None:
            seg.append(blank)
        else:
            prob = 1.0 / (1.0 + np.exp(-np.clip(lm.segmentation, -50, 50)))
            seg.append(np.rint(prob * 255.0).astype(np.uint8))
    if not any(r is not None for r in rows):
        raise InputError("no person found in any frame", path)
    t = len(rows)

    def stack(get, shape) -> np.ndarray:
        return np.stack([get(r) if r is not None else np.zeros(shape) for r in rows]).astype(np.float64)

    return VideoTrack(
        found=np.array([r is not None for r in rows]),
        unsure=np.array(unsure, bool),
        xy=stack(lambda r: r.xy, (NUM_LANDMARKS, 2)),
        z=stack(lambda r: r.z, (NUM_LANDMARKS,)),
        world=stack(lambda r: r.world, (NUM_LANDMARKS, 3)),
        visibility=stack(lambda r: r.visibility, (NUM_LANDMARKS,)),
        presence=stack(lambda r: r.presence, (NUM_LANDMARKS,)),
        score=np.array([r.score if r is not None else 0.0 for r in rows], np.float64),
        roi=stack(lambda r: [r.roi.centre[0], r.roi.centre[1], r.roi.size, r.roi.rotation], (4,)).reshape(t, 4),
        segmentation=np.stack(seg),
        fps=float(info.fps), width=int(info.width), height=int(info.height),
    )


def save_video_track(path: str | Path, track: VideoTrack) -> Path:
    """Write a :class:`VideoTrack` as a compressed ``.npz`` (atomically). Returns the path."""
    return save_npz(path, {
        "found": track.found, "unsure": track.unsure, "xy": track.xy, "z": track.z, "world": track.world, "visibility": track.visibility,
        "presence": track.presence, "score": track.score, "roi": track.roi, "segmentation": track.segmentation,
        "fps": np.float64(track.fps), "image_size": np.array([track.width, track.height], np.int64),
        "version": np.int64(TRACK_VERSION),
    }, compressed=True)


def load_video_track(path: str | Path) -> VideoTrack:
    """Read a file written by :func:`save_video_track`; InputError naming it when it is not one (or of
    another version)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError) as err:
        raise InputError(f"not a readable video track .npz ({type(err).__name__})", path) from None
    missing = [k for k in TRACK_KEYS if k not in data]
    if missing:
        raise InputError(f"not a video track file (lacks {', '.join(missing)})", path)
    if int(data["version"]) != TRACK_VERSION:
        raise InputError(f"video track version {int(data['version'])}, expected {TRACK_VERSION}", path)
    t = len(data["found"])
    shapes = {"xy": (t, NUM_LANDMARKS, 2), "world": (t, NUM_LANDMARKS, 3), "roi": (t, 4),
              "segmentation": (t, LANDMARK_SIZE, LANDMARK_SIZE)}
    for key, shape in shapes.items():
        if data[key].shape != shape:
            raise InputError(f"video track {key} has shape {data[key].shape}, expected {shape}", path)
    w, h = (int(v) for v in data["image_size"])
    return VideoTrack(data["found"].astype(bool), data["unsure"].astype(bool), data["xy"], data["z"], data["world"], data["visibility"],
                      data["presence"], data["score"], data["roi"], data["segmentation"].astype(np.uint8),
                      float(data["fps"]), w, h)
