"""The talking-head reconstruction protocol (FOMM, TPSMM, LivePortrait) on a real face video.

Frame 0 of the face track (the first frame with the face) is the reference; the later frames' tracked face
motion (``motion2video pose --face``: the Anny head's pose and 52 expression coefficients fitted to the face
mesh) drives the generator; the real later frames are the truth.

Framing: every frame is cut to one square, the close-up the face generators were trained on. Their training
renders put the head's centre at eye height in the middle of the picture and make chin-to-crown
``FaceStyle.head_fraction`` (0.72) of its height (:meth:`renderers.face.FaceRenderer.camera_for`); the square
here is that view of the fitted head: its centre the framing point of the Anny head seen through each frame's
fitted camera (averaged over the scored frames), its side the close-up's view height in metres times the
fitted scale (pixels per metre, averaged). So the generator sees a real face at the size and place its
training faces had, and one fixed square (as the training camera is fixed per sequence) keeps the head's
own motion in the picture. Outside the video the border is replicated.

The generator's head mesh: the Anny head posed by each frame's fitted motion, seen by a camera in front of it
(the close-up's field of view) placed so that the fitted weak-perspective camera is reproduced at the face's
centre (:func:`crop_face_motion`); its vertices then give the mesh generator's correspondence, as in training.
The mesh generator lays the moved head over the reference frame itself (:func:`mesh_face_frames`), not over the
reference with the head inpainted as on rendered pairs: see there why.

Per method (the generator, ``copy-reference``, ``landmark-warp`` and named baseline generators):

- ``l1``: mean absolute error of the whole frame, in [0, 1]; ``psnr`` and ``ssim`` of the whole frame;
- ``head_psnr`` / ``head_ssim`` over the real face: the convex hull of the target frame's tracked landmarks;
- ``landmark_error``: the face mesh (:class:`motion2video.pose.facemesh.FaceMesh`, detector then landmarks, on
  each frame alone) run on the generated frame and on the real one, the mean distance of the 468 landmarks and
  two iris centres, over the real face's size (the long side of its landmarks' box), over the frames where both
  are found; ``landmark_missing``: the share of generated frames where no face is found.

``landmark-warp``: a piecewise-affine warp of the reference taking its tracked landmarks to the target's
(:func:`motion2video.generator.image_baselines.limb_warp`, scikit-image's piecewise-affine map, with the 470
tracked points as the control points).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import torch

from motion2video.core.camera import PinholeCamera
from motion2video.core.errors import InputError
from motion2video.core.rotations import axis_angle_to_matrix
from motion2video.evaluation.reconstruction import cut_square, protocol_frames
from motion2video.generator.data import FramePairs, face_structures
from motion2video.generator.mesh_flow import MeshTrack, complete_reference_uv, flows_to_targets
from motion2video.generator.mesh_warp import mesh_inputs
from motion2video.generator.model import images_to_tensor
from motion2video.generator.scores import FrameEvaluation, MethodScores, evaluate_pairs
from motion2video.pose.estimate import iter_video_frames
from motion2video.pose.face_fit import PROJECTION
from motion2video.pose.face_track import FaceTrack
from motion2video.pose.facemesh import FaceMesh, shared_face_mesh

LANDMARK_WARP = "landmark-warp"


@dataclass(frozen=True)
class FaceVideoFrames:
    """Frames of a face video cut to the close-up square and resized, with the head mesh that drives them.

    Attributes:
        images: (N, S, S, 3) uint8; images[0] is the reference.
        landmarks: (N, 470, 2) float32 tracked face points in the crop's pixels.
        grey: (N, S, S) uint8 the fitted head's grey structure renders (the face generators' structure input).
        mesh: the fitted head's :class:`MeshTrack` in the crop (vertex pixels, front-surface flags, silhouettes).
        frame_index: (N,) the video frame of each.
        fps: the video's rate.
        box: (x0, y0, side) of the square in the video's pixels.
    """

    images: np.ndarray
    landmarks: np.ndarray
    grey: np.ndarray
    mesh: MeshTrack
    frame_index: np.ndarray
    fps: float
    box: tuple[int, int, int]


def close_up_view() -> tuple[np.ndarray, float, float]:
    """The face renderer's close-up of Anny's default head at rest: (3,) the point it centres (metres, rest
    coordinates), the view height in metres, and the vertical field of view in radians."""
    from motion2video.core.motion import FACE_DIM, FaceMotion
    from renderers.face import FaceRenderer, FaceStyle

    style = FaceStyle(size=(64, 64))
    renderer = FaceRenderer(style)
    try:
        camera = renderer.camera_for(FaceMotion(np.zeros((1, FACE_DIM), np.float32), 30.0))
    finally:
        renderer.close()
    target = np.asarray(camera.target, np.float64)
    distance = float(np.linalg.norm(target - np.asarray(camera.position, np.float64)))
    return target, 2.0 * distance * np.tan(0.5 * camera.yfov), float(camera.yfov)


def close_up_box(track: FaceTrack, rows: np.ndarray) -> tuple[int, int, int]:
    """(x0, y0, side) in the video's pixels: the close-up square of the fitted head over track ``rows`` (the
    module docstring's framing)."""
    target, view_height, _ = close_up_view()
    cams = track.camera[rows]  # (R, 3) scale, shift x, shift y
    R = axis_angle_to_matrix(track.motion.head_rotation[rows].astype(np.float64))  # (R, 3, 3)
    centre = cams[:, :1] * (R @ target) @ PROJECTION.T + cams[:, 1:]  # (R, 2)
    side = int(round(view_height * float(cams[:, 0].mean())))
    mid = centre.mean(axis=0)
    return int(round(mid[0] - side / 2)), int(round(mid[1] - side / 2)), max(side, 8)


