"""MediaPipe BlazePose (full) run through LiteRT, with the project's own pre- and post-processing.

Two bundled Apache-2.0 models (``motion2video/weights/blazepose.md``):

- the detector ``pose_detection.tflite``: a 224 x 224 letterboxed RGB image in [-1, 1] -> 2254 SSD boxes of
  12 values (box centre, size, 4 keypoints: hip centre, full-body scale point, shoulder centre, upper-body
  scale point) and a score logit;
- the landmark model ``pose_landmark_full.tflite``: a 256 x 256 RGB crop in [0, 1] of a rotated square
  region of interest (ROI) -> 39 landmarks x (x, y, z, visibility logit, presence logit) in crop pixels, a
  pose-presence score, a 64 x 64 x 39 heatmap and 39 world landmarks (metres, hip-centred, y down).

The constants follow MediaPipe's graphs (``pose_detection_cpu.pbtxt``, ``pose_detection_to_roi.pbtxt``,
``pose_landmarks_to_roi.pbtxt``, ``tensors_to_pose_landmarks_and_segmentation.pbtxt``); the code is written
here from those facts. Every geometric step is a pure function on arrays; :class:`BlazePose` only holds the
two interpreters.

Coordinates: image pixels, x right, y down, origin at the top-left corner of the top-left pixel.
"""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np

WEIGHTS = Path(__file__).resolve().parent.parent / "weights"
DETECTOR_FILE = WEIGHTS / "pose_detection.tflite"
LANDMARK_FILE = WEIGHTS / "pose_landmark_full.tflite"

DETECTOR_SIZE = 224
LANDMARK_SIZE = 256
NUM_LANDMARKS = 39  # 33 body landmarks + 2 ROI landmarks (33 hip centre, 34 scale point) + 4 unused
HEATMAP_KERNEL = 7
HEATMAP_MIN_CONFIDENCE = 0.5
DETECTION_MIN_SCORE = 0.5
NMS_MIN_IOU = 0.3
SCORE_CLIP = 100.0
ROI_SCALE = 1.25
ROI_TARGET_ANGLE = np.pi / 2  # the hip -> scale-point vector points up in the crop (90 degrees)

# BlazePose's 33 body landmarks.
LANDMARK_NAMES: tuple[str, ...] = (
    "nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye", "right_eye_outer",
    "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder", "right_shoulder", "left_elbow",
    "right_elbow", "left_wrist", "right_wrist", "left_pinky", "right_pinky", "left_index", "right_index",
    "left_thumb", "right_thumb", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle",
    "right_ankle", "left_heel", "right_heel", "left_foot_index", "right_foot_index",
)
NUM_BODY_LANDMARKS = 33


# --- detector ----------------------------------------------------------------------------------------------

@lru_cache(maxsize=None)
def ssd_anchors(size: int = DETECTOR_SIZE, strides: tuple[int, ...] = (8, 16, 32, 32, 32),
                anchors_per_layer: int = 2) -> np.ndarray:
    """Anchor centres of MediaPipe's SsdAnchorsCalculator for the pose detector.

    Options of ``pose_detection_cpu.pbtxt``: 5 layers, strides 8, 16, 32, 32, 32, aspect ratio 1 plus the
    interpolated scale (2 anchors per layer and cell), fixed anchor size (width = height = 1), offset 0.5.
    Consecutive layers with the same stride share one grid, so a cell of the stride-32 grid has 6 anchors.

    Returns:
        (N, 2) anchor centres (x, y), normalised to [0, 1]; N = 2254 for the defaults.
    """
    centres = []
    layer = 0
    while layer < len(strides):
        last = layer
        while last < len(strides) and strides[last] == strides[layer]:
            last += 1
        repeats = anchors_per_layer * (last - layer)
        cells = int(np.ceil(size / strides[layer]))
        ys, xs = np.meshgrid((np.arange(cells) + 0.5) / cells, (np.arange(cells) + 0.5) / cells, indexing="ij")
        grid = np.stack([xs.ravel(), ys.ravel()], axis=1)  # (cells^2, 2), row-major (y outer, x inner)
        centres.append(np.repeat(grid, repeats, axis=0))
        layer = last
    return np.concatenate(centres, axis=0)


