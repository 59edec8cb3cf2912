"""The reconstruction protocol of the image-animation field (FOMM, TPSMM) on a real video.

Frame 0 (the first frame with the person) is the reference; later frames' estimated poses drive the
generator; the real later frames are the truth. Every frame is cut to one square around the person over the
evaluated frames (10% margin) and resized to the generator's size.

Per method (the generator, copy-reference, limb-warp, and named baseline generators):

- ``l1``: mean absolute error of the whole frame, in [0, 1] (the field's L1);
- ``psnr``, ``ssim`` of the whole frame; ``person_psnr``, ``person_ssim``, ``person_sharpness`` over the
  person, whose mask is BlazePose's segmentation of the real frame;
- ``head_psnr``, ``head_ssim`` over the head: a square around the truth frame's head and neck joints
  (:func:`head_box_masks`);
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
from motion2video.generator.data import FramePairs, body_structures
from motion2video.generator.scores import FrameEvaluation, evaluate_pairs
from motion2video.pose.blazepose import NUM_BODY_LANDMARKS, BlazePose
from motion2video.pose.estimate import default_model, estimate_image, iter_video_frames, landmarks_to_joints
from motion2video.pose.h36m import blazepose_to_h36m
from motion2video.pose.track import VideoTrack
from motion2video.stages.people import video_track

CROP_MARGIN = 0.1
# head_box_masks: the head's square is centred between the neck/nose and head joints, its side this many times the
# thorax-to-head distance (Human3.6M: 236 mm, about a head's height; 1.2 takes in the chin and the hair at the
# sides), and at least MIN_HEAD_BOX_PX pixels.
HEAD_BOX_SCALE = 1.2
MIN_HEAD_BOX_PX = 4


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


def tail_start(total: int, fraction: float) -> int:
    """The first frame of a video's tail: ``round(fraction * total)`` of its ``total`` frames come before it
    (the part a generator may be fine-tuned on; :mod:`motion2video.evaluation.personalise`)."""
    if not 0.0 <= fraction < 1.0:
        raise InputError(f"the start fraction must be in [0, 1), got {fraction:g}")
    return int(round(fraction * total))


def protocol_frames(total: int, *, targets: int = 64, stride: int | None = None, start_fraction: float = 0.0
                    ) -> list[int]:
    """The video frames the protocol scores: frame 0 (the reference), then ``targets`` frames ``stride`` apart
    (default: spread over the video), from the tail's first frame (:func:`tail_start`) on when
    ``start_fraction`` > 0."""
    first = tail_start(total, start_fraction)
    if first == 0:
        stride = max(1, (total - 1) // max(targets, 1)) if stride is None else int(stride)
        return list(range(0, total, stride)[: targets + 1])
    stride = max(1, (total - first) // max(targets, 1)) if stride is None else int(stride)
    return [0] + list(range(first, total, stride)[:targets])


def crop_frames(path: str | Path, track: VideoTrack, indices: list[int], *, size: int,
                box: tuple[int, int, int] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frames ``indices`` of a video (the person found in each) cut to the square ``box`` (default: the
    :func:`square_box` of their landmarks) and resized to ``size``.

    Returns:
        images (N, S, S, 3) uint8, points (N, 17, 2) float32 canonical joints in the crop's pixels, masks
        (N, S, S) bool person masks (BlazePose's segmentation above one half).
    Raises:
        InputError: the video decodes to fewer frames than ``indices`` need.
    """
    if box is None:
        box = square_box(np.concatenate([track.body_landmarks(i) for i in indices]))
    scale = size / box[2]
    wanted = set(indices)
    images, points, masks = {}, {}, {}
    last = max(indices)
    for i, frame in enumerate(iter_video_frames(path)):
        if i in wanted:
            images[i] = cv2.resize(cut_square(frame, box), (size, size), interpolation=cv2.INTER_AREA)
            mask = track.person_mask(i)
            masks[i] = cv2.resize(cut_square(mask, box, replicate=False), (size, size)) > 0.5
            pts, _ = blazepose_to_h36m(track.body_landmarks(i))
            points[i] = (pts - box[:2]) * scale
        if i >= last:
            break
    missing = [i for i in indices if i not in images]
    if missing:
        raise InputError(f"the video ended before frame {missing[0]} (it was tracked with more frames)", path)
    return (np.stack([images[i] for i in indices]), np.stack([points[i] for i in indices]).astype(np.float32),
            np.stack([masks[i] for i in indices]))