def crop_face_motion(track: FaceTrack, rows: np.ndarray, box: tuple[int, int, int], size: int
                     ) -> tuple[np.ndarray, PinholeCamera]:
    """The fitted head of track ``rows`` as face-motion parameters for the face renderer, and the camera that
    sees it in the square ``box`` resized to ``size``.

    The camera sits at the origin looking along +y with the close-up's field of view; each frame's head is
    placed so that its landmarks' centre lies at the depth where the camera's focal length over the depth
    equals the fitted scale in the crop's pixels, and sideways and up where the fitted camera puts it.

    Returns:
        (R, 58) float32 parameters (expressions, rotation, translation in metres), and the camera.
    """
    from motion2video.pose.face_anny import head_basis, head_offset

    _, _, yfov = close_up_view()
    camera = PinholeCamera((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), yfov, size, size)
    x0, y0, side = box
    cams = track.camera[rows].astype(np.float64)
    rotations = track.motion.head_rotation[rows].astype(np.float64)  # (R, 3)
    k = cams[:, 0] * size / side  # crop pixels per metre
    centre = (head_basis().neutral + track.neutral_offsets).mean(axis=0)  # (3,) the landmarks' centre, rest frame
    turned = axis_angle_to_matrix(rotations) @ centre  # (R, 3)
    px = (cams[:, 1] - x0) * size / side - size / 2
    py = (cams[:, 2] - y0) * size / side - size / 2
    placed = np.stack([px / k, camera.focal / k - turned[:, 1], -py / k], axis=1)  # where R v + placed draws v
    params = np.concatenate([track.motion.expressions[rows], rotations, placed - head_offset(rotations)], axis=1)
    return params.astype(np.float32), camera


def face_video_frames(path: str | Path, track: FaceTrack, *, size: int, targets: int = 64,
                      stride: int | None = None) -> FaceVideoFrames:
    """Frame 0 of the face track and ``targets`` later frames ``stride`` apart (default: spread over the track),
    cut to the close-up square and resized to ``size``, with the fitted head rendered in each.

    Raises:
        InputError: fewer than two frames, or the video ends before a tracked frame.
    """
    from motion2video.core.motion import FaceMotion
    from motion2video.pose.face_shape import fit_shape_to_offsets, head_shape
    from renderers.registry import renderer_for

    rows = np.array(protocol_frames(track.num_frames, targets=targets, stride=stride), np.int64)
    if len(rows) < 2:
        raise InputError("the face is tracked in fewer than two frames to evaluate", path)
    box = close_up_box(track, rows)
    video_rows = rows + track.first_frame
    wanted = {int(v): i for i, v in enumerate(video_rows)}
    images = np.zeros((len(rows), size, size, 3), np.uint8)
    found = 0
    for i, frame in enumerate(iter_video_frames(path)):
        if i in wanted:
            images[wanted[i]] = cv2.resize(cut_square(frame, box), (size, size), interpolation=cv2.INTER_AREA)
            found += 1
        if i >= video_rows[-1]:
            break
    if found < len(rows):
        raise InputError(f"the video ended before frame {int(video_rows[-1])} (it was tracked with more frames)",
                         path)
    x0, y0, side = box
    landmarks = ((track.landmarks2d[rows] - np.array([x0, y0])) * size / side).astype(np.float32)
    params, camera = crop_face_motion(track, rows, box, size)
    with renderer_for("face", "structure", size=size) as drawer:
        shape = head_shape(fit_shape_to_offsets(track.neutral_offsets))  # the person's face shape, every frame
        out = drawer.renderer.render_with_masks(FaceMotion(params, track.motion.fps), camera=camera, vertices=True,
                                                shape=shape)
    grey = np.rint(out.frames.astype(np.float32).mean(axis=-1)).astype(np.uint8)  # as the training data
    mesh = MeshTrack(uv=out.vertex_uv, visible=out.vertex_visible, masks=out.masks)
    return FaceVideoFrames(images, landmarks, grey, mesh, video_rows, float(track.motion.fps), box)


