"""A portrait (a photo or a painting of a face) as the face frame generator's reference: the Anny head fitted to
the face in one image, and the square of the image framed as the face renderer's close-up frames its head.

- :func:`fit_portrait`: the face mesh on the largest face (searched in squares of the picture when the detector
  finds none in the whole, :func:`face_candidates`; its ROI taken twice: from the detection, then from the first
  landmarks, as the tracker's second frame would), then the head's pose and 52 ARKit coefficients fitted
  to the 470 points (:func:`.face_fit.fit_frame`) with a ridge that keeps the person's own face shape out of the
  coefficients (:data:`PORTRAIT_RIDGE`), and the face's shape (:mod:`.face_shape`'s targets: where the eyes, brows,
  nose and mouth sit and how large they are), the two fitted in turn.
- :func:`portrait_framing`: the similarity (scale, shift; no turn: the head's roll is in its pose) that takes the
  image's landmarks onto the fitted head's landmarks as the close-up camera sees them
  (:func:`renderers.face.close_up_camera`, the camera of the face generators' training frames), the head at no
  translation, i.e. where the training frames hold a head on average.
- :func:`frame_portrait`: the image moved by that similarity into the generator's square (down-sampled by area
  first, its border replicated), and which of its pixels come from the image.

The head keeps Anny's default phenotype: letting the six phenotype values vary (a coordinate search over 0, 0.25,
..., 1) lowered the mean re-projection error only from 1.66% to 1.55% of the face size on ``portrait_mona_lisa.jpg``
and from 2.40% to 2.37% on ``portrait_pearl_earring.jpg``, and took the oldest age for both. The face targets lower
the median error from 1.31% to 1.09% and from 1.97% to 1.75%.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np

from motion2video.core.camera import PinholeCamera
from motion2video.core.motion import FACE_DIM, NUM_EXPRESSIONS
from motion2video.core.rotations import axis_angle_to_matrix
from motion2video.pose.face_anny import head_basis, posed_landmarks
from motion2video.pose.face_fit import FitConfig, FrameFit, fit_frame
from motion2video.pose.face_shape import fit_shape, shape_points, target_names
from motion2video.pose.blazepose import weighted_nms
from motion2video.pose.facemesh import (MIN_PRESENCE, NMS_MIN_IOU, FaceDetection, FaceLandmarks, FaceMesh,
                                        detection_roi, shared_face_mesh)

# The coefficients' ridge for one picture, where no other frame tells the person's face from their expression: at
# the tracker's 1e-6 a dozen coefficients of either shared portrait went to 1 (the face's shape taken for an
# expression); at 1e-3 every one stayed under 0.11 (Mona Lisa's smile gone). At 1e-4: at most 0.34 and 0.42, the
# median landmark 1.3% and 2.0% of the face size from the fitted head's.
PORTRAIT_RIDGE = 1e-4
PORTRAIT_FIT = FitConfig(ridge=PORTRAIT_RIDGE, first_iterations=6)
# face_candidates: squares of a picture searched for a face on their own, down to a quarter of its short side (a
# face over about a 40th of it: a standing person's head in a full-length photo) and no smaller than 96 px
TILE_LEVELS = 2
SMALLEST_TILE = 96
SHAPE_ROUNDS = 2  # the face's shape, then its pose and expression again (_fit)


@dataclass(frozen=True)
class PortraitFit:
    """The Anny head fitted to the face of one picture.

    Attributes:
        landmarks: (470, 2) the face mesh's 468 landmarks and the two iris centres, the picture's pixels.
        score: the face-presence score in [0, 1].
        fit: the fitted weak-perspective pose and coefficients (:class:`.face_fit.FrameFit`, the picture's pixels).
        faces: how many faces the detector found.
        shape: (K,) the pictured face's shape, the coefficients of :mod:`.face_shape`'s targets in [0, 1] (``fit``
            is the pose and expression of the head with that shape).
        plain_fit: the pose and expression fitted to Anny's own face, without a shape.
    """

    landmarks: np.ndarray
    score: float
    fit: FrameFit
    faces: int
    shape: np.ndarray
    plain_fit: FrameFit

    @property
    def size(self) -> float:
        """The face's size in pixels: the long side of its landmarks' bounding box."""
        return float(np.max(self.landmarks.max(axis=0) - self.landmarks.min(axis=0)))

    def params(self) -> np.ndarray:
        """(58,) float32 face parameters: the fitted coefficients and head rotation, no translation."""
        out = np.zeros(FACE_DIM, np.float32)
        out[:NUM_EXPRESSIONS] = self.fit.expressions
        out[NUM_EXPRESSIONS:NUM_EXPRESSIONS + 3] = self.fit.rotation
        return out

    def relative_error(self) -> float:
        """The median distance of the landmarks from the fitted head's (Anny's face), in face sizes."""
        return float(np.median(self.fit.residual) / self.size)

    def plain_error(self) -> float:
        """The median distance of the landmarks from Anny's own head fitted to them, in face sizes."""
        return float(np.median(self.plain_fit.residual) / self.size)


