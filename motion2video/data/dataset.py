"""Motion datasets for the motion models: clips -> split -> windows -> normalised features.

:func:`build_dataset` loads a folder of BVH files (default ``../shared/data/mocap`` with its
``manifest.csv``), a single body clip, or face captures, resamples everything to 25 fps, splits the clips
deterministically (CMU clips by subject, every other clip on its own), computes normalisation statistics on
the training split and serves

- :meth:`MotionDataset.sample_batch`: random augmented training windows (left/right mirroring, rotation
  about the vertical axis, +-20% speed), and
- :meth:`MotionDataset.windows`: every sliding window of a split, un-augmented, for validation and
  evaluation.

The feature encoding and the canonical window frame are pure functions in
:mod:`motion2video.data.windows`; this module only organises clips. :func:`encode_observation` and
:func:`decode_samples` carry one user clip to model features and sampled futures back to joints.

Corpus (a mocap folder with ``manifest.csv``, :mod:`motion2video.data.corpus`): every file of every
format is read (:func:`motion2video.formats.mocap.load_mocap`); copies of one recorded trial in several
folders are dropped (``drop_duplicates``); each clip belongs to a split group, its performer (a CMU
subject, across all folders) or its source, linked where a performer is unknown.

Split rule (``held_out="corpus"``, the default): the groups pinned in
:data:`motion2video.data.corpus.TEST_GROUPS` / :data:`~motion2video.data.corpus.VAL_GROUPS` hold out whole
subjects and sources; every other group trains. When the clips hold none of the pinned groups (another
folder), when pinning would leave fewer than two groups to train on (a few linked test clips), or with
``held_out="hash"``, groups are ordered by a hash of
``(split_seed, group)`` and assigned in that order to test until it holds ``test_fraction`` of the frames,
then to validation until ``val_fraction``, the rest to training; at least one CMU subject is held out for
test when there are two or more subjects. The split is a list of clip names, written into checkpoints.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from motion2video.data import windows as W
from motion2video.data.corpus import (
    SUBJECT_TEST_GROUPS,
    TEST_GROUPS,
    action_class,
    corpus_rows,
    pinned_split,
    source_of,
)
from motion2video.data.clip_cache import cached_canonical
from motion2video.data.corpus import clip_group as corpus_group
from motion2video.data.face_data import face_files, load_face_clip, mirror_face
from motion2video.data.licences import licence_record
from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion, Motion
from motion2video.formats.mocap import load_mocap
from motion2video.core.skeletons import H36M_17

DEFAULT_MOCAP = Path(__file__).resolve().parents[3] / "shared" / "data" / "mocap"
DEFAULT_FACE = Path(__file__).resolve().parents[3] / "shared" / "data" / "face"
BODY_SUFFIXES = (".bvh", ".npz", ".json")
MULTIMODAL_SOURCE = "procedural:multimodal"  # --data value naming the known-answer benchmark
MULTIMODAL_CLIPS = 2000
HELD_OUT_RULES = ("corpus", "hash", "subjects")


@dataclass(frozen=True)
class DatasetConfig:
    """How clips become training windows.

    Attributes:
        layout: feature layout, ``"body3d"``, ``"body2d"`` or ``"face"``.
        fps: every clip is resampled to this rate.
        observed: observed frames per window (To).
        future: future frames per window (Tf).
        stride: frames between consecutive sliding windows (validation and evaluation windows).
        canonical_heading: rotate each window about z so the body faces -y at its last observed frame.
        mirror: left/right mirroring augmentation (probability 0.5).
        rotate: random rotation about z (body layouts). With canonical_heading on, every window is
            rotated to its own heading anyway, so this augmentation only acts when canonical_heading is off.
        speed: speed augmentation range: windows are played at a rate drawn from [1 - speed, 1 + speed].
        val_fraction, test_fraction: share of frames held out (by group) for validation and test.
        split_seed: seed of the deterministic split.
        min_std: floor of the normalisation standard deviation.
        held_out: ``"corpus"``: the corpus's pinned held-out groups when the clips hold any of them, else
            the hash rule; ``"hash"``: the hash rule only (module docstring); ``"subjects"``: as ``"corpus"``
            with one Bandai-Namco performer per set held out too
            (:data:`motion2video.data.corpus.SUBJECT_TEST_GROUPS`).
        drop_duplicates: keep one copy of a trial found in several folders of a mocap folder
            (:func:`motion2video.data.corpus.duplicates`).
        face_head_pose: ``"procedural"``: a face capture whose head pose is all zero (Live Link Face takes
            recorded without head streaming) gets a head-pose track from
            :func:`motion2video.data.face_dynamics.head_pose_track` (seeded by the clip name); captures with
            real head pose keep it. ``"zero"``: head pose as captured.
        balance_actions: training windows are drawn with weight ``share ** -balance_actions``, ``share`` the
            fraction of training windows whose clip has the window's action label (clips without one form
            one class): 0 draws every window alike (the corpus mix, half salsa), 1 gives every action the
            same share of the batches, 0.5 is between (:func:`clip_sampling_weights`).
        balance_sources: the same for the clip's source folder (``cmu``, ``acrnn``, ``cmu-bench``, ...).
    """

    layout: str = "body3d"
    fps: float = 25.0
    observed: int = 16
    future: int = 48
    stride: int = 8
    canonical_heading: bool = True
    mirror: bool = True
    rotate: bool = True
    speed: float = 0.2
    val_fraction: float = 0.1
    test_fraction: float = 0.15
    split_seed: int = 0
    min_std: float = 1e-3
    face_head_pose: str = "procedural"
    held_out: str = "corpus"
    drop_duplicates: bool = True
    balance_actions: float = 0.0
    balance_sources: float = 0.0

    def __post_init__(self) -> None:
        if not (0.0 <= self.balance_actions <= 1.0 and 0.0 <= self.balance_sources <= 1.0):
            raise ValueError(f"balance_actions and balance_sources must be in [0, 1], got "
                             f"{self.balance_actions}, {self.balance_sources}")
        W.FeatureLayout(self.layout)  # validates the name
        if self.observed < 2 or self.future < 1:
            raise ValueError(f"need observed >= 2 and future >= 1, got {self.observed}, {self.future}")
        if self.stride < 1:
            raise ValueError(f"stride must be >= 1, got {self.stride}")
        if not 0.0 <= self.speed < 1.0:
            raise ValueError(f"speed must be in [0, 1), got {self.speed}")
        if self.held_out not in HELD_OUT_RULES:
            raise ValueError(f"held_out must be one of {', '.join(HELD_OUT_RULES)}, got {self.held_out!r}")
        if self.face_head_pose not in ("procedural", "zero"):
            raise ValueError(f"face_head_pose must be 'procedural' or 'zero', got {self.face_head_pose!r}")

    @property
    def length(self) -> int:
        return self.observed + self.future

    @property
    def feature_layout(self) -> W.FeatureLayout:
        return W.FeatureLayout(self.layout)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @staticmethod
    def from_dict(d: dict) -> "DatasetConfig":
        fields = {f.name for f in dataclasses.fields(DatasetConfig)}
        unknown = set(d) - fields
        if unknown:
            raise KeyError(f"DatasetConfig has no field(s) {sorted(unknown)}")
        return DatasetConfig(**d)


@dataclass(frozen=True)
class Clip:
    """One clip at the dataset rate.

    Attributes:
        name: clip name (path relative to the data folder, e.g. ``"cmu/08_01.bvh"``).
        data: (T, 17, 3) world joints (body) or (T, 58) face parameters, float32.
        label: coarse action class (``"walk"``, :func:`motion2video.data.corpus.action_class`), or None.
        group: split unit (:func:`motion2video.data.corpus.clip_group`, linked by
            :func:`motion2video.data.corpus.link_groups` in a mocap folder).
        licence: the file's licence (its manifest row's), None when unknown.
    """

    name: str
    data: np.ndarray
    label: str | None
    group: str
    licence: str | None = None

    @property
    def num_frames(self) -> int:
        return int(self.data.shape[0])


@dataclass(frozen=True)
class Split:
    """Clip names per split."""

    train: tuple[str, ...]
    val: tuple[str, ...]
    test: tuple[str, ...]

    def names(self, split: str) -> tuple[str, ...]:
        if split not in ("train", "val", "test"):
            raise ValueError(f"unknown split {split!r}")
        return getattr(self, split)

    def to_dict(self) -> dict:
        return {"train": list(self.train), "val": list(self.val), "test": list(self.test)}

    @staticmethod
    def from_dict(d: dict) -> "Split":
        return Split(tuple(d["train"]), tuple(d["val"]), tuple(d["test"]))


@dataclass
class WindowSet:
    """Every sliding window of some clips (no augmentation).

    Attributes:
        features: (N, L, F) normalised float32, L = observed + future.
        raw: (N, L, F) un-normalised float64 (metres / image units / face parameters).
        frames: the canonical frames of body windows (None for faces).
        clip_names: (N,) clip of each window; starts: (N,) first frame in its clip.
        labels: (N,) action label per window (None when unknown).
        observed: number of observed frames in each window.
    """

    features: np.ndarray
    raw: np.ndarray
    frames: W.WindowFrame | None
    clip_names: tuple[str, ...]
    starts: np.ndarray
    labels: tuple[str | None, ...]
    observed: int

    def __len__(self) -> int:
        return int(self.features.shape[0])

    @property
    def obs(self) -> np.ndarray:
        return self.features[:, : self.observed]

    @property
    def future(self) -> np.ndarray:
        return self.features[:, self.observed:]


@dataclass
class MotionDataset:
    """Clips of one layout with their split and normalisation statistics."""

    config: DatasetConfig
    clips: list[Clip]
    split: Split
    stats: W.NormStats
    source: str
    summary: dict = field(default_factory=dict)

    @property
    def layout(self) -> W.FeatureLayout:
        return self.config.feature_layout

    @property
    def num_features(self) -> int:
        return self.layout.num_features

    def clips_of(self, split: str) -> list[Clip]:
        """Clips of ``split`` (``"train"``, ``"val"``, ``"test"`` or ``"all"``), in dataset order."""
        if split == "all":
            return list(self.clips)
        names = set(self.split.names(split))
        return [c for c in self.clips if c.name in names]

    def windows(self, split: str, *, stride: int | None = None) -> WindowSet:
        """Every full window of the clips of ``split``, ``stride`` frames apart (default config.stride)."""
        return clip_windows(self.clips_of(split), config=self.config, stats=self.stats,
                            stride=stride or self.config.stride)

    def sample_batch(self, rng: np.random.Generator, batch_size: int, *, augment: bool = True) -> np.ndarray:
        """A random batch of training windows, normalised: (B, L, F) float32.

        Clips are drawn in proportion to their number of windows, reweighted by action and source
        (:func:`clip_sampling_weights`, ``config.balance_actions`` / ``balance_sources``); each window gets a random start, a
        speed in [1 - speed, 1 + speed] (lowered to what the clip's length allows, never below 1 - speed,
        so with augmentation a clip a little shorter than a window still gives slowed-down windows), a
        mirror flip with probability 0.5 and (without canonical heading) a random rotation about z.
        """
        cfg = self.config
        length = cfg.length
        slowest = 1.0 - cfg.speed if augment else 1.0
        min_frames = int(np.ceil((length - 1) * slowest - 1e-9)) + 1
        clips = [c for c in self.clips_of("train") if c.num_frames >= min_frames]
        if not clips:
            raise InputError(f"no training clip has the {min_frames} frames a window needs", self.source)
        weights = clip_sampling_weights(clips, min_frames=min_frames, balance_actions=cfg.balance_actions,
                                        balance_sources=cfg.balance_sources)
        picks = rng.choice(len(clips), size=batch_size, p=weights / weights.sum())
        out = []
        for i in picks:
            data = clips[i].data
            speed = 1.0 + rng.uniform(-cfg.speed, cfg.speed) if augment and cfg.speed > 0 else 1.0
            speed = max(min(speed, (data.shape[0] - 1) / (length - 1)), slowest)  # fit the window in the clip
            span = (length - 1) * speed
            start = rng.uniform(0.0, max(data.shape[0] - 1 - span, 0.0)) if augment else \
                float(rng.integers(0, data.shape[0] - length + 1))
            window = W.speed_window(data, start=start, length=length, speed=speed)
            if augment and cfg.mirror and rng.random() < 0.5:
                window = (W.mirror_joints(window, H36M_17.mirror_permutation()) if self.layout.is_body
                          else mirror_face(window))
            if augment and cfg.rotate and self.layout.is_body and not cfg.canonical_heading:
                window = W.rotate_about_z(window, rng.uniform(-np.pi, np.pi), window[cfg.observed - 1, 0])
            out.append(window)
        batch = np.stack(out)  # (B, L, 17, 3) or (B, L, 58)
        raw = encode_windows(batch, config=cfg)[0]
        return self.stats.normalize(raw)

    def describe(self) -> dict:
        """A JSON-able summary of the data (written into checkpoints)."""
        return dict(self.summary)


def clip_sampling_weights(clips: list[Clip], *, min_frames: int, balance_actions: float = 0.0,
                          balance_sources: float = 0.0) -> np.ndarray:
    """Unnormalised probability of drawing each clip for a training window: (N,) float64.

    A clip's weight is its number of window starts (``num_frames - min_frames + 1``, at least 0) times
    ``action_share ** -balance_actions`` times ``source_share ** -balance_sources``, the shares being the
    fractions of all window starts that belong to the clip's action label (None is one class) and to its
    source folder (:func:`motion2video.data.corpus.source_of`). With both at 0 every window is equally
    likely; with ``balance_actions=1`` every action receives the same total weight.
    """
    starts = np.array([max(c.num_frames - min_frames + 1, 0) for c in clips], np.float64)
    weights = starts.copy()
    total = starts.sum()
    if total <= 0:
        return weights
    for key, power in ((lambda c: c.label, balance_actions), (lambda c: source_of(c.name), balance_sources)):
        if power == 0.0:
            continue
        share: dict = {}
        for c, n in zip(clips, starts):
            share[key(c)] = share.get(key(c), 0.0) + n / total
        weights *= np.array([share[key(c)] ** -power if share[key(c)] > 0 else 0.0 for c in clips])
    return weights


# --- encoding --------------------------------------------------------------------------------------------


def encode_windows(windows: np.ndarray, *, config: DatasetConfig) -> tuple[np.ndarray, W.WindowFrame | None]:
    """Raw windows -> un-normalised features.

    Args:
        windows: (B, T, 17, 3) world joints or (B, T, 58) face parameters; the anchor is frame
            ``config.observed - 1`` (T may be just the observed part).
        config: the dataset config (layout, canonical heading).
    Returns:
        (B, T, F) float64 features and the window frames (None for faces).
    """
    layout = config.feature_layout
    if layout.kind == "face":
        return np.asarray(windows, np.float64), None
    return W.body_window_features(windows, layout=layout, anchor=config.observed - 1,
                                  canonical_heading=config.canonical_heading)


def clip_windows(clips: list[Clip], *, config: DatasetConfig, stats: W.NormStats, stride: int) -> WindowSet:
    """Every full window (``config.length`` frames, ``stride`` apart) of ``clips``, un-augmented."""
    raws, names, starts, labels, origins, angles = [], [], [], [], [], []
    for clip in clips:
        st = W.sliding_starts(clip.num_frames, length=config.length, stride=stride)
        if len(st) == 0:
            continue
        batch = np.stack([clip.data[s:s + config.length] for s in st])
        raw, frame = encode_windows(batch, config=config)
        raws.append(raw)
        names += [clip.name] * len(st)
        labels += [clip.label] * len(st)
        starts.append(st)
        if frame is not None:
            origins.append(frame.origin)
            angles.append(frame.angle)
    num_f = config.feature_layout.num_features
    raw = np.concatenate(raws) if raws else np.zeros((0, config.length, num_f))
    frames = None
    if config.feature_layout.is_body:
        frames = W.WindowFrame(origin=np.concatenate(origins) if origins else np.zeros((0, 3)),
                               angle=np.concatenate(angles) if angles else np.zeros(0))
    return WindowSet(features=stats.normalize(raw), raw=raw, frames=frames, clip_names=tuple(names),
                     starts=np.concatenate(starts) if starts else np.zeros(0, np.int64), labels=tuple(labels),
                     observed=config.observed)


def encode_observation(data: np.ndarray, *, config: DatasetConfig, stats: W.NormStats
                       ) -> tuple[np.ndarray, W.WindowFrame | None]:
    """One observed clip segment -> normalised model input.

    Args:
        data: (To, 17, 3) world joints or (To, 58) face parameters, at ``config.fps``.
    Returns:
        (1, To, F) float32 normalised features and the window frame (anchored at the last frame).
    """
    cfg = dataclasses.replace(config, observed=int(data.shape[0]))
    raw, frame = encode_windows(np.asarray(data)[None], config=cfg)
    return stats.normalize(raw), frame


def decode_samples(samples: np.ndarray, *, config: DatasetConfig, stats: W.NormStats,
                   frame: W.WindowFrame | None) -> np.ndarray:
    """Normalised model output -> motion in the clip's own coordinates.

    Args:
        samples: (B, K, T, F) normalised features.
        frame: the window frames the observations were encoded with (body layouts).
    Returns:
        body3d: (B, K, T, 17, 3) world joints (metres, z up); body2d: (B, K, T, 17, 2) pixels of the
        virtual camera; face: (B, K, T, 58) parameters (coefficients clipped to [0, 1]).
    """
    raw = stats.denormalize(samples)
    layout = config.feature_layout
    if layout.kind == "face":
        out = raw.copy()
        out[..., :52] = np.clip(out[..., :52], 0.0, 1.0)
        return out
    joints = W.features_to_joints(raw, dim=layout.dim)
    if layout.kind == "body2d":
        return W.virtual_to_pixels(joints)
    if frame is None:
        raise ValueError("body3d samples need the window frame to go back to world coordinates")
    return W.from_canonical(joints, frame)


def observed_in_layout(data: np.ndarray, *, config: DatasetConfig) -> np.ndarray:
    """The observed frames as the layout draws them: body3d world joints unchanged, body2d joints
    projected to the virtual camera's pixels (through the canonical frame), faces unchanged.

    Args:
        data: (To, 17, 3) world joints or (To, 58) face parameters.
    """
    if config.layout != "body2d":
        return np.asarray(data, np.float64)
    cfg = dataclasses.replace(config, observed=int(data.shape[0]))
    raw, _ = encode_windows(np.asarray(data)[None], config=cfg)
    return W.virtual_to_pixels(W.features_to_joints(raw[0], dim=2))


# --- loading and splitting -------------------------------------------------------------------------------


def coarse_label(action: str | None) -> str | None:
    """A short action class from a manifest description (:func:`motion2video.data.corpus.action_class`):
    ``"walk (start-walk-stop)"`` -> ``"walk"``, ``"dance_a"`` -> ``"dance"``."""
    return action_class(action)


def clip_group(name: str, label: str | None = None) -> str:
    """Split unit of a clip (:func:`motion2video.data.corpus.clip_group`): ``cmu-<subject>`` for CMU
    clips (``08_01.bvh``, or a ``cmu-bench`` label naming the trial), the source for DeepMimic and MASS
    clips, else the name."""
    return corpus_group(name, label)


def make_split(clips: list[Clip], *, val_fraction: float, test_fraction: float, seed: int,
               pinned: bool = True, test_groups: tuple[str, ...] = TEST_GROUPS) -> Split:
    """Deterministic split by group (see the module docstring); ``pinned=False`` is the hash rule only;
    ``test_groups``: the groups pinned to test (:data:`~motion2video.data.corpus.SUBJECT_TEST_GROUPS` for the
    ``"subjects"`` rule)."""
    frames: dict[str, int] = {}
    for c in clips:
        frames[c.group] = frames.get(c.group, 0) + c.num_frames
    assign: dict[str, str] = {}
    if pinned and len(frames) > 2:
        assign = {g: s for g in frames if (s := pinned_split(g, test_groups=test_groups)) is not None}
        if len(frames) - len(assign) < 2:  # fewer than two groups would be left to train on
            assign = {}
    if assign:
        assign.update({g: "train" for g in frames if g not in assign})
    else:
        order = sorted(frames, key=lambda g: hashlib.sha1(f"{seed}:{g}".encode()).hexdigest())
        cmu = [g for g in order if g.startswith("cmu-")]
        if len(cmu) >= 2:  # hold out at least one whole CMU subject for test
            order.remove(cmu[0])
            order.insert(0, cmu[0])
        total = sum(frames.values())
        held_test = held_val = 0
        for g in order:
            if len(frames) > 2 and held_test < test_fraction * total:
                assign[g], held_test = "test", held_test + frames[g]
            elif len(frames) > 2 and held_val < val_fraction * total:
                assign[g], held_val = "val", held_val + frames[g]
            else:
                assign[g] = "train"
    by = {s: tuple(c.name for c in clips if assign[c.group] == s) for s in ("train", "val", "test")}
    return Split(train=by["train"], val=by["val"], test=by["test"])


def _body_clip_from_motion(motion: Motion, *, name: str, fps: float, group: str | None = None,
                           licence: str | None = None) -> Clip:
    if motion.skeleton != "h36m-17" or motion.dim != 3:
        raise InputError(f"body models need 3D h36m-17 joints, got {motion.skeleton} with D={motion.dim}",
                         motion.source or name)
    data = W.resample(motion.joints, motion.fps, fps).astype(np.float32)
    return Clip(name=name, data=data, label=coarse_label(motion.label),
                group=clip_group(name, motion.label) if group is None else group, licence=licence)


def stable_seed(text: str) -> int:
    """A seed derived from a string (the same on every machine and Python run)."""
    return int(hashlib.sha1(text.encode()).hexdigest()[:8], 16)


def _face_clip_from_motion(face: FaceMotion, *, name: str, fps: float, head_pose: str) -> Clip:
    data = W.resample(face.params, face.fps, fps).astype(np.float32)
    if head_pose == "procedural" and not np.any(data[:, 52:]):
        from motion2video.data.face_dynamics import head_pose_track

        data[:, 52:] = head_pose_track(data.shape[0], fps, stable_seed(name))
    return Clip(name=name, data=data, label=coarse_label(face.label), group=name)


def _relative_name(path: Path, root: Path) -> str:
    """``path`` relative to ``root`` (symbolic links are not followed), else its file name."""
    try:
        return Path(os.path.abspath(path)).relative_to(os.path.abspath(root)).as_posix()
    except ValueError:
        return path.name


def load_clips(data: str | Path | list, *, config: DatasetConfig, character: str | Path | None = None) -> list[Clip]:
    """Load every clip ``data`` names, resampled to ``config.fps``. ``character``: the character file of its
    DeepMimic motion files (default: found as the formats find it, else the shipped humanoid3d).

    Body layouts: a mocap folder (with ``manifest.csv``: its clips of every format, rates, labels and
    trims, duplicates dropped per ``config.drop_duplicates``; without one: its ``*.bvh`` files), one
    motion file (``.bvh``, DeepMimic / exp-map ``.txt``, Motion ``.npz``, ...), or ``"procedural:multimodal"`` (:func:`multimodal_clips`). Face layout: one ``.csv`` / FaceMotion ``.npz`` capture
    or a folder of them. Clip names are paths relative to the folder (the file name for a single file). A list
    of mocap folders forms one corpus (:func:`motion2video.data.corpus.corpus_rows`: the clips of every folder
    after the first named with the folder's name in front).
    """
    if isinstance(data, (list, tuple)):
        if config.layout == "face":
            raise InputError("face captures come from one folder", data[0])
        for folder in data:
            if not Path(folder).is_dir():
                raise InputError("not a folder (several --data are mocap folders forming one corpus)", folder)
        return _corpus_clips(list(data), config=config, character=character)
    if str(data) == MULTIMODAL_SOURCE:
        return multimodal_clips(config)
    if character is not None and not Path(character).is_file():
        raise InputError("no such character file", character)
    path = Path(data)
    fps = config.fps
    if not path.exists():
        raise InputError("no such file or directory", path)
    if config.layout == "face":
        files = face_files(path)
        root = path if path.is_dir() else path.parent
        return [_face_clip_from_motion(load_face_clip(f), name=_relative_name(f, root), fps=fps,
                                       head_pose=config.face_head_pose) for f in files]
    if path.is_dir():
        return _corpus_clips([path], config=config, character=character)
    if path.suffix.lower() in (".csv",):
        raise InputError("this is a face capture, but the model is a body model", path)
    from motion2video.formats.io import load_motion

    motion = load_motion(path, character=character)
    if isinstance(motion, FaceMotion):
        raise InputError("this file holds face motion, but the model is a body model", path)
    return [_body_clip_from_motion(motion, name=path.name, fps=fps)]


def _corpus_clips(folders: list, *, config: DatasetConfig, character: str | Path | None) -> list[Clip]:
    """The clips of one or more mocap folders (:func:`motion2video.data.corpus.corpus_rows`) at ``config.fps``."""
    return [_body_clip_from_motion(load_mocap(path, manifest=row.entry or False, character=character,
                                              canonical=cached_canonical(path, entry=row.entry, character=character)),
                                   name=row.name, fps=config.fps, group=row.group,
                                   licence=row.entry.licence if row.entry is not None else None)
            for path, row in corpus_rows(folders, drop_duplicates=config.drop_duplicates)]


def multimodal_clips(config: DatasetConfig, *, count: int = MULTIMODAL_CLIPS) -> list[Clip]:
    """The known-answer multimodal benchmark (:mod:`motion2video.data.multimodal`) as ``count`` one-window
    clips named ``multimodal/<index>``, labelled with their context mode; drawn with seed
    ``config.split_seed``. Train with ``speed=0`` so every window is a whole clip."""
    if config.layout == "face":
        raise InputError("the multimodal benchmark is body motion; it has no face layout", MULTIMODAL_SOURCE)
    from motion2video.data.multimodal import MultimodalBenchmark

    bench = MultimodalBenchmark(observed_frames=config.observed, future_frames=config.future, fps=config.fps)
    batch = bench.sample(count, seed=config.split_seed)
    joints = np.concatenate([batch.observed, batch.future], axis=1).astype(np.float32)  # (n, L, 17, 3)
    return [Clip(name=f"multimodal/{i:05d}", data=joints[i], label=batch.context[i], group=f"multimodal/{i:05d}")
            for i in range(count)]


def extend_split(split: Split, clips: list[Clip], *, new_clips: str = "unseen_subjects") -> Split:
    """A recorded split (a checkpoint's) applied to ``clips``, which may hold clips it does not name (the
    checkpoint was trained on an older or smaller folder, or the clips are a user's file).

    A clip the split names keeps its split. One it does not name goes to test with ``new_clips="all"``;
    with ``"unseen_subjects"`` only when no clip of its group (subject) is in the recorded training or
    validation split (else it would be no held-out clip, and it is left out of all three lists), so a
    checkpoint trained on the first 72 clips evaluates on its own test clips plus the new clips of subjects
    it never saw; with ``"none"`` it is left out (how a checkpoint's own results were measured).
    """
    if new_clips not in ("all", "unseen_subjects", "none"):
        raise ValueError(f"new_clips must be 'all', 'unseen_subjects' or 'none', got {new_clips!r}")
    if new_clips == "none":
        return split
    known = set(split.train) | set(split.val) | set(split.test)
    seen_groups = {c.group for c in clips if c.name in set(split.train) | set(split.val)}
    unseen = tuple(c.name for c in clips if c.name not in known
                   and (new_clips == "all" or c.group not in seen_groups))
    return Split(split.train, split.val, split.test + unseen)


def build_dataset(data: str | Path, config: DatasetConfig, *, split: Split | None = None,
                  stats: W.NormStats | None = None, clips: list[Clip] | None = None,
                  recorded_only: bool = False, character: str | Path | None = None) -> MotionDataset:
    """Load ``data`` and prepare it for training or evaluation.

    Args:
        data: a BVH folder / motion file (body layouts) or face captures (face layout).
        config: the dataset config.
        split: a split to reuse (from a checkpoint); clips it does not name go to ``test``, from a folder
            only when they share no group with its training or validation clips (:func:`extend_split`).
        stats: normalisation statistics to reuse (from a checkpoint); computed on the training windows when
            None.
        clips: already loaded clips (skips loading ``data``; ``data`` is then only recorded).
        recorded_only: with ``split``, use only the clips it names (:func:`extend_split`).
        character: the character file of DeepMimic motion files (``--character``; default as the readers find it).
    Returns:
        The :class:`MotionDataset`.
    """
    if clips is None:
        clips = load_clips(data, config=config, character=character)
    if not clips:
        raise InputError("no clips to use", data)
    if split is None:
        split = make_split(clips, val_fraction=config.val_fraction, test_fraction=config.test_fraction,
                           seed=config.split_seed, pinned=config.held_out in ("corpus", "subjects"),
                           test_groups=SUBJECT_TEST_GROUPS if config.held_out == "subjects" else TEST_GROUPS)
    else:
        folders = isinstance(data, (list, tuple)) or Path(str(data)).is_dir()
        new_clips = "none" if recorded_only else "unseen_subjects" if folders else "all"
        split = extend_split(split, clips, new_clips=new_clips)
    if stats is None:
        train = [c for c in clips if c.name in set(split.train)]
        if not train:
            raise InputError("the training split is empty (need at least one training clip)", data)
        train_windows = clip_windows(train, config=config, stats=W.NormStats.identity(config.feature_layout.num_features),
                                     stride=config.stride)
        if len(train_windows) == 0:
            raise InputError(f"no training clip is long enough for a {config.length}-frame window", data)
        stats = W.compute_stats(train_windows.raw, min_std=config.min_std)
    summary = {
        "source": str(data),
        "fps": config.fps,
        "clips": len(clips),
        "frames": int(sum(c.num_frames for c in clips)),
        "per_split": {
            s: {"clips": len(split.names(s)),
                "frames": int(sum(c.num_frames for c in clips if c.name in set(split.names(s))))}
            for s in ("train", "val", "test")
        },
        "test_groups": sorted({c.group for c in clips if c.name in set(split.test)}),
        # what the training files allow (a model trained on non-commercial files says so when loaded)
        "licences": licence_record([c.licence for c in clips if c.name in set(split.train) | set(split.val)]),
        "val_groups": sorted({c.group for c in clips if c.name in set(split.val)}),
    }
    return MotionDataset(config=config, clips=list(clips), split=split, stats=stats, source=str(data),
                         summary=summary)