def face_pairs(frames: FaceVideoFrames) -> FramePairs:
    """Frame 0 as every pair's reference, each later frame a target; the control points are the tracked face
    points (the landmark warp's), the masks the fitted head's silhouettes, the mesh correspondence that of the
    fitted head (the surface the reference does not show completed as in ``synthesize``)."""
    n = len(frames.images) - 1
    mesh = frames.mesh
    ref_uv = complete_reference_uv(mesh.uv[0], mesh.visible[0], image=frames.images[0])
    flows, visibility = flows_to_targets(ref_uv, mesh.visible[0], mesh, range(1, n + 1))
    structures = face_structures(frames.grey)
    return FramePairs(np.repeat(frames.images[:1], n, axis=0), frames.images[1:],
                      np.repeat(frames.landmarks[:1], n, axis=0), frames.landmarks[1:],
                      np.repeat(structures[:1], n, axis=0), structures[1:],
                      np.repeat(mesh.masks[:1], n, axis=0), mesh.masks[1:], mesh_flow=flows,
                      mesh_visibility=visibility)


@torch.inference_mode()
def mesh_face_frames(model, pairs: FramePairs, *, batch_size: int = 8) -> np.ndarray:
    """(N, S, S, 3) uint8 frames of the face mesh generator on :func:`face_pairs`, laid over the reference frame.

    On rendered pairs the generator lays the moved head over the reference with the head's silhouette inpainted
    (:func:`motion2video.generator.mesh_warp.mesh_plate`). A real head is not Anny's: long hair, ears and the
    hairline reach past the fitted head's silhouette and stay in that plate, and where the moved head uncovers the
    plate the inpainted silhouette shows (Telea smears the hair and wall around it into a grey arc over the head).
    A talking head moves little about a still body, so the reference's own pixels are the nearer guess there: on
    the first 16 scored frames of the two face videos of ``../shared/data/video`` (frames-face-mesh-128), L1 0.0402
    -> 0.0329 (woman) and 0.0278 -> 0.0213 (man), PSNR 20.81 -> 23.36 and 22.87 -> 26.52 dB; the landmark
    warp's own plate (the reference warped on the landmarks) gave 0.0404 and 0.0257; the silhouettes grown by the
    person's margin over the reference with the person inpainted, as body videos are drawn, 0.0534 (woman: the long
    hair was inpainted away).
    """
    if pairs.mesh_flow is None:
        raise ValueError("the face mesh generator needs pairs with the head mesh's correspondence")
    model.eval()
    out = []
    for i in range(0, len(pairs), batch_size):
        part = pairs.subset(slice(i, i + batch_size))
        ref = images_to_tensor(part.ref_images)
        x = model.forward_parts(ref, *mesh_inputs(part), torch.from_numpy(part.tgt_structures), plate=ref).image
        out.append((x.clamp(0, 1) * 255).round().to(torch.uint8).permute(0, 2, 3, 1).numpy())
    return np.concatenate(out)


def hull_masks(points: np.ndarray, size: int) -> np.ndarray:
    """(N, S, S) bool: the convex hull of each frame's (N, L, 2) points (pixels)."""
    out = np.zeros((len(points), size, size), np.uint8)
    for mask, pts in zip(out, np.asarray(points, np.float64)):
        hull = cv2.convexHull(np.round(pts - 0.5).astype(np.int32))
        cv2.fillConvexPoly(mask, hull, 1)
    return out.astype(bool)


def face_points(image: np.ndarray, model: FaceMesh) -> np.ndarray | None:
    """(470, 2) the face points the face mesh finds in an (H, W, 3) uint8 image on its own (the largest face the
    detector finds, then the landmarks and the eye model on its region), or None without a face."""
    from motion2video.pose.facemesh import MIN_PRESENCE, detection_roi

    detections = model.detect(image)
    if not detections:
        return None
    found = model.landmarks(image, detection_roi(max(detections, key=lambda d: d.area)))
    return found.points() if found.score >= MIN_PRESENCE else None


def landmark_error(pred: np.ndarray, truth: list[np.ndarray | None], model: FaceMesh) -> tuple[float, float]:
    """The mean landmark distance over the real face's size, and the share of frames without a face found.

    Args:
        pred: (N, S, S, 3) uint8 generated frames.
        truth: N arrays (470, 2): the points found on the real frames (None where none were found: skipped).
    """
    errors, missing = [], 0
    for image, real in zip(pred, truth):
        found = face_points(image, model)
        if found is None:
            missing += 1
            continue
        if real is None:
            continue
        size = float(np.max(real.max(axis=0) - real.min(axis=0)))
        errors.append(float(np.linalg.norm(found - real, axis=1).mean()) / size)
    return (float(np.mean(errors)) if errors else float("nan")), missing / max(len(pred), 1)