def video_frames(path: str | Path, *, size: int, targets: int = 64, stride: int | None = None,
                 person: str | int = "largest", model: BlazePose | None = None, start_fraction: float = 0.0,
                 track: VideoTrack | None = None) -> VideoFrames:
    """Track the person through a video (or take ``track``; tracks are cached:
    :func:`motion2video.stages.people.video_track`) and keep frame 0 and ``targets`` later frames,
    ``stride`` apart (default: spread over the whole video, or over its tail from ``start_fraction`` of it
    on).

    Raises:
        InputError: unreadable video, no person in the first frame, fewer than two usable frames.
    """
    if track is None:
        track = video_track(path, person=person, model=model)
    wanted = protocol_frames(track.num_frames, targets=targets, stride=stride, start_fraction=start_fraction)
    if not track.found[0]:
        raise InputError("no person in the first frame (the reference of the reconstruction protocol)", path)
    kept = [i for i in wanted if track.found[i]]
    if len(kept) < 2:
        raise InputError("fewer than two frames with the person to evaluate", path)
    box = square_box(np.concatenate([track.body_landmarks(i) for i in kept]))
    images, points, masks = crop_frames(path, track, kept, size=size, box=box)
    body = slice(0, NUM_BODY_LANDMARKS)
    _, joints3d, _ = landmarks_to_joints(track.xy[kept, body], track.world[kept, body], track.visibility[kept, body],
                                         width=track.width, height=track.height, fps=track.fps)
    return VideoFrames(images, points, masks, np.array(kept), track.fps, box, len(wanted) - len(kept), joints3d)


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
    """The pairs with the correspondence of Anny fitted to every frame (:func:`stages.mesh_generation.video_mesh_track`),
    for the mesh generator: the fitted mesh's silhouettes (its surface fitted to frame 0's person outline, grown by
    :func:`generator.outline_fit.outline_margin`) stand in for the masks it is given (the scores still use BlazePose's
    person masks). As in ``synthesize``, a vertex frame 0 shows counts as shown only where it lands on the person
    (:func:`generator.mesh_reference.on_person`), the colours are sampled from the segmented person
    (:func:`generator.mesh_warp.mesh_source_mask`), and frame 0's face, when one is found, is laid over the generated
    heads (:func:`stages.pictured_face.pictured_face`, :func:`generator.head_paste.head_moves`)."""
    from dataclasses import replace

    from motion2video.generator.mesh_flow import MeshTrack, complete_reference_uv, flows_to_targets, grow_masks
    from motion2video.generator.mesh_reference import on_person
    from motion2video.generator.outline_fit import outline_margin
    from motion2video.generator.head_paste import pixel_index_affine
    from motion2video.stages.mesh_generation import video_mesh_track
    from motion2video.stages.pictured_face import (
        face_moves, landmark_triangles, landmarks_in_reference, pictured_face,
    )
    from renderers import anny_model

    size = frames.images.shape[1]
    track, phenotype = video_mesh_track(frames.joints3d, frames.points, size=size, person_mask=frames.masks[0])
    # as synthesize does (stages.mesh_generation.mesh_video): a vertex frame 0 shows counts as shown only on the person
    shown = track.visible.copy()
    shown[0] &= on_person(track.uv[0], frames.masks[0])
    track = MeshTrack(track.uv, shown, track.masks)
    margin = outline_margin(size)  # the body is fitted to frame 0's outline (video_mesh_track)
    ref_uv = complete_reference_uv(track.uv[0], track.visible[0], image=frames.images[0],
                                   person=frames.masks[0])
    flows, visibility = flows_to_targets(ref_uv, track.visible[0], track, range(1, len(track.uv)), margin=margin)
    pairs = replace(pairs, mesh_flow=flows, mesh_visibility=visibility,
                    mesh_ref_masks=np.repeat(grow_masks(track.masks[:1], margin), len(flows), axis=0),
                    mesh_tgt_masks=grow_masks(track.masks[1:], margin))
    face = pictured_face(frames.images[0], frames.points[0], person=frames.masks[0].astype(np.float32))
    if face is None:
        return pairs
    # the face found in frame 0's square; frame 0 itself is the picture it is laid from
    head = face_moves(face, track.uv[0], track.uv[1:], track.visible[1:], rest=anny_model.anny_rest(phenotype))
    mattes = cv2.warpAffine(face.matte, pixel_index_affine(face.to_reference), (size, size), flags=cv2.INTER_LINEAR)
    n = len(flows)
    return replace(pairs, head_mattes=np.repeat(mattes[None], n, axis=0), head_affines=head.affines,
                   head_weights=head.weights, head_shown=head.shown,
                   head_landmarks=np.repeat(landmarks_in_reference(face)[None], n, axis=0),
                   head_triangles=np.repeat(landmark_triangles()[None], n, axis=0), head_offsets=head.offsets)


