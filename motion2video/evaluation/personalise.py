"""Personalisation: fine-tune a body frame generator on one person's video, scored on the video's tail.

The video is tracked once (BlazePose, cached: :func:`motion2video.stages.people.video_track`). Its first
``train_fraction`` of frames (80% by default) are the training data: every frame with the person, cut to one
square around the person over those frames (:func:`~motion2video.evaluation.reconstruction.square_box`, the crop
of the reconstruction protocol) and resized to the model's size, with its tracked joints and BlazePose's person
mask; a training pair is any two of them. The rest of the video (the tail) is never trained on: it is scored
afterwards by the reconstruction protocol of ``evaluate-frames --video`` with the same start fraction
(:func:`~motion2video.evaluation.reconstruction.video_frames`: frame 0 the reference, targets from the tail
only), for the fine-tuned model and the model it started from, on the same pairs.

Frame 0 is the reference at test time and also a training frame: the protocol's reference is always
available to whoever animates it, so training on it is no leak; the tail's frames (the truth) are unseen.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from motion2video.core.errors import InputError
from motion2video.evaluation.reconstruction import (VideoEvaluation, crop_frames, evaluate_video_frames,
                                                  protocol_frames, square_box, tail_start, video_frames)
from motion2video.generator.specs import FrameSequences
from motion2video.pose.track import VideoTrack

TRAIN_FRACTION = 0.8
MIN_VIDEO_FRAMES = 10  # 8 to train on and 2 to score, at the default fraction
MAX_TRAIN_FRAMES = 2000  # longer training parts are subsampled evenly (128x128 frames: 100 MB)


@dataclass(frozen=True)
class VideoTrainingData:
    """The training part of a video as one sequence of person crops.

    Attributes:
        sequences: one body sequence (1, T, S, S, 3) with its joints and person masks.
        frame_index: (T,) the video frames it holds.
        box: (x0, y0, side) of the crop in the video's pixels.
        end: the first frame not trained on (the tail's first frame).
    """

    sequences: FrameSequences
    frame_index: np.ndarray
    box: tuple[int, int, int]
    end: int


def training_frames(track: VideoTrack, end: int, *, max_frames: int = MAX_TRAIN_FRAMES) -> list[int]:
    """The frames before ``end`` where the person was found, at most ``max_frames`` of them spread evenly."""
    found = [i for i in range(min(end, track.num_frames)) if track.found[i]]
    if len(found) > max_frames:
        pick = np.unique(np.round(np.linspace(0, len(found) - 1, max_frames)).astype(int))
        found = [found[i] for i in pick]
    return found


def video_training_data(path: str | Path, track: VideoTrack, *, size: int, end: int,
                        max_frames: int = MAX_TRAIN_FRAMES) -> VideoTrainingData:
    """The frames before ``end`` (:func:`training_frames`) as one training sequence (module docstring): a
    training pair is any two of its frames.

    Raises:
        InputError: fewer than two frames with the person before ``end``.
    """
    indices = training_frames(track, end, max_frames=max_frames)
    if len(indices) < 2:
        raise InputError(f"the person is found in {len(indices)} of the {end} frames to train on; fine-tuning "
                         "needs at least 2", path)
    box = square_box(np.concatenate([track.body_landmarks(i) for i in indices]))
    images, points, masks = crop_frames(path, track, indices, size=size, box=box)
    seqs = FrameSequences(domain="body", images=images[None], points=points[None], structure_images=None,
                          identity=np.zeros(1, np.int64), clip=np.array([Path(path).name]),
                          start=np.zeros(1, np.int64), masks=masks[None])
    return VideoTrainingData(seqs, np.asarray(indices), box, end)


@dataclass(frozen=True)
class PersonaliseSettings:
    """How the fine-tune runs (see ``motion2video train-frames --video``).

    Attributes:
        steps, batch_size, lr, crop, edge_weight, person_weight, seed, checkpoint_every: as
            :class:`motion2video.generator.training.TrainFramesConfig`; ``crop`` 0 trains on whole frames, as the
            protocol generates them (the warp generator's inference crop is then the whole square; a smaller
            training crop is centred on the pair's joints when they do not fit, so it would seldom see the hands).
        flip: mirror pairs left-right (off: a person is not symmetric, e.g. gloves of two colours).
        train_fraction: the share of the video's frames trained on; the rest is scored.
        targets: tail frames scored (spread over the tail).
        max_train_frames: at most this many training frames (spread evenly).
    """

    steps: int = 600
    batch_size: int = 8
    lr: float = 5e-4
    crop: int = 0
    edge_weight: float = 2.0
    person_weight: float = 2.0
    seed: int = 0
    checkpoint_every: int = 250
    flip: bool = False
    train_fraction: float = TRAIN_FRACTION
    targets: int = 64
    max_train_frames: int = MAX_TRAIN_FRAMES


@dataclass
class PersonaliseResult:
    """A fine-tune and its score on the tail.

    Attributes:
        checkpoint: the fine-tuned model's file.
        generic_name: the name of the model it started from (its file's stem).
        evaluation: the protocol on the tail: ``generator`` is the fine-tuned model, ``generic_name`` the
            one it started from, next to copy-reference and limb-warp.
        data: the training part.
        train: the :class:`motion2video.generator.training.TrainFramesResult`.
        wall_s: seconds of the whole run (tracking, data, training, scoring).
        settings: how it was fine-tuned.
    """

    checkpoint: Path
    generic_name: str
    evaluation: VideoEvaluation
    data: VideoTrainingData
    train: object
    wall_s: float
    settings: PersonaliseSettings = PersonaliseSettings()

    def scores(self, name: str) -> dict:
        """l1, person_psnr, akd (and the rest of the protocol's metrics) of one method."""
        return self.evaluation.to_dict()["results"][name]

    def to_dict(self) -> dict:
        personal, generic = self.scores("generator"), self.scores(self.generic_name)
        ratio = personal["l1"] / generic["l1"] if generic["l1"] else float("nan")
        return {
            "video": self.evaluation.video,
            "checkpoint": str(self.checkpoint),
            "init_from": self.generic_name,
            "personalised": personal,
            "generic": generic,
            "l1_ratio": round(ratio, 4),
            "person_psnr_gain_db": (None if personal["person_psnr"] is None or generic["person_psnr"] is None
                                    else round(personal["person_psnr"] - generic["person_psnr"], 3)),
            "train": {"frames": int(len(self.data.frame_index)), "first_frame": int(self.data.frame_index[0]),
                      "last_frame": int(self.data.frame_index[-1]), "tail_start": int(self.data.end),
                      "crop_box": [int(v) for v in self.data.box], "steps": int(self.train.steps),
                      "wall_s": round(self.train.wall_s, 1),
                      "steps_per_second": round(self.train.steps_per_second, 3),
                      "settings": dataclasses.asdict(self.settings)},
            "tail": self.evaluation.to_dict(),
            "wall_s": round(self.wall_s, 1),
        }


def check_tail(track: VideoTrack, path: str | Path, *, train_fraction: float, targets: int) -> None:
    """InputError unless the video is long enough to split (:data:`MIN_VIDEO_FRAMES`), frame 0 shows the
    person (the protocol's reference) and some scored tail frame does."""
    total = track.num_frames
    if total < MIN_VIDEO_FRAMES:
        raise InputError(f"the video is too short: {total} frames; fine-tuning on it needs at least "
                         f"{MIN_VIDEO_FRAMES} ({train_fraction:.0%} to train on, the rest to score)", path)
    if not track.found[0]:
        raise InputError("no person in the first frame (the reference of the reconstruction protocol)", path)
    tail = protocol_frames(total, targets=targets, start_fraction=train_fraction)[1:]
    if not any(track.found[i] for i in tail):
        raise InputError(f"no person in the video's tail (frames {tail_start(total, train_fraction)} on) to "
                         "score the fine-tune on", path)


def personalise(video: str | Path, *, init_from: str | Path, output: str | Path,
                settings: PersonaliseSettings = PersonaliseSettings(), resume: bool = False, progress: bool = True,
                note: Callable[[str], None] | None = None, track: VideoTrack | None = None) -> PersonaliseResult:
    """Fine-tune the body generator ``init_from`` on the first part of ``video`` into ``output`` and score
    it and ``init_from`` on the tail (module docstring). Everything that can refuse the input (the model,
    the video, its person, its length) is checked before anything is written.

    Raises:
        InputError: not a body generator, an unreadable video, no person, a video too short to split.
    """
    from motion2video.generator.checkpoint import load_frame_model
    from motion2video.generator.training import TrainFramesConfig, train_frames
    from motion2video.stages.people import video_track

    t0 = time.perf_counter()
    generic = load_frame_model(init_from)
    cfg = generic.config
    if cfg.domain != "body":
        raise InputError("fine-tuning on a video needs a body frame generator (this one makes face frames)",
                         generic.path)
    if generic.kind == "mesh":
        raise InputError("fine-tuning on a video takes a keypoint generator (warp or analogy): a mesh generator "
                         "needs Anny fitted to every training frame, which this fine-tune does not do", generic.path)
    if settings.crop > cfg.image_size:
        raise InputError(f"--crop {settings.crop} is larger than the model's {cfg.image_size} px frames", generic.path)
    notes: list[str] = []  # said once the video is accepted: a refused input is one line
    if track is None:
        track = video_track(video, note=notes.append)
    check_tail(track, video, train_fraction=settings.train_fraction, targets=settings.targets)
    for line in notes:
        if note:
            note(line)
    end = tail_start(track.num_frames, settings.train_fraction)
    tail = video_frames(video, size=cfg.image_size, targets=settings.targets, start_fraction=settings.train_fraction,
                        track=track)
    data = video_training_data(video, track, size=cfg.image_size, end=end, max_frames=settings.max_train_frames)
    if note:
        note(f"training on {len(data.frame_index)} frames (0..{int(data.frame_index[-1])}), scoring "
             f"{len(tail.frame_index) - 1} tail frames ({int(tail.frame_index[1])}..{int(tail.frame_index[-1])}) "
             f"against frame 0")
    config = TrainFramesConfig(steps=settings.steps, batch_size=settings.batch_size, lr=settings.lr,
                               crop=settings.crop, checkpoint_every=settings.checkpoint_every, seed=settings.seed,
                               model_kind=generic.kind, edge_weight=settings.edge_weight,
                               person_weight=settings.person_weight, flip=settings.flip)
    meta = {"video": str(video), "video_frames": track.num_frames, "train_fraction": settings.train_fraction,
            "train_frames": [int(data.frame_index[0]), int(data.frame_index[-1])],
            "crop_box": [int(v) for v in data.box]}
    trained = train_frames(data.sequences, output=output, config=config, model_config=cfg, resume=resume,
                           progress=progress, init_from=generic.path, extra_metadata=meta)
    personal = load_frame_model(trained.path)
    name = generic.path.name.removesuffix(".safetensors")
    evaluation = evaluate_video_frames(personal.model, tail, video=video, baseline_models={name: generic.model},
                                       start_fraction=settings.train_fraction)
    return PersonaliseResult(Path(trained.path), name, evaluation, data, trained, time.perf_counter() - t0,
                             settings)