@dataclass
class FaceVideoEvaluation:
    """The protocol's scores: the frame evaluation plus ``l1``, ``landmark_error`` and ``landmark_missing`` per
    method, and where the frames came from."""

    frames: FrameEvaluation
    l1: dict[str, float]
    landmark_error: dict[str, float]
    landmark_missing: dict[str, float]
    video: str
    frame_index: np.ndarray
    box: tuple[int, int, int]
    truth_missing: int

    def to_dict(self) -> dict:
        out = self.frames.to_dict()
        for name, scores in out["results"].items():
            scores["l1"] = round(self.l1[name], 5)
            err = self.landmark_error[name]
            scores["landmark_error"] = None if not np.isfinite(err) else round(err, 5)
            scores["landmark_missing"] = round(self.landmark_missing[name], 4)
        out.update(protocol="talking-head reconstruction: frame 0 is the reference, later frames' tracked face "
                            "motion drives, real frames are the truth",
                   video=self.video, num_frames=int(len(self.frame_index)),
                   frames=[int(i) for i in self.frame_index[:1]] + [int(self.frame_index[-1])],
                   crop_box=[int(v) for v in self.box],
                   framing="the close-up square of the face generators' training renders, on the fitted head",
                   head_mask="the convex hull of the target frame's tracked face landmarks",
                   landmark_error_unit="mean distance of 470 face points over the real face's size",
                   truth_frames_without_face=self.truth_missing)
        if "generator" in self.l1:
            out["targets_met"] = {f"l1_below_{name}": self.l1["generator"] < self.l1[name]
                                  for name in ("copy-reference", LANDMARK_WARP)}
        return out


def evaluate_face_video_frames(model, frames: FaceVideoFrames, *, video: str | Path,
                               baseline_models: dict | None = None, face_model: FaceMesh | None = None
                               ) -> FaceVideoEvaluation:
    """Score a face generator (and the baselines) on frames of :func:`face_video_frames` (the module
    docstring's metrics)."""
    face_model = face_model or shared_face_mesh(num_threads=1)
    pairs = face_pairs(frames)
    size = pairs.tgt_images.shape[1]
    heads = hull_masks(pairs.tgt_points, size)
    models = {"generator": model, **(baseline_models or {})}
    mesh = {name: m for name, m in models.items() if getattr(m, "kind", None) == "mesh"}
    others = {name: m for name, m in models.items() if name not in mesh and name != "generator"}
    evaluation = evaluate_pairs(None if "generator" in mesh else model, pairs, domain="face",
                                baseline_models=others, tgt_head_masks=heads)
    for name, net in mesh.items():  # laid over the reference frame (mesh_face_frames)
        pred = mesh_face_frames(net, pairs)
        evaluation.predictions[name] = pred
        evaluation.results[name] = MethodScores.from_frames(
            pred, pairs.tgt_images, ref=pairs.ref_images, ref_masks=pairs.ref_masks, tgt_masks=pairs.tgt_masks,
            tgt_head_masks=heads)
    order = [*models, *(k for k in evaluation.results if k not in models)]
    evaluation.results = {k: evaluation.results[k] for k in order if k in evaluation.results}
    # the piecewise-affine warp on the tracked face points is the landmark warp
    for store in (evaluation.results, evaluation.predictions):
        store[LANDMARK_WARP] = store.pop("limb-warp")
    truth = [face_points(image, face_model) for image in pairs.tgt_images]
    l1, err, missing = {}, {}, {}
    for name in evaluation.results:
        pred = evaluation.predictions[name]
        l1[name] = float(np.abs(pred.astype(np.float64) - pairs.tgt_images).mean() / 255.0)
        err[name], missing[name] = landmark_error(pred, truth, face_model)
    return FaceVideoEvaluation(evaluation, l1, err, missing, str(video), frames.frame_index, frames.box,
                               sum(t is None for t in truth))


def evaluate_face_video(model, path: str | Path, *, size: int, targets: int = 64, stride: int | None = None,
                        baseline_models: dict | None = None, track: FaceTrack | None = None,
                        note=None) -> FaceVideoEvaluation:
    """Run the protocol (module docstring) on one face video for a face frame generator; the face is tracked
    once and cached (:func:`motion2video.stages.people.face_video_track`) unless ``track`` is given.

    Raises:
        InputError: unreadable video, no face in it (one line naming the file), fewer than two frames.
    """
    from motion2video.stages.people import face_video_track

    if track is None:
        track = face_video_track(path, note=note)
    frames = face_video_frames(path, track, size=size, targets=targets, stride=stride)
    return evaluate_face_video_frames(model, frames, video=path, baseline_models=baseline_models)