def letterbox(image: np.ndarray, size: int = DETECTOR_SIZE) -> tuple[np.ndarray, float, np.ndarray]:
    """Scale an image to fit a ``size`` square, centred, zero-padded (ImageToTensor, keep_aspect_ratio).

    Args:
        image: (H, W, 3) uint8 RGB.
    Returns:
        (size, size, 3) float32 in [-1, 1], the scale (input pixels per image pixel), and the (2,) offset
        (x, y) in input pixels of the image's top-left corner.
    """
    h, w = image.shape[:2]
    scale = size / max(h, w)
    nw, nh = max(1, round(w * scale)), max(1, round(h * scale))
    out = np.zeros((size, size, 3), np.uint8)
    ox, oy = (size - nw) // 2, (size - nh) // 2
    out[oy:oy + nh, ox:ox + nw] = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_AREA)
    offset = np.array([ox + (nw - w * scale) / 2, oy + (nh - h * scale) / 2])
    return out.astype(np.float32) / 127.5 - 1.0, scale, offset


@dataclass(frozen=True)
class Detection:
    """One person found by the detector, in image pixels.

    Attributes:
        score: detection probability in [0, 1].
        box: (4,) x_min, y_min, x_max, y_max.
        keypoints: (4, 2) hip centre, full-body scale point, shoulder centre, upper-body scale point.
    """

    score: float
    box: np.ndarray
    keypoints: np.ndarray

    @property
    def area(self) -> float:
        return float(max(0.0, self.box[2] - self.box[0]) * max(0.0, self.box[3] - self.box[1]))


def decode_detections(raw_boxes: np.ndarray, raw_scores: np.ndarray, anchors: np.ndarray,
                      size: int = DETECTOR_SIZE, min_score: float = DETECTION_MIN_SCORE
                      ) -> tuple[np.ndarray, np.ndarray]:
    """SSD decoding of the detector's outputs (TensorsToDetectionsCalculator, reverse_output_order).

    Args:
        raw_boxes: (N, 4 + 2K) x, y, w, h, then K keypoints (x, y), in input pixels relative to the anchor
            (K = 4 for the pose detector, 6 for the face detector).
        raw_scores: (N,) score logits.
        anchors: (N, 2) anchor centres, normalised.
    Returns:
        (M, 4 + 2K) decoded boxes (x_min, y_min, x_max, y_max, then K keypoints (x, y)) normalised to the
        detector input, and (M,) scores, for the M anchors scoring at least ``min_score``.
    """
    scores = 1.0 / (1.0 + np.exp(-np.clip(raw_scores.astype(np.float64), -SCORE_CLIP, SCORE_CLIP)))
    keep = scores >= min_score
    raw, anc, scores = raw_boxes[keep] / size, anchors[keep], scores[keep]
    centre = raw[:, 0:2] + anc  # (M, 2)
    half = raw[:, 2:4] / 2
    num_keypoints = (raw_boxes.shape[1] - 4) // 2
    kps = raw[:, 4:].reshape(len(raw), num_keypoints, 2) + anc[:, None, :]  # (M, K, 2)
    out = np.concatenate([centre - half, centre + half, kps.reshape(len(raw), 2 * num_keypoints)], axis=1)
    return out, scores


