"""Following one person through a video: what they look like and where they should be next.

Pure functions on one frame's BlazePose landmarks, used by :func:`motion2video.pose.estimate.track_frames`:

- :func:`torso_histogram`: the person's appearance, a colour histogram of the torso (the quadrilateral of the
  shoulders and hips, shrunk towards its centre so that the background at its sides stays out);
- :func:`appearance_distance`: Bhattacharyya distance of two histograms (0 = the same colours, 1 = none shared);
- :class:`MotionState`: the pelvis position, velocity and torso length of the frames so far, and where the
  pelvis should be in the next frame (constant velocity);
- :func:`check_candidate`: whether a landmark result is the followed person (presence, distance from the
  predicted position in torso lengths, appearance), only plausibly so (near, but looking somewhat different),
  and its cost among several candidates.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

L_SHOULDER, R_SHOULDER, L_HIP, R_HIP = 11, 12, 23, 24
HIST_BINS = (8, 8, 8)  # RGB bins: coarse enough for lighting changes, fine enough to tell clothes apart
TORSO_SHRINK = 0.7  # the torso quadrilateral scaled about its centre: background at the sides stays out


@dataclass(frozen=True)
class FollowConfig:
    """Thresholds of :func:`check_candidate`.

    Attributes:
        min_presence: BlazePose's pose presence score below which the frame has no person.
        max_jump: how far (in torso lengths) the pelvis may land from its predicted position (on the dancer video
            and a person approaching the camera it lands at most 0.11 away, 0.07 for 99% of the frames).
        jump_per_missed_frame: how much farther it may land per frame since the person was last seen (a walk
            moves the pelvis about 0.1 torso lengths a frame at 25 fps).
        max_appearance: Bhattacharyya distance of the torso histograms up to which it looks like the person (the
            dancer video's torso, hands and coloured gloves crossing it, stays under 0.41 of its first frame).
        max_appearance_unsure: up to which a candidate where the person should be is still taken, as unsure (a
            hand or an object across the torso, a change of light); beyond it, someone else (the dancer in black
            against a man in a red shirt: 0.97).
        appearance_rate: how fast the appearance model follows a confident frame (exponential average).
        reanchor_frames: after this many frames in a row taken as unsure by their look alone, the model moves
            halfway to the current look (the light changed for good).
    """

    min_presence: float = 0.5
    max_jump: float = 0.2
    jump_per_missed_frame: float = 0.1
    max_appearance: float = 0.45
    max_appearance_unsure: float = 0.75
    appearance_rate: float = 0.05
    reanchor_frames: int = 15


def pelvis_and_torso(xy: np.ndarray) -> tuple[np.ndarray, float]:
    """(2,) the hip midpoint and the torso length (shoulder midpoint to hip midpoint, pixels) of (33+, 2)
    landmarks."""
    hips = 0.5 * (xy[L_HIP] + xy[R_HIP])
    shoulders = 0.5 * (xy[L_SHOULDER] + xy[R_SHOULDER])
    return np.asarray(hips, np.float64), float(np.hypot(*(shoulders - hips)))


def torso_histogram(image: np.ndarray, xy: np.ndarray) -> np.ndarray | None:
    """(512,) float32 normalised RGB histogram of the torso of landmarks ``xy`` (33+, 2) in an (H, W, 3) uint8
    image; None when the torso covers under 20 pixels of the image."""
    quad = np.asarray(xy, np.float64)[[L_SHOULDER, R_SHOULDER, R_HIP, L_HIP]]
    quad = quad.mean(axis=0) + TORSO_SHRINK * (quad - quad.mean(axis=0))
    h, w = image.shape[:2]
    x0, y0 = np.floor(quad.min(axis=0)).astype(int)
    x1, y1 = np.ceil(quad.max(axis=0)).astype(int) + 1
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.fillConvexPoly(mask, np.rint(quad - (x0, y0)).astype(np.int32), 1)
    if int(mask.sum()) < 20:
        return None
    hist = cv2.calcHist([np.ascontiguousarray(image[y0:y1, x0:x1])], [0, 1, 2], mask, list(HIST_BINS),
                        [0, 256, 0, 256, 0, 256]).ravel()
    return (hist / max(float(hist.sum()), 1.0)).astype(np.float32)


def appearance_distance(a: np.ndarray | None, b: np.ndarray | None) -> float:
    """Bhattacharyya distance in [0, 1] of two normalised histograms; 0 when either is unknown."""
    if a is None or b is None:
        return 0.0
    return float(cv2.compareHist(a, b, cv2.HISTCMP_BHATTACHARYYA))


@dataclass(frozen=True)
class MotionState:
    """Where the followed person was and how they moved.

    Attributes:
        pelvis: (2,) last seen hip midpoint, pixels.
        velocity: (2,) pixels per frame (exponential average of the last frames' steps).
        torso: torso length, pixels (exponential average).
        missed: frames since the person was last seen.
        appearance: (512,) the torso histogram model, or None until one is seen.
        unlike: frames in a row taken although their look differed from the model.
    """

    pelvis: np.ndarray
    velocity: np.ndarray
    torso: float
    missed: int = 0
    appearance: np.ndarray | None = None
    unlike: int = 0

    @staticmethod
    def start(xy: np.ndarray, appearance: np.ndarray | None) -> "MotionState":
        pelvis, torso = pelvis_and_torso(xy)
        return MotionState(pelvis, np.zeros(2), max(torso, 1.0), 0, appearance)

    def predicted(self) -> np.ndarray:
        """(2,) where the pelvis should be in the next frame."""
        return self.pelvis + self.velocity * (self.missed + 1)

    def seen(self, xy: np.ndarray, found: "Candidate", config: "FollowConfig") -> "MotionState":
        """The state after the person was found at landmarks ``xy``, scored ``found``: a confident look (half the
        :attr:`FollowConfig.max_appearance`) moves the appearance model by the rate; a look unlike the model for
        :attr:`FollowConfig.reanchor_frames` frames in a row moves it halfway."""
        pelvis, torso = pelvis_and_torso(xy)
        step = (pelvis - self.pelvis) / (self.missed + 1)
        model, hist = self.appearance, found.histogram
        unlike = 0 if found.appearance <= config.max_appearance else self.unlike + 1
        if hist is not None and model is None:
            model = hist
        elif hist is not None and found.appearance <= 0.5 * config.max_appearance:
            model = ((1 - config.appearance_rate) * model + config.appearance_rate * hist).astype(np.float32)
        elif hist is not None and unlike >= config.reanchor_frames:
            model, unlike = (0.5 * model + 0.5 * hist).astype(np.float32), 0
        return MotionState(pelvis, 0.5 * self.velocity + 0.5 * step, 0.8 * self.torso + 0.2 * max(torso, 1.0), 0,
                           model, unlike)

    def lost(self) -> "MotionState":
        """The state after a frame without the person (the velocity fades)."""
        return replace(self, missed=self.missed + 1, velocity=0.8 * self.velocity)


@dataclass(frozen=True)
class Candidate:
    """How well one landmark result matches the followed person.

    Attributes:
        jump: distance of its pelvis from the predicted position, in torso lengths.
        appearance: Bhattacharyya distance of its torso histogram from the model.
        present: its pose presence reached the threshold.
        matches: present, near enough and alike enough to be the followed person.
        plausible: present, near enough, and not unlike enough to be someone else (taken when nothing matches,
            as unsure).
        cost: jump / allowed jump + appearance / max_appearance (lower is better).
        histogram: its torso histogram (None when the torso is not in the image).
    """

    jump: float
    appearance: float
    present: bool
    matches: bool
    plausible: bool
    cost: float
    histogram: np.ndarray | None


def check_candidate(image: np.ndarray, xy: np.ndarray, score: float, state: MotionState,
                    config: FollowConfig) -> Candidate:
    """Score landmarks ``xy`` (33+, 2) of presence ``score`` in ``image`` as the person of ``state``."""
    pelvis, _ = pelvis_and_torso(xy)
    jump = float(np.hypot(*(pelvis - state.predicted()))) / state.torso
    hist = torso_histogram(image, xy)
    appearance = appearance_distance(hist, state.appearance)
    present = score >= config.min_presence
    allowed = config.max_jump + config.jump_per_missed_frame * state.missed
    near = present and jump <= allowed
    matches = near and appearance <= config.max_appearance
    plausible = near and appearance <= config.max_appearance_unsure
    cost = jump / allowed + appearance / config.max_appearance
    return Candidate(jump, appearance, present, matches, plausible, cost, hist)