def head_box_masks(points: np.ndarray, size: int) -> np.ndarray:
    """(N, S, S) bool: the head of each frame, a square around its canonical joints (N, 17, 2) (pixels): centred
    between the neck/nose and the head joint, its side :data:`HEAD_BOX_SCALE` times the thorax-to-head distance
    (at least :data:`MIN_HEAD_BOX_PX`), clipped to the frame
    (:func:`motion2video.generator.head_paste.head_squares`)."""
    from motion2video.generator.head_paste import head_squares

    return head_squares(points, size, scale=HEAD_BOX_SCALE, min_side=MIN_HEAD_BOX_PX)


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
            found = estimate_image(image, model=model, second_look=False)
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
            out[i] = estimate_image(image, model=model, second_look=False).points2d
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
    start_fraction: float = 0.0
    box: tuple[int, int, int] | None = None

    def to_dict(self) -> dict:
        out = self.frames.to_dict()
        for name, scores in out["results"].items():
            scores["l1"] = round(self.l1[name], 5)
            scores["akd"] = None if not np.isfinite(self.akd[name]) else round(self.akd[name], 3)
            scores["akd_missing"] = round(self.akd_missing[name], 4)
        out.update(protocol="reconstruction: frame 0 is the reference, later frames' poses drive, real frames "
                            "are the truth", video=self.video, num_frames=int(len(self.frame_index)),
                   frames=[int(i) for i in self.frame_index[:1]] + [int(self.frame_index[-1])],
                   skipped_frames=self.skipped, person_mask="BlazePose segmentation",
                   head_mask=f"a square of {HEAD_BOX_SCALE:g} x the thorax-to-head distance around the truth frame's "
                             "neck and head joints")
        if self.start_fraction:
            out.update(start_fraction=self.start_fraction, targets_from=int(self.frame_index[1]))
        if self.box is not None:
            out["crop_box"] = [int(v) for v in self.box]
        return out


def evaluate_video_frames(model, frames: VideoFrames, *, video: str | Path, baseline_models: dict | None = None,
                          start_fraction: float = 0.0, pose_model: BlazePose | None = None) -> VideoEvaluation:
    """Score a generator (and the baselines) on frames of :func:`video_frames` (the module docstring's
    metrics)."""
    pose_model = pose_model or default_model()
    pairs = video_pairs(frames)
    if getattr(model, "kind", None) == "mesh" or any(getattr(m, "kind", None) == "mesh"
                                                     for m in (baseline_models or {}).values()):
        pairs = with_mesh(pairs, frames)
    evaluation = evaluate_pairs(model, pairs, domain="body", baseline_models=baseline_models,
                                tgt_head_masks=head_box_masks(pairs.tgt_points, pairs.tgt_images.shape[1]))
    truth = truth_points(pairs.tgt_images, pairs.tgt_points, pose_model)
    l1, akd, missing = {}, {}, {}
    for name in evaluation.results:
        pred = evaluation.predictions[name]
        l1[name] = float(np.abs(pred.astype(np.float64) - pairs.tgt_images).mean() / 255.0)
        akd[name], missing[name] = keypoint_distance(pred, truth, pose_model)
    return VideoEvaluation(evaluation, l1, akd, missing, str(video), frames.frame_index, frames.skipped,
                           start_fraction, frames.box)


def evaluate_video(model, path: str | Path, *, size: int, targets: int = 64, stride: int | None = None,
                   baseline_models: dict | None = None, start_fraction: float = 0.0,
                   track: VideoTrack | None = None) -> VideoEvaluation:
    """Run the protocol (module docstring) on one video for a body frame generator (either kind); with
    ``start_fraction`` > 0 the targets come from the video's tail only (frame 0 stays the reference)."""
    pose_model = default_model()
    frames = video_frames(path, size=size, targets=targets, stride=stride, model=pose_model,
                          start_fraction=start_fraction, track=track)
    return evaluate_video_frames(model, frames, video=path, baseline_models=baseline_models,
                                 start_fraction=start_fraction, pose_model=pose_model)