def box_iou(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(M,) intersection over union of one (4,) box with (M, 4) boxes (x_min, y_min, x_max, y_max)."""
    lo = np.maximum(box[:2], boxes[:, :2])
    hi = np.minimum(box[2:4], boxes[:, 2:4])
    inter = np.prod(np.clip(hi - lo, 0, None), axis=1)
    area = np.prod(box[2:4] - box[:2])
    areas = np.prod(boxes[:, 2:4] - boxes[:, :2], axis=1)
    return inter / np.maximum(area + areas - inter, 1e-12)


def weighted_nms(boxes: np.ndarray, scores: np.ndarray, min_iou: float = NMS_MIN_IOU
                 ) -> tuple[np.ndarray, np.ndarray]:
    """MediaPipe's WEIGHTED non-maximum suppression.

    The best remaining box takes every remaining box overlapping it by more than ``min_iou`` (itself
    included) and becomes their score-weighted mean (box and keypoints); its score stays the best score.

    Args:
        boxes: (M, K) boxes whose first 4 values are x_min, y_min, x_max, y_max (the rest are averaged too).
        scores: (M,) scores.
    Returns:
        (P, K) merged boxes and (P,) scores, best first.
    """
    order = np.argsort(-scores, kind="stable")
    boxes, scores = boxes[order], scores[order]
    out_boxes, out_scores = [], []
    while len(scores):
        iou = box_iou(boxes[0, :4], boxes[:, :4])
        group = iou > min_iou
        group[0] = True
        w = scores[group][:, None]
        out_boxes.append((boxes[group] * w).sum(axis=0) / w.sum())
        out_scores.append(scores[0])
        boxes, scores = boxes[~group], scores[~group]
    if not out_boxes:
        return np.zeros((0, boxes.shape[1])), np.zeros(0)
    return np.stack(out_boxes), np.asarray(out_scores)


# --- region of interest --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Roi:
    """A rotated square region of the image, the landmark model's input.

    Attributes:
        centre: (2,) x, y in pixels.
        size: side in pixels.
        rotation: radians; a crop's +x axis is the image's (cos, sin) direction (y down).
    """

    centre: np.ndarray
    size: float
    rotation: float


def normalize_radians(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return float(angle - 2 * np.pi * np.floor((angle + np.pi) / (2 * np.pi)))


def roi_from_points(centre: np.ndarray, scale_point: np.ndarray, scale: float = ROI_SCALE) -> Roi:
    """The ROI of AlignmentPointsRectsCalculator + RectTransformationCalculator (scale 1.25, square long).

    The square is centred on ``centre`` (the hip centre), its side is twice the distance to
    ``scale_point`` times ``scale``, and it is rotated so that centre -> scale point points up in the crop.

    Args:
        centre, scale_point: (2,) pixels.
    """
    d = np.asarray(scale_point, np.float64) - np.asarray(centre, np.float64)
    size = 2.0 * float(np.hypot(*d)) * scale
    rotation = normalize_radians(ROI_TARGET_ANGLE - np.arctan2(-d[1], d[0]))
    return Roi(np.asarray(centre, np.float64), size, rotation)


def roi_matrix(roi: Roi, out_size: int = LANDMARK_SIZE) -> np.ndarray:
    """(2, 3) affine map from crop pixels (continuous, [0, out_size]) to image pixels."""
    c, s = np.cos(roi.rotation), np.sin(roi.rotation)
    rot = np.array([[c, -s], [s, c]]) * (roi.size / out_size)
    offset = roi.centre - rot @ np.array([out_size / 2, out_size / 2])
    return np.concatenate([rot, offset[:, None]], axis=1)


def crop_roi(image: np.ndarray, roi: Roi, out_size: int = LANDMARK_SIZE) -> np.ndarray:
    """(out_size, out_size, 3) float32 [0, 1] crop of the ROI from (H, W, 3) uint8 RGB (border replicated)."""
    mat = roi_matrix(roi, out_size)
    # OpenCV maps pixel indices (centres at integers); ours maps continuous coordinates (centres at +0.5).
    mat[:, 2] += mat[:, :2] @ np.array([0.5, 0.5]) - 0.5
    crop = cv2.warpAffine(image, mat, (out_size, out_size),
                          flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE)
    return crop.astype(np.float32) * (1.0 / 255.0)


def refine_from_heatmap(xy: np.ndarray, heatmap: np.ndarray, kernel: int = HEATMAP_KERNEL,
                        min_confidence: float = HEATMAP_MIN_CONFIDENCE) -> np.ndarray:
    """RefineLandmarksFromHeatmapCalculator: move each landmark to the sigmoid-weighted mean of its
    ``kernel`` x ``kernel`` heatmap window when the window's peak confidence reaches ``min_confidence``.

    Args:
        xy: (L, 2) landmarks normalised to the crop, [0, 1].
        heatmap: (h, w, L) logits.
    Returns:
        (L, 2) refined landmarks, normalised.
    """
    hh, hw, _ = heatmap.shape
    out = xy.copy()
    half = (kernel - 1) // 2
    for i, (x, y) in enumerate(xy):
        col, row = int(x * hw), int(y * hh)  # truncation, as MediaPipe
        if not (0 <= col < hw and 0 <= row < hh):
            continue
        r0, r1, c0, c1 = max(0, row - half), min(hh, row + half + 1), max(0, col - half), min(hw, col + half + 1)
        conf = 1.0 / (1.0 + np.exp(-heatmap[r0:r1, c0:c1, i]))  # (kh, kw)
        total = conf.sum()
        if conf.max() >= min_confidence and total > 0:
            rows, cols = np.mgrid[r0:r1, c0:c1]
            out[i] = ((cols * conf).sum() / hw / total, (rows * conf).sum() / hh / total)
    return out


@dataclass(frozen=True)
class Landmarks:
    """The landmark model's result for one ROI.

    Attributes:
        xy: (39, 2) image pixels (33 body landmarks, then the 2 ROI landmarks and 4 unused).
        z: (39,) depth in image pixels relative to the hips (smaller is nearer the camera).
        visibility: (39,) probability that the landmark is visible (not occluded).
        presence: (39,) probability that the landmark is inside the image.
        world: (39, 3) metres, hip-centred, x right, y down, z away from the camera.
        score: pose presence score in [0, 1].
        roi: the ROI it was computed on.
        segmentation: (256, 256) person segmentation logits over the ROI crop, or None.
    """

    xy: np.ndarray
    z: np.ndarray
    visibility: np.ndarray
    presence: np.ndarray
    world: np.ndarray
    score: float
    roi: Roi
    segmentation: np.ndarray | None = None

    def person_mask(self, width: int, height: int) -> np.ndarray:
        """(height, width) float32 person probability in the image, from the segmentation over the ROI
        (0 outside the ROI); zeros when there is no segmentation."""
        if self.segmentation is None:
            return np.zeros((height, width), np.float32)
        prob = (1.0 / (1.0 + np.exp(-np.clip(self.segmentation, -50, 50)))).astype(np.float32)
        return roi_map_to_image(prob, self.roi, width, height)

    def next_roi(self) -> Roi:
        """The ROI for the next video frame, from the two ROI landmarks (PoseLandmarksToRoi)."""
        return roi_from_points(self.xy[33], self.xy[34])


def roi_map_to_image(values: np.ndarray, roi: Roi, width: int, height: int) -> np.ndarray:
    """An (n, n) float32 map over a ROI crop (the segmentation's grid) drawn into a (height, width) image
    (bilinear, 0 outside the ROI)."""
    n = values.shape[0]
    mat = roi_matrix(roi, n)
    mat[:, 2] += mat[:, :2] @ np.array([0.5, 0.5]) - 0.5  # pixel indices, as in crop_roi
    return cv2.warpAffine(np.asarray(values, np.float32), mat, (width, height), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-x))


def decode_landmarks(raw: np.ndarray, flag: float, heatmap: np.ndarray, world: np.ndarray, roi: Roi,
                     segmentation: np.ndarray | None = None) -> Landmarks:
    """Landmark-model outputs -> :class:`Landmarks` in image pixels.

    Args:
        raw: (195,) 39 x (x, y, z, visibility logit, presence logit), crop pixels.
        flag: pose presence score.
        heatmap: (64, 64, 39) logits.
        world: (117,) 39 x (x, y, z) metres in the crop's orientation.
        roi: the ROI the crop was taken from.
        segmentation: (256, 256) segmentation logits over the crop, kept as they are.
    """
    lm = raw.reshape(NUM_LANDMARKS, 5).astype(np.float64)
    norm = refine_from_heatmap(lm[:, :2] / LANDMARK_SIZE, heatmap)
    mat = roi_matrix(roi, 1)
    xy = norm @ mat[:, :2].T + mat[:, 2]
    z = lm[:, 2] / LANDMARK_SIZE * roi.size
    c, s = np.cos(roi.rotation), np.sin(roi.rotation)
    w = world.reshape(NUM_LANDMARKS, 3).astype(np.float64)
    w_rot = np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=1)
    return Landmarks(xy, z, _sigmoid(lm[:, 3]), _sigmoid(lm[:, 4]), w_rot, float(flag), roi,
                     None if segmentation is None else np.array(segmentation, np.float32).reshape(
                         segmentation.shape[0], segmentation.shape[1]))


# --- the two models -------------------------------------------------------------------------------------------

@contextmanager
def _quiet_stderr():
    """Silence file descriptor 2 (C++ logging) for the block; Python's own errors still propagate."""
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, OSError, ValueError):  # no real stderr (e.g. captured): nothing to silence
        yield
        return
    sys.stderr.flush()
    saved = os.dup(fd)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), fd)
            yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)


