"""MediaPipe's face detector and face mesh run through LiteRT, with the project's own pre- and post-processing.

Three bundled Apache-2.0 models (``motion2video/weights/facemesh.md``):

- the detector ``face_detection_short_range.tflite`` (BlazeFace, faces within about 2 m): a 128 x 128
  letterboxed RGB image in [-1, 1] -> 896 SSD boxes of 16 values (box centre, size, 6 keypoints: right eye,
  left eye, nose tip, mouth centre, right ear tragion, left ear tragion) and a score logit;
- the landmark model ``face_landmark.tflite``: a 192 x 192 RGB crop in [0, 1] of a rotated square region of
  interest (ROI) -> 468 landmarks x (x, y, z) in crop pixels and a face-presence logit;
- the eye model ``iris_landmark.tflite``: a 64 x 64 RGB crop in [0, 1] around one eye -> 71 eyelid, eye-halo
  and brow points and 5 iris points x (x, y, z) in crop pixels; its eyelid and brow points replace the
  mesh's (face mesh with refined landmarks, before the attention model), and the iris centres follow the
  gaze.

The constants follow MediaPipe's graphs (``face_detection_short_range.pbtxt``,
``face_detection_front_detection_to_roi.pbtxt``, ``face_landmark_cpu.pbtxt``,
``face_landmark_landmarks_to_roi.pbtxt``, ``iris_landmark_left_and_right_cpu.pbtxt``,
``update_face_landmarks_calculator.cc``); the code is written here from those facts and shares the SSD,
non-maximum suppression and ROI geometry of :mod:`motion2video.pose.blazepose`. ``right``/``left`` are the
person's own sides (their right eye is on the image's left in a frontal view).

Coordinates: image pixels, x right, y down, origin at the top-left corner of the top-left pixel.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from motion2video.pose.blazepose import (
    WEIGHTS, Roi, _quiet_stderr, crop_roi, decode_detections, letterbox, normalize_radians, roi_matrix,
    ssd_anchors, weighted_nms,
)

DETECTOR_FILE = WEIGHTS / "face_detection_short_range.tflite"
LANDMARK_FILE = WEIGHTS / "face_landmark.tflite"
IRIS_FILE = WEIGHTS / "iris_landmark.tflite"

DETECTOR_SIZE = 128
DETECTOR_STRIDES = (8, 16, 16, 16)
LANDMARK_SIZE = 192
NUM_LANDMARKS = 468
NUM_POINTS = NUM_LANDMARKS + 2  # the tracked points: the mesh's landmarks, then the right and left iris centres
NUM_DETECTION_KEYPOINTS = 6
DETECTION_MIN_SCORE = 0.5
NMS_MIN_IOU = 0.3
ROI_SCALE = 1.5
MIN_PRESENCE = 0.5  # face_landmark_front: tracking is dropped (the detector runs again) below this
# The two eye corners whose direction sets the ROI's rotation in tracking (right eye outer, left eye outer).
ROI_ROTATION_LANDMARKS = (33, 263)
IRIS_SIZE = 64
EYE_ROI_SCALE = 2.3
# The eye model's crop runs from the first corner to the second; it sees a right eye (the person's), so the left
# eye's crop is mirrored (iris_landmark_left_and_right_cpu.pbtxt).
EYE_CORNERS = ((33, 133), (362, 263))
# Where the eye model's 71 eye-contour and brow points go in the face mesh, per eye (update_face_landmarks):
# lower lid (9), upper lid (7), then four halos around the eye and the brow.
EYE_CONTOUR_IN_MESH = (
    (33, 7, 163, 144, 145, 153, 154, 155, 133, 246, 161, 160, 159, 158, 157, 173,
     130, 25, 110, 24, 23, 22, 26, 112, 243, 247, 30, 29, 27, 28, 56, 190,
     226, 31, 228, 229, 230, 231, 232, 233, 244, 113, 225, 224, 223, 222, 221, 189,
     35, 124, 46, 53, 52, 65, 143, 111, 117, 118, 119, 120, 121, 128, 245, 156, 70, 63, 105, 66, 107, 55, 193),
    (263, 249, 390, 373, 374, 380, 381, 382, 362, 466, 388, 387, 386, 385, 384, 398,
     359, 255, 339, 254, 253, 252, 256, 341, 463, 467, 260, 259, 257, 258, 286, 414,
     446, 261, 448, 449, 450, 451, 452, 453, 464, 342, 445, 444, 443, 442, 441, 413,
     265, 353, 276, 283, 282, 295, 372, 340, 346, 347, 348, 349, 350, 357, 465, 383, 300, 293, 334, 296, 336, 285, 417),
)


@dataclass(frozen=True)
class FaceDetection:
    """One face found by the detector, in image pixels.

    Attributes:
        score: detection probability in [0, 1].
        box: (4,) x_min, y_min, x_max, y_max.
        keypoints: (6, 2) right eye, left eye, nose tip, mouth centre, right ear tragion, left ear tragion.
    """

    score: float
    box: np.ndarray
    keypoints: np.ndarray

    @property
    def area(self) -> float:
        return float(max(0.0, self.box[2] - self.box[0]) * max(0.0, self.box[3] - self.box[1]))

    @property
    def centre(self) -> np.ndarray:
        """(2,) box centre, pixels."""
        return 0.5 * (self.box[:2] + self.box[2:4])


def rotated_square_roi(box: np.ndarray, start: np.ndarray, end: np.ndarray, scale: float = ROI_SCALE) -> Roi:
    """DetectionsToRects (rotation from two points, target angle 0) + RectTransformation (x ``scale``,
    square long side): the square centred on ``box``, its side the box's long side times ``scale``, turned so
    that ``start`` -> ``end`` (right eye -> left eye) points along the crop's +x.

    Args:
        box: (4,) x_min, y_min, x_max, y_max, pixels.
        start, end: (2,) pixels.
    """
    d = np.asarray(end, np.float64) - np.asarray(start, np.float64)
    rotation = normalize_radians(-np.arctan2(-d[1], d[0]))
    centre = 0.5 * (np.asarray(box[:2], np.float64) + np.asarray(box[2:4], np.float64))
    size = float(max(box[2] - box[0], box[3] - box[1])) * scale
    return Roi(centre, size, rotation)


def detection_roi(det: FaceDetection) -> Roi:
    """The landmark ROI of a detection (face_detection_front_detection_to_roi): box, eyes, x 1.5."""
    return rotated_square_roi(det.box, det.keypoints[0], det.keypoints[1])


def landmarks_roi(xy: np.ndarray) -> Roi:
    """The next frame's ROI from (468, 2) landmarks (face_landmark_landmarks_to_roi): their axis-aligned
    bounding box, turned by the outer eye corners, x 1.5."""
    box = np.concatenate([xy.min(axis=0), xy.max(axis=0)])
    return rotated_square_roi(box, xy[ROI_ROTATION_LANDMARKS[0]], xy[ROI_ROTATION_LANDMARKS[1]])


def eye_roi(xy: np.ndarray, eye: int) -> Roi:
    """The eye model's ROI for eye ``eye`` (0: the person's right, 1: left) of (468, 2) landmarks
    (IrisLandmarkLandmarksToRoi): the square around the two corners, 2.3 x their distance, turned along them."""
    a, b = xy[EYE_CORNERS[eye][0]], xy[EYE_CORNERS[eye][1]]
    box = np.concatenate([np.minimum(a, b), np.maximum(a, b)])
    return rotated_square_roi(box, a, b, EYE_ROI_SCALE)


def decode_eye_points(raw: np.ndarray, roi: Roi, mirrored: bool) -> np.ndarray:
    """(K, 2) image pixels of an eye-model output, (3K,) = K x (x, y, z) in crop pixels (71 contour points or 5
    iris points, the centre first), taken on ``roi`` (``mirrored``: the crop was flipped left to right)."""
    pts = np.asarray(raw, np.float64).reshape(-1, 3)[:, :2] / IRIS_SIZE  # (K, 2) normalised
    if mirrored:
        pts[:, 0] = 1.0 - pts[:, 0]
    mat = roi_matrix(roi, 1)
    return pts @ mat[:, :2].T + mat[:, 2]


@dataclass(frozen=True)
class FaceLandmarks:
    """The face mesh's result for one ROI.

    Attributes:
        xy: (468, 2) image pixels.
        z: (468,) depth in image pixels (smaller is nearer the camera), relative to the face's centre.
        score: face presence probability in [0, 1].
        roi: the ROI it was computed on.
        iris: (2, 2) the right and left iris centres, pixels, from the eye model; None without it.
    """

    xy: np.ndarray
    z: np.ndarray
    score: float
    roi: Roi
    iris: np.ndarray | None = None

    def points(self) -> np.ndarray:
        """(470, 2) the tracked points: :attr:`xy`, then :attr:`iris` (ValueError without the eye model)."""
        if self.iris is None:
            raise ValueError("no iris centres: the landmarks were found without the eye model")
        return np.concatenate([self.xy, self.iris])

    def next_roi(self) -> Roi:
        return landmarks_roi(self.xy)

    @property
    def size(self) -> float:
        """The face's size in pixels: the long side of the landmarks' bounding box."""
        return float(np.max(self.xy.max(axis=0) - self.xy.min(axis=0)))


def decode_face_landmarks(raw: np.ndarray, flag: float, roi: Roi) -> FaceLandmarks:
    """Face-mesh outputs -> :class:`FaceLandmarks` in image pixels.

    Args:
        raw: (1404,) 468 x (x, y, z) in crop pixels (z at the scale of x).
        flag: the face-presence logit.
        roi: the ROI the crop was taken from.
    """
    lm = np.asarray(raw, np.float64).reshape(NUM_LANDMARKS, 3)
    mat = roi_matrix(roi, 1)
    xy = (lm[:, :2] / LANDMARK_SIZE) @ mat[:, :2].T + mat[:, 2]  # (468, 2)
    z = lm[:, 2] / LANDMARK_SIZE * roi.size
    return FaceLandmarks(xy, z, float(1.0 / (1.0 + np.exp(-np.clip(flag, -100, 100)))), roi)


@lru_cache(maxsize=None)
def face_anchors() -> np.ndarray:
    """(896, 2) normalised anchor centres of the short-range face detector (4 layers, strides 8, 16, 16,
    16, 2 anchors per layer and cell, fixed size, offset 0.5)."""
    return ssd_anchors(DETECTOR_SIZE, DETECTOR_STRIDES)


class FaceMesh:
    """The face detector, the face mesh and the eye model behind LiteRT interpreters.

    Args:
        num_threads: CPU threads for each interpreter.
        refine_eyes: run the eye model on both eyes and put its eyelid and brow points in the mesh (the mesh
            alone closes the lids by about a third of their gap on a blink, the eye model by about half).
    """

    def __init__(self, *, num_threads: int = 2, refine_eyes: bool = True) -> None:
        from ai_edge_litert.interpreter import Interpreter

        with _quiet_stderr():  # LiteRT prints "INFO: Created TensorFlow Lite XNNPACK delegate" to fd 2
            self._det = Interpreter(model_path=str(DETECTOR_FILE), num_threads=num_threads)
            self._det.allocate_tensors()
            self._lmk = Interpreter(model_path=str(LANDMARK_FILE), num_threads=num_threads)
            self._lmk.allocate_tensors()
            self._eye = None
            if refine_eyes:
                self._eye = Interpreter(model_path=str(IRIS_FILE), num_threads=num_threads)
                self._eye.allocate_tensors()
                self._eye_in = self._eye.get_input_details()[0]["index"]
                outputs = {int(np.prod(d["shape"])): d["index"] for d in self._eye.get_output_details()}
                self._eye_contour, self._eye_iris = outputs[71 * 3], outputs[5 * 3]
        self._det_in = self._det.get_input_details()[0]["index"]
        det_out = {d["shape"][-1]: d["index"] for d in self._det.get_output_details()}
        self._det_boxes, self._det_scores = det_out[4 + 2 * NUM_DETECTION_KEYPOINTS], det_out[1]
        self._lmk_in = self._lmk.get_input_details()[0]["index"]
        by_size = {int(np.prod(d["shape"])): d["index"] for d in self._lmk.get_output_details()}
        self._lmk_raw, self._lmk_flag = by_size[NUM_LANDMARKS * 3], by_size[1]

    def detect(self, image: np.ndarray) -> list[FaceDetection]:
        """Faces in an (H, W, 3) uint8 RGB image, best score first."""
        tensor, scale, offset = letterbox(image, DETECTOR_SIZE)
        self._det.set_tensor(self._det_in, tensor[None])
        self._det.invoke()
        raw_boxes = self._det.get_tensor(self._det_boxes)[0]  # (896, 16)
        raw_scores = self._det.get_tensor(self._det_scores)[0, :, 0]  # (896,)
        boxes, scores = decode_detections(raw_boxes, raw_scores, face_anchors(), DETECTOR_SIZE,
                                          DETECTION_MIN_SCORE)
        boxes, scores = weighted_nms(boxes, scores, NMS_MIN_IOU)
        pts = (boxes.reshape(-1, 2 + NUM_DETECTION_KEYPOINTS, 2) * DETECTOR_SIZE - offset) / scale  # (P, 8, 2)
        return [FaceDetection(float(s), p[:2].reshape(4), p[2:].copy()) for p, s in zip(pts, scores)]

    def landmarks(self, image: np.ndarray, roi: Roi) -> FaceLandmarks:
        """The face mesh on one ROI of an (H, W, 3) uint8 RGB image."""
        self._lmk.set_tensor(self._lmk_in, crop_roi(image, roi, LANDMARK_SIZE)[None])
        self._lmk.invoke()
        lm = decode_face_landmarks(self._lmk.get_tensor(self._lmk_raw).reshape(-1),
                                   float(self._lmk.get_tensor(self._lmk_flag).reshape(())), roi)
        if self._eye is None:
            return lm
        xy = lm.xy.copy()
        iris = np.zeros((2, 2))
        for eye in (0, 1):
            eye_box = eye_roi(lm.xy, eye)
            crop = crop_roi(image, eye_box, IRIS_SIZE)
            mirrored = eye == 1
            self._eye.set_tensor(self._eye_in, np.ascontiguousarray(crop[:, ::-1] if mirrored else crop)[None])
            self._eye.invoke()
            xy[list(EYE_CONTOUR_IN_MESH[eye])] = decode_eye_points(self._eye.get_tensor(self._eye_contour)[0],
                                                                   eye_box, mirrored)
            iris[eye] = decode_eye_points(self._eye.get_tensor(self._eye_iris)[0], eye_box, mirrored)[0]
        return FaceLandmarks(xy, lm.z, lm.score, lm.roi, iris)


@lru_cache(maxsize=None)
def shared_face_mesh(*, num_threads: int = 2, refine_eyes: bool = True) -> FaceMesh:
    """One :class:`FaceMesh` per process and setting, for every caller that does not bring its own (the face
    tracker, the portrait fit, the pictured face of a body reference, the talking-head protocol)."""
    return FaceMesh(num_threads=num_threads, refine_eyes=refine_eyes)
