"""The reconstruction protocol of the image-animation field (FOMM, TPSMM) on a real video.

Frame 0 (the first frame with the person) is the reference; later frames' estimated poses drive the
generator; the real later frames are the truth. Every frame is cut to one square around the person over the
evaluated frames (10% margin) and resized to the generator's size.

Per method (the generator, copy-reference, limb-warp, and named baseline generators):

- ``l1``: mean absolute error of the whole frame, in [0, 1] (the field's L1);
- ``psnr``, ``ssim`` of the whole frame; ``person_psnr``, ``person_ssim``, ``person_sharpness`` over the
  person, whose mask is BlazePose's segmentation of the real frame;
- ``akd``: average keypoint distance (pixels at the generator's size) between the pose BlazePose finds on
  the generated frame and the one it finds on the real frame (17 canonical joints), over the frames where
  both are found; ``akd_missing``: the share of frames where the generated one has no pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from motion2video.core.errors import InputError
from motion2video.frames.data import FramePairs, body_structures
from motion2video.frames.evaluate import FrameEvaluation, evaluate_pairs
from motion2video.pose.blazepose import NUM_BODY_LANDMARKS, BlazePose
from motion2video.pose.estimate import (default_model, estimate_image, iter_video_frames, landmarks_to_joints,
                                        open_video, track_frames)
from motion2video.pose.h36m import blazepose_to_h36m

CROP_MARGIN = 0.1


@dataclass(frozen=True)
class VideoFrames:
    """Frames of a video cut to the person and resized, with their estimated pose.

    Attributes:
        images: (N, S, S, 3) uint8; images[0] is the reference.
        points: (N, 17, 2) canonical joints in the crop's pixels.
        masks: (N, S, S) bool person masks (BlazePose's segmentation).
        frame_index: (N,) the video frame of each.
        fps: the video's rate.
        box: (x0, y0, side) of the square in the video's pixels.
        skipped: evaluated frames dropped because no person was found in them.
        joints3d: (N, 17, 3) canonical joints (metres, z up) from BlazePose's world landmarks, for the mesh
            generator's body fit.
    """

    images: np.ndarray
    points: np.ndarray
    masks: np.ndarray
    frame_index: np.ndarray
    fps: float
    box: tuple[int, int, int]
    skipped: int
    joints3d: np.ndarray | None = None


def square_box(points: np.ndarray, *, margin: float = CROP_MARGIN) -> tuple[int, int, int]:
    """(x0, y0, side): the square centred on the bounding box of (..., 2) points, ``margin`` of its larger
    side added on every side."""
    pts = np.asarray(points, np.float64).reshape(-1, 2)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    side = int(round(max(hi - lo) * (1 + 2 * margin)))
    centre = (lo + hi) / 2
    return int(round(centre[0] - side / 2)), int(round(centre[1] - side / 2)), max(side, 8)


def cut_square(image: np.ndarray, box: tuple[int, int, int], *, replicate: bool = True) -> np.ndarray:
    """The ``box`` square of (H, W[, C]) ``image``; outside it the border is replicated (or zero)."""
    x0, y0, side = box
    h, w = image.shape[:2]
    pad = max(0, -x0, -y0, x0 + side - w, y0 + side - h)
    if pad:
        mode = cv2.BORDER_REPLICATE if replicate else cv2.BORDER_CONSTANT
        image = cv2.copyMakeBorder(image, pad, pad, pad, pad, mode, value=0)
    return np.ascontiguousarray(image[y0 + pad:y0 + pad + side, x0 + pad:x0 + pad + side])


def video_frames(path: str | Path, *, size: int, targets: int = 64, stride: int | None = None,
                 person: str | int = "largest", model: BlazePose | None = None) -> VideoFrames:
    """Track the person through a video and keep frame 0 and ``targets`` later frames, ``stride`` apart
    (default: spread over the whole video).

    Raises:
        InputError: unreadable video, no person in the first frame, fewer than two usable frames.
    """
    cap, info = open_video(path)
    cap.release()
    total = info.frames or sum(1 for _ in iter_video_frames(path))
    stride = max(1, (total - 1) // max(targets, 1)) if stride is None else int(stride)
    wanted = set(range(0, total, stride)[: targets + 1])
    model = model or default_model()
    kept: list[tuple[int, np.ndarray, object]] = []
    skipped = 0
    current: list[np.ndarray] = []

    def frames():  # the tracker yields once per frame it takes: current[-1] is that frame
        for frame in iter_video_frames(path):
            current[:] = [frame]
            yield frame

    for i, lm in enumerate(track_frames(frames(), person=person, model=model, source=path)):
        if i == 0 and lm is None:
            raise InputError("no person in the first frame (the reference of the reconstruction protocol)", path)
        if i in wanted:
            if lm is None:
                skipped += 1
            else:
                kept.append((i, current[0], lm))
        if i >= max(wanted):
            break
    if len(kept) < 2:
        raise InputError("fewer than two frames with the person to evaluate", path)
    box = square_box(np.concatenate([lm.xy[:NUM_BODY_LANDMARKS] for _, _, lm in kept]))
    scale = size / box[2]
    images, points, masks = [], [], []
    for _, frame, lm in kept:
        images.append(cv2.resize(cut_square(frame, box), (size, size), interpolation=cv2.INTER_AREA))
        mask = lm.person_mask(frame.shape[1], frame.shape[0])
        masks.append(cv2.resize(cut_square(mask, box, replicate=False), (size, size)) > 0.5)
        pts, _ = blazepose_to_h36m(lm.xy[:NUM_BODY_LANDMARKS])
        points.append((pts - box[:2]) * scale)
    _, joints3d, _ = landmarks_to_joints(np.stack([lm.xy[:NUM_BODY_LANDMARKS] for _, _, lm in kept]),
                                         np.stack([lm.world[:NUM_BODY_LANDMARKS] for _, _, lm in kept]),
                                         np.stack([lm.visibility[:NUM_BODY_LANDMARKS] for _, _, lm in kept]))
    return VideoFrames(np.stack(images), np.stack(points).astype(np.float32), np.stack(masks),
                       np.array([i for i, _, _ in kept]), info.fps, box, skipped, joints3d)


def video_pairs(frames: VideoFrames) -> FramePairs:
    """Frame 0 as every pair's reference, each later frame a target."""
    n = len(frames.images) - 1
    size = frames.images.shape[1]
    ref_pts = np.repeat(frames.points[:1], n, axis=0)
    tgt_pts = frames.points[1:]
    return FramePairs(np.repeat(frames.images[:1], n, axis=0), frames.images[1:], ref_pts, tgt_pts,
                      body_structures(ref_pts, size), body_structures(tgt_pts, size),
                      np.repeat(frames.masks[:1], n, axis=0), frames.masks[1:])


def with_mesh(pairs: FramePairs, frames: VideoFrames) -> FramePairs:
    """The pairs with the correspondence of Anny fitted to every frame (:func:`stages.mesh_frames.video_mesh_track`),
    for the mesh generator: the fitted mesh's silhouettes stand in for the masks it is given (the scores still use
    BlazePose's person masks)."""
    from dataclasses import replace

    from motion2video.frames.mesh_flow import band_width, dense_flow, extend_flow
    from motion2video.stages.mesh_frames import video_mesh_track

    track = video_mesh_track(frames.joints3d, frames.points, size=frames.images.shape[1], person_mask=frames.masks[0])
    band = band_width(frames.images.shape[1])
    flows = [extend_flow(dense_flow(track.uv[0], track.visible[0], track.uv[t], track.visible[t], track.masks[t]),
                         band) for t in range(1, len(track.uv))]
    return replace(pairs, mesh_flow=np.stack([f.flow for f in flows]),
                   mesh_visibility=np.stack([f.visibility for f in flows]),
                   mesh_ref_masks=np.repeat(track.masks[:1], len(flows), axis=0),
                   mesh_tgt_masks=track.masks[1:])


def keypoint_distance(pred: np.ndarray, truth_points: np.ndarray, model: BlazePose | None = None
                      ) -> tuple[float, float]:
    """AKD and the missing rate: BlazePose on each (S, S, 3) predicted frame against the truth's joints.

    Args:
        pred: (N, S, S, 3) uint8 frames.
        truth_points: (N, 17, 2) the joints found on the real frames.
    Returns:
        (mean joint distance in pixels over the frames with a pose, share of frames without one).
    """
    dists, missing = [], 0
    for image, truth in zip(pred, truth_points):
        try:
            found = estimate_image(image, model=model)
        except InputError:
            missing += 1
            continue
        dists.append(float(np.linalg.norm(found.points2d - truth, axis=-1).mean()))
    return (float(np.mean(dists)) if dists else float("nan")), missing / max(len(pred), 1)


def truth_points(images: np.ndarray, fallback: np.ndarray, model: BlazePose | None = None) -> np.ndarray:
    """(N, 17, 2) joints BlazePose finds on each real (resized) frame alone, as on a generated one; the
    tracked joints where it finds none."""
    out = np.array(fallback, np.float64, copy=True)
    for i, image in enumerate(images):
        try:
            out[i] = estimate_image(image, model=model).points2d
        except InputError:
            pass
    return out


@dataclass
class VideoEvaluation:
    """The protocol's scores: the frame evaluation (PSNR, SSIM, person metrics, predictions) plus ``l1``,
    ``akd`` and ``akd_missing`` per method, and where the frames came from."""

    frames: FrameEvaluation
    l1: dict[str, float]
    akd: dict[str, float]
    akd_missing: dict[str, float]
    video: str
    frame_index: np.ndarray
    skipped: int

    def to_dict(self) -> dict:
        out = self.frames.to_dict()
        for name, scores in out["results"].items():
            scores["l1"] = round(self.l1[name], 5)
            scores["akd"] = None if not np.isfinite(self.akd[name]) else round(self.akd[name], 3)
            scores["akd_missing"] = round(self.akd_missing[name], 4)
        out.update(protocol="reconstruction: frame 0 is the reference, later frames' poses drive, real frames "
                            "are the truth", video=self.video, num_frames=int(len(self.frame_index)),
                   frames=[int(i) for i in self.frame_index[:1]] + [int(self.frame_index[-1])],
                   skipped_frames=self.skipped, person_mask="BlazePose segmentation")
        return out


def evaluate_video(model, path: str | Path, *, size: int, targets: int = 64, stride: int | None = None,
                   baseline_models: dict | None = None) -> VideoEvaluation:
    """Run the protocol (module docstring) on one video for a body frame generator (either kind)."""
    pose_model = default_model()
    frames = video_frames(path, size=size, targets=targets, stride=stride, model=pose_model)
    pairs = video_pairs(frames)
    if getattr(model, "kind", None) == "mesh" or any(getattr(m, "kind", None) == "mesh"
                                                     for m in (baseline_models or {}).values()):
        pairs = with_mesh(pairs, frames)
    evaluation = evaluate_pairs(model, pairs, domain="body", baseline_models=baseline_models)
    truth = truth_points(pairs.tgt_images, pairs.tgt_points, pose_model)
    l1, akd, missing = {}, {}, {}
    for name in evaluation.results:
        pred = evaluation.predictions[name]
        l1[name] = float(np.abs(pred.astype(np.float64) - pairs.tgt_images).mean() / 255.0)
        akd[name], missing[name] = keypoint_distance(pred, truth, pose_model)
    return VideoEvaluation(evaluation, l1, akd, missing, str(path), frames.frame_index, frames.skipped)