class BlazePose:
    """The two BlazePose models behind LiteRT interpreters.

    Args:
        num_threads: CPU threads for each interpreter.
    """

    def __init__(self, *, num_threads: int = 2) -> None:
        from ai_edge_litert.interpreter import Interpreter

        with _quiet_stderr():  # LiteRT prints "INFO: Created TensorFlow Lite XNNPACK delegate" to fd 2
            self._det = Interpreter(model_path=str(DETECTOR_FILE), num_threads=num_threads)
            self._det.allocate_tensors()
            self._lmk = Interpreter(model_path=str(LANDMARK_FILE), num_threads=num_threads)
            self._lmk.allocate_tensors()
        self._det_in = self._det.get_input_details()[0]["index"]
        det_out = {d["shape"][-1]: d["index"] for d in self._det.get_output_details()}
        self._det_boxes, self._det_scores = det_out[12], det_out[1]
        self._lmk_in = self._lmk.get_input_details()[0]["index"]
        by_size = {int(np.prod(d["shape"])): d["index"] for d in self._lmk.get_output_details()}
        self._lmk_raw, self._lmk_flag = by_size[195], by_size[1]
        self._lmk_heat, self._lmk_world = by_size[64 * 64 * 39], by_size[117]
        self._lmk_seg = by_size[LANDMARK_SIZE * LANDMARK_SIZE]

    def detect(self, image: np.ndarray, *, min_score: float = DETECTION_MIN_SCORE) -> list[Detection]:
        """People in an (H, W, 3) uint8 RGB image scoring at least ``min_score``, best score first."""
        tensor, scale, offset = letterbox(image)
        self._det.set_tensor(self._det_in, tensor[None])
        self._det.invoke()
        raw_boxes = self._det.get_tensor(self._det_boxes)[0]  # (2254, 12)
        raw_scores = self._det.get_tensor(self._det_scores)[0, :, 0]  # (2254,)
        boxes, scores = decode_detections(raw_boxes, raw_scores, ssd_anchors(), min_score=min_score)
        boxes, scores = weighted_nms(boxes, scores)
        # detector input (normalised) -> image pixels: undo the letterbox.
        pts = (boxes.reshape(-1, 6, 2) * DETECTOR_SIZE - offset) / scale  # (P, 6, 2)
        return [Detection(float(s), p[:2].reshape(4), p[2:].copy()) for p, s in zip(pts, scores)]

    def landmarks(self, image: np.ndarray, roi: Roi) -> Landmarks:
        """The landmark model on one ROI of an (H, W, 3) uint8 RGB image."""
        self._lmk.set_tensor(self._lmk_in, crop_roi(image, roi)[None])
        self._lmk.invoke()
        return decode_landmarks(self._lmk.get_tensor(self._lmk_raw)[0],
                                float(self._lmk.get_tensor(self._lmk_flag).reshape(())),
                                self._lmk.get_tensor(self._lmk_heat)[0],
                                self._lmk.get_tensor(self._lmk_world)[0], roi,
                                self._lmk.get_tensor(self._lmk_seg)[0, :, :, 0])


def detection_roi(det: Detection) -> Roi:
    """The landmark ROI of a detection (PoseDetectionToRoi): hip centre and full-body scale point."""
    return roi_from_points(det.keypoints[0], det.keypoints[1])