def face_candidates(image: np.ndarray, model: FaceMesh, *, levels: int = TILE_LEVELS) -> Iterator[list[FaceDetection]]:
    """Faces the detector finds in an (H, W, 3) uint8 RGB picture, coarse to fine: on the whole picture, then on
    overlapping squares of half its short side, then a quarter (``levels`` halvings, none under
    :data:`SMALLEST_TILE` pixels), each square at the detector's input size: the short-range detector sees a face
    only when it is over about a tenth of its 128 px input (the head of a person in a full-length photo is
    smaller). Detections of one face in overlapping squares are merged (weighted NMS, as the detector's own).

    Yields:
        per level, the detections in the picture's pixels, best score first (maybe none).
    """
    yield model.detect(image)
    h, w = image.shape[:2]
    for level in range(1, levels + 1):
        side = min(h, w) >> level
        if side < SMALLEST_TILE:
            return
        boxes, scores = [], []
        for y in _starts(h, side, side // 2):
            for x in _starts(w, side, side // 2):
                for det in model.detect(np.ascontiguousarray(image[y:y + side, x:x + side])):
                    boxes.append(np.concatenate([det.box + (x, y, x, y), (det.keypoints + (x, y)).reshape(-1)]))
                    scores.append(det.score)
        if not boxes:
            yield []
            continue
        merged, best = weighted_nms(np.stack(boxes), np.array(scores), NMS_MIN_IOU)
        yield [FaceDetection(float(sc), b[:4].copy(), b[4:].reshape(-1, 2).copy()) for b, sc in zip(merged, best)]


def _starts(length: int, side: int, step: int) -> list[int]:
    """First pixels of squares of ``side`` every ``step`` along ``length``, the last one flush with the end."""
    last = max(length - side, 0)
    return sorted(set(list(range(0, last + 1, step)) + [last]))


def fit_portrait(image: np.ndarray, *, model: FaceMesh | None = None) -> PortraitFit | None:
    """Fit the Anny head to the largest face of an (H, W, 3) uint8 RGB picture (the largest of the first level of
    :func:`face_candidates` whose face mesh confirms a face); None when no face is found (no detection, or none
    with a face-presence score over the tracker's threshold)."""
    model = model or shared_face_mesh()
    for detections in face_candidates(image, model):
        for det in sorted(detections, key=lambda d: d.area, reverse=True):
            lm = model.landmarks(image, detection_roi(det))
            if lm.score < MIN_PRESENCE:  # not a face after all (a face-like pattern, a mask)
                continue
            again = model.landmarks(image, lm.next_roi())  # the ROI a tracked face gets: the landmarks' own box
            return _fit(again if again.score >= MIN_PRESENCE else lm, len(detections))
    return None


def _fit(lm: FaceLandmarks, faces: int) -> PortraitFit:
    """The head fitted to one face's landmarks (:data:`PORTRAIT_FIT`); ``faces`` found beside it. The shape and
    the pose with the expression are fitted in turn (:data:`SHAPE_ROUNDS` times), each holding the other."""
    xy = lm.points()
    basis = head_basis()
    weights = PORTRAIT_FIT.weights()
    plain = fit = fit_frame(basis.neutral, basis.basis, xy, PORTRAIT_FIT, None, weights)
    shape = np.zeros(len(target_names()))
    for _ in range(SHAPE_ROUNDS):
        shape = fit_shape(basis.neutral + np.tensordot(fit.expressions, basis.basis, axes=1), xy, fit, weights)
        fit = fit_frame(basis.neutral + shape_points(shape), basis.basis, xy, PORTRAIT_FIT, fit, weights)
    return PortraitFit(xy, lm.score, fit, faces, shape, plain)


@dataclass(frozen=True)
class PortraitFraming:
    """``out = in * scale + offset`` (pixels, centres at integer + 0.5): the picture into the close-up's square.

    Attributes:
        scale: output pixels per picture pixel.
        offset: (2,) output pixels.
        camera: the close-up camera at the output's size.
        error: the median distance, in face sizes, between the moved landmarks and the head's seen by the camera.
    """

    scale: float
    offset: np.ndarray
    camera: PinholeCamera
    error: float

    def box(self) -> tuple[float, float, float]:
        """(x0, y0, side): the square of the picture's pixels the output shows."""
        return (float(-self.offset[0] / self.scale), float(-self.offset[1] / self.scale),
                float(self.size / self.scale))

    @property
    def size(self) -> int:
        return int(self.camera.width)


def similarity_fit(src: np.ndarray, dst: np.ndarray) -> tuple[float, np.ndarray]:
    """The scale and (2,) shift, no rotation, that take (L, 2) ``src`` nearest (least squares) onto (L, 2) ``dst``."""
    sm, dm = src.mean(axis=0), dst.mean(axis=0)
    a, b = src - sm, dst - dm
    scale = float(np.sum(a * b) / max(np.sum(a * a), 1e-12))
    return scale, dm - scale * sm


def portrait_framing(portrait: PortraitFit, size: int) -> PortraitFraming:
    """Where the picture goes in a ``size`` square so that its face lies where the close-up camera sees the fitted
    head (see the module docstring)."""
    from renderers import anny_model
    from renderers.face import FaceStyle, close_up_camera

    camera = close_up_camera(anny_model.anny_rest(None), FaceStyle(size=(size, size)))
    params = portrait.params()[None].astype(np.float64)  # (1, 58)
    e = NUM_EXPRESSIONS
    points = posed_landmarks(params[:, :e], params[:, e:e + 3], params[:, e + 3:])[0]  # (470, 3)
    # the pictured face's shape on the head, turned with it
    points = points + shape_points(portrait.shape) @ axis_angle_to_matrix(params[0, e:e + 3]).T
    seen = camera.project(points)[:, :2]  # (470, 2) the head's landmarks in the close-up
    scale, offset = similarity_fit(portrait.landmarks, seen)
    moved = portrait.landmarks * scale + offset
    error = float(np.median(np.linalg.norm(moved - seen, axis=1)) / (portrait.size * scale))
    return PortraitFraming(scale, offset, camera, error)


def frame_portrait(image: np.ndarray, framing: PortraitFraming) -> tuple[np.ndarray, np.ndarray]:
    """The picture moved into the close-up's square.

    Args:
        image: (H, W, 3) uint8.
    Returns:
        (S, S, 3) uint8, and (S, S) float32 1 where the pixel comes from the picture, 0 where its border was
        replicated.
    """
    size = framing.size
    h, w = image.shape[:2]
    scale, offset = framing.scale, np.asarray(framing.offset, np.float64)
    source = image
    if scale < 1.0:  # by area first: a linear warp alone would alias a large picture's fine detail
        source = cv2.resize(image, (max(1, round(w * scale)), max(1, round(h * scale))), interpolation=cv2.INTER_AREA)
    sx, sy = source.shape[1] / w, source.shape[0] / h  # the area step's own scales per axis
    a = scale / np.array([sx, sy])
    shift = 0.5 * a + offset - 0.5  # pixel indices of warpAffine, centres at +0.5 in the project's pixels
    mat = np.array([[a[0], 0.0, shift[0]], [0.0, a[1], shift[1]]])
    out = cv2.warpAffine(source, mat, (size, size), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    picture = cv2.warpAffine(np.ones(source.shape[:2], np.float32), mat, (size, size), flags=cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
    return np.ascontiguousarray(out), picture
