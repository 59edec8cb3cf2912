"""A multimodal motion-prediction benchmark with a known answer, and a mode classifier to score it.

Each sequence shows ``observed_frames`` of one *context* mode (e.g. walking); its future is one of a few
modes with known probabilities (walk -> walk 0.4 / run 0.3 / turn 0.3). Body height, speed, amplitude,
cycle phase and left/right variant are random per sample, so the observed part alone cannot tell which
future comes (the future mode only starts fading in at the first future frame). A good stochastic
predictor's K samples should hit every valid future mode (coverage) and only valid ones (precision), in
roughly the right proportions.

The :class:`ModeClassifier` labels a future window by its nearest template: clean procedural instances of
each mode, compared on root-relative poses and root velocities, after dropping the cross-fade at the start
of the window and rotating the window to face -y at its first kept frame. Template clips longer than the
window give several phases per instance (time-alignment tolerance). A window far from every template is
labelled :data:`UNKNOWN`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Mapping, NamedTuple, Sequence

import numpy as np

from motion2video.core.rotations import heading_of
from motion2video.data.procedural import MODES, BodyParams, ModeSpec, generate
from motion2video.core.errors import InputError
from motion2video.core.skeletons import H36M_17

UNKNOWN = "unknown"

DEFAULT_FUTURES: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = (
    ("walk", (("walk", 0.4), ("run", 0.3), ("turn", 0.3))),
    ("stand", (("jump", 0.3), ("squat", 0.25), ("wave", 0.25), ("punch", 0.2))),
    ("run", (("run", 0.5), ("walk", 0.5))),
)


class BenchmarkBatch(NamedTuple):
    """Samples of the benchmark (unpacks as ``observed, future, context, future_mode``).

    Attributes:
        observed: (n, O, 17, 3) float32 world joints, metres.
        future: (n, F, 17, 3) float32, the frames right after ``observed``.
        context: n context mode names (the observed mode).
        future_mode: n future mode names.
    """

    observed: np.ndarray
    future: np.ndarray
    context: tuple[str, ...]
    future_mode: tuple[str, ...]


@dataclass(frozen=True)
class _Draw:
    """Everything random about one benchmark sequence."""

    context: str
    future: str
    body: BodyParams
    speed: float
    amplitude: float
    phase: float
    future_phase: float
    mirror: bool
    future_mirror: bool


@dataclass(frozen=True)
class MultimodalBenchmark:
    """Known-answer benchmark configuration and sampler.

    Attributes:
        observed_frames: O, frames of the context mode shown.
        future_frames: F, frames to predict.
        fps: frame rate.
        futures: per context mode, (future mode, probability) pairs; probabilities sum to 1.
        blend: seconds over which the future mode fades in, starting at the first future frame.
        height_range, speed_range, amplitude_range: uniform ranges of the per-sample body height (m),
            speed and amplitude.
        mirror: draw left/right variants at random (wave hand, turn direction, leading fist).
    """

    observed_frames: int = 16
    future_frames: int = 48
    fps: float = 25.0
    futures: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = DEFAULT_FUTURES
    blend: float = 0.4
    height_range: tuple[float, float] = (1.55, 1.9)
    speed_range: tuple[float, float] = (0.85, 1.15)
    amplitude_range: tuple[float, float] = (0.85, 1.15)
    mirror: bool = True

    def __post_init__(self) -> None:
        if self.observed_frames < 1 or self.future_frames < 2:
            raise InputError("observed_frames must be >= 1 and future_frames >= 2")
        for context, options in self.futures:
            for name in [context] + [m for m, _ in options]:
                if name not in MODES:
                    raise InputError(f"benchmark mode {name!r} is not a procedural mode ({', '.join(MODES)})")
            total = sum(p for _, p in options)
            if abs(total - 1.0) > 1e-6 or any(p <= 0 for _, p in options):
                raise InputError(f"future probabilities of context {context!r} must be positive and sum to 1")

    @property
    def contexts(self) -> tuple[str, ...]:
        return tuple(c for c, _ in self.futures)

    @property
    def future_modes(self) -> tuple[str, ...]:
        """Every mode some context can lead to, in first-seen order."""
        seen: dict[str, None] = {}
        for _, options in self.futures:
            for m, _ in options:
                seen[m] = None
        return tuple(seen)

    @property
    def blend_frames(self) -> int:
        """Frames at the start of a future during which the modes cross-fade."""
        return int(np.ceil(self.blend * self.fps))

    def valid_modes(self, context: str) -> dict[str, float]:
        """The future modes of ``context`` and their probabilities."""
        for c, options in self.futures:
            if c == context:
                return dict(options)
        raise InputError(f"unknown benchmark context {context!r}; known: {', '.join(self.contexts)}")

    # --- sampling -------------------------------------------------------------------------------------

    def _draw(self, rng: np.random.Generator, *, context: str | None = None) -> _Draw:
        if context is None:
            context = self.contexts[int(rng.integers(len(self.contexts)))]
        options = self.valid_modes(context)
        names = list(options)
        future = names[int(rng.choice(len(names), p=np.array([options[n] for n in names])))]
        return _Draw(
            context=context,
            future=future,
            body=BodyParams(height=float(rng.uniform(*self.height_range))),
            speed=float(rng.uniform(*self.speed_range)),
            amplitude=float(rng.uniform(*self.amplitude_range)),
            phase=float(rng.uniform()),
            future_phase=float(rng.uniform(0.0, 0.15)),  # actions start near their beginning (a jump crouches)
            mirror=bool(self.mirror and rng.uniform() < 0.5),
            future_mirror=bool(self.mirror and rng.uniform() < 0.5),
        )

    def _render(self, draw: _Draw, future: str) -> np.ndarray:
        """(O + F, 17, 3) joints of ``draw``'s context followed by ``future``."""
        obs_s = self.observed_frames / self.fps
        fut_s = self.future_frames / self.fps
        common = dict(speed=draw.speed, amplitude=draw.amplitude)
        if future == draw.context:  # the same mode simply goes on
            specs = [ModeSpec(draw.context, obs_s + fut_s, phase=draw.phase, mirror=draw.mirror, **common)]
        else:
            specs = [ModeSpec(draw.context, obs_s, phase=draw.phase, mirror=draw.mirror, **common),
                     ModeSpec(future, fut_s, phase=draw.future_phase, mirror=draw.future_mirror, **common)]
        joints = generate(specs, fps=self.fps, params=draw.body, blend=self.blend, variation=0.0).joints
        expected = self.observed_frames + self.future_frames
        if joints.shape[0] != expected:  # pragma: no cover - frame counts are whole numbers of frames
            raise RuntimeError(f"generated {joints.shape[0]} frames, expected {expected}")
        return joints

    def sample(self, n: int, seed: int) -> BenchmarkBatch:
        """``n`` sequences; the same seed gives the same batch.

        Returns:
            BenchmarkBatch: observed (n, O, 17, 3), future (n, F, 17, 3), context names, future mode names.
        """
        if n < 1:
            raise InputError(f"number of samples must be >= 1, got {n}")
        rng = np.random.default_rng(seed)
        draws = [self._draw(rng) for _ in range(n)]
        clips = np.stack([self._render(d, d.future) for d in draws])  # (n, O+F, 17, 3)
        O = self.observed_frames
        return BenchmarkBatch(clips[:, :O], clips[:, O:], tuple(d.context for d in draws),
                              tuple(d.future for d in draws))

    def oracle_futures(self, n: int, seed: int, *, k: int, future_seed: int = 0) -> np.ndarray:
        """K futures drawn from the TRUE distribution for each sequence of ``sample(n, seed)``.

        The same body, speed and phase continue into modes drawn from :meth:`valid_modes`: an upper-bound
        predictor whose coverage and precision are ~1.

        Returns:
            (n, k, F, 17, 3) float32.
        """
        rng = np.random.default_rng(seed)
        draws = [self._draw(rng) for _ in range(n)]
        frng = np.random.default_rng(future_seed)
        out = np.empty((n, k, self.future_frames, H36M_17.num_joints, 3), dtype=np.float32)
        for i, d in enumerate(draws):
            options = self.valid_modes(d.context)
            names = list(options)
            probs = np.array([options[m] for m in names])
            for j in range(k):
                mode = names[int(frng.choice(len(names), p=probs))]
                alt = _Draw(d.context, mode, d.body, d.speed, d.amplitude, d.phase,
                            float(frng.uniform(0.0, 0.15)), d.mirror, bool(self.mirror and frng.uniform() < 0.5))
                out[i, j] = self._render(alt, mode)[self.observed_frames:]
        return out

    def templates(self, modes: Sequence[str] = MODES, *, per_mode: int, seed: int,
                  extra_frames: int = 0) -> dict[str, np.ndarray]:
        """Clean instances of each mode alone, with random body, speed, amplitude, phase and mirror.

        Args:
            modes: which modes.
            per_mode: instances per mode.
            seed: the same seed gives the same instances.
            extra_frames: frames beyond ``future_frames`` per instance (for sliding-window phases).
        Returns:
            mode -> (per_mode, F + extra_frames, 17, 3) float32.
        """
        rng = np.random.default_rng(seed)
        frames = self.future_frames + extra_frames
        out = {}
        for mode in modes:
            clips = []
            for _ in range(per_mode):
                d = self._draw(rng, context=self.contexts[0])
                spec = ModeSpec(mode, frames / self.fps, speed=d.speed, amplitude=d.amplitude, phase=d.phase,
                                mirror=d.mirror)
                clips.append(generate([spec], fps=self.fps, params=d.body, variation=0.0).joints[:frames])
            out[mode] = np.stack(clips)
        return out


# --- features and classifier ----------------------------------------------------------------------------

def mode_features(joints: np.ndarray, *, skip: int, fps: float, span: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Pose and root-velocity features of future windows, invariant to position, heading and body size.

    The first ``skip`` frames are dropped; the rest is rotated about z so that the first kept frame faces
    -y, and measured in units of the window's mean bone length (about 0.2 m for a 1.7 m body).

    Args:
        joints: (n, F, 17, 3) world joints, metres.
        skip: frames to drop at the start.
        fps: frame rate, for velocities per second.
        span: frames over which each root velocity is measured (averages out per-frame jitter).
    Returns:
        pose (n, F - skip, 51): root-relative joints in bone units; velocity (n, F - skip - span, 3): root
        velocity in bone units per second.
    """
    x = np.asarray(joints, dtype=np.float64)[:, skip:]  # (n, F', 17, 3)
    if x.shape[1] <= span:
        raise InputError(f"future windows need more than {skip} + {span} frames, got {joints.shape[1]}")
    n, F = x.shape[:2]
    angle = heading_of(x[:, 0])  # (n,)
    c, s = np.cos(-angle), np.sin(-angle)
    rot = np.zeros((n, 3, 3))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 1, 0], rot[:, 1, 1], rot[:, 2, 2] = c, -s, s, c, 1.0
    x = np.einsum("nij,ntkj->ntki", rot, x)  # (n, F', 17, 3) facing -y at the first kept frame
    bones = np.array(H36M_17.bones)  # (16, 2)
    scale = np.linalg.norm(x[:, :, bones[:, 1]] - x[:, :, bones[:, 0]], axis=-1).mean(axis=(1, 2))  # (n,)
    scale = np.maximum(scale, 1e-6)[:, None, None]
    root = x[:, :, 0]  # (n, F', 3)
    pose = (x - root[:, :, None]).reshape(n, F, -1) / scale  # (n, F', 51)
    velocity = (root[:, span:] - root[:, :-span]) * (fps / span) / scale  # (n, F' - span, 3)
    return pose, velocity


@dataclass(frozen=True)
class ClassifierConfig:
    """Mode classifier settings.

    The distance between two windows is ``mean((pose_a - pose_b)^2) + velocity_weight *
    mean((vel_a - vel_b)^2)`` with the units of :func:`mode_features` (bone lengths, per second).

    Attributes:
        skip_frames: frames dropped at the start of each window (the cross-fade from the context mode).
        window_stride: stride of the sliding windows cut from template clips longer than the window.
        velocity_span: frames per root-velocity measurement.
        velocity_weight: weight of the velocity term (a 1 m/s speed difference is ~25 squared bone
            units per second).
        reject_factor, reject_gap, reject_floor: a window whose nearest template has mode m is labelled
            :data:`UNKNOWN` when its distance exceeds all of: ``reject_factor`` times m's spread (the
            largest distance from one of m's templates to the nearest template of another instance of m),
            ``reject_gap`` times m's gap (the median distance from m's templates to the nearest template of
            another mode) and ``reject_floor`` (about the distance that 2 cm of joint jitter adds).
            ``reject_factor=None`` never rejects.
    """

    skip_frames: int = 10
    window_stride: int = 4
    velocity_span: int = 4
    velocity_weight: float = 0.05
    reject_factor: float | None = 3.0
    reject_gap: float = 0.5
    reject_floor: float = 0.05


@dataclass
class ModeClassifier:
    """Nearest-template motion-mode classifier (build it with :meth:`fit`).

    Attributes:
        config: settings.
        window: window length in frames the classifier expects.
        fps: frame rate of the windows.
        labels: (M,) mode name per template window.
        features: (M, D) template features, scaled so that squared Euclidean distance is the configured
            distance.
        thresholds: (M,) rejection distance per template (its mode's; inf when rejection is off).
    """

    config: ClassifierConfig
    window: int
    fps: float
    labels: np.ndarray
    features: np.ndarray
    thresholds: np.ndarray

    @classmethod
    def fit(cls, templates: Mapping[str, np.ndarray], *, window: int = 48, fps: float = 25.0,
            config: ClassifierConfig = ClassifierConfig()) -> "ModeClassifier":
        """Build the template bank.

        Args:
            templates: mode -> (n, T, 17, 3) clean clips with T >= ``window``; clips longer than the
                window contribute windows every ``config.window_stride`` frames (several phases).
            window: the length of the windows to classify (the benchmark's future_frames).
            fps: their frame rate.
            config: settings.
        """
        if not templates:
            raise InputError("no templates to fit the mode classifier")
        windows, labels, instances = [], [], []
        for mode, clips in templates.items():
            clips = np.asarray(clips)
            if clips.ndim != 4 or clips.shape[1] < window:
                raise InputError(f"templates of {mode!r} must be (n, T >= {window}, 17, 3), got {clips.shape}")
            for start in range(0, clips.shape[1] - window + 1, config.window_stride):
                windows.append(clips[:, start:start + window])
                labels += [mode] * clips.shape[0]
                instances += [f"{mode}/{i}" for i in range(clips.shape[0])]
        feats = _features(np.concatenate(windows), fps=fps, config=config)
        labels_arr = np.array(labels)
        thresholds = np.full(len(labels), np.inf)
        if config.reject_factor is not None:
            inst = np.array(instances)
            d = _sq_distances(feats, feats)  # (M, M)
            same_mode = labels_arr[:, None] == labels_arr[None, :]
            loo = np.where(same_mode & (inst[:, None] != inst[None, :]), d, np.inf).min(axis=1)  # (M,)
            other = np.where(same_mode, np.inf, d).min(axis=1)  # (M,) nearest template of another mode
            for mode in set(labels):
                rows = labels_arr == mode
                if not np.all(np.isfinite(loo[rows])):
                    raise InputError(f"mode {mode!r} needs templates from at least 2 instances to set its "
                                     "rejection distance (or use reject_factor=None)")
                limit = max(config.reject_factor * float(loo[rows].max()), config.reject_floor)
                if np.any(np.isfinite(other[rows])):
                    limit = max(limit, config.reject_gap * float(np.median(other[rows])))
                thresholds[rows] = limit
        return cls(config, int(window), float(fps), labels_arr, feats, thresholds)

    def distances(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nearest-template label (n,) and distance (n,) of each (n, window, 17, 3) window."""
        index, dist = self._nearest(joints)
        return self.labels[index], dist

    def predict(self, joints: np.ndarray) -> np.ndarray:
        """(n, window, 17, 3) -> (n,) mode names, :data:`UNKNOWN` where no template is close enough."""
        index, dist = self._nearest(joints)
        return np.where(dist > self.thresholds[index], UNKNOWN, self.labels[index])

    def _nearest(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        joints = np.asarray(joints)
        if joints.ndim != 4 or joints.shape[1] != self.window:
            raise InputError(f"mode classifier expects (n, {self.window}, 17, 3) windows, got {joints.shape}")
        feats = _features(joints, fps=self.fps, config=self.config)
        best_d = np.empty(feats.shape[0])
        best_i = np.empty(feats.shape[0], dtype=int)
        for start in range(0, feats.shape[0], 256):  # chunks keep the distance matrix small
            d = _sq_distances(feats[start:start + 256], self.features)  # (c, M)
            best_i[start:start + 256] = d.argmin(axis=1)
            best_d[start:start + 256] = d.min(axis=1)
        return best_i, best_d


def _features(joints: np.ndarray, *, fps: float, config: ClassifierConfig) -> np.ndarray:
    """(n, F, 17, 3) -> (n, D) rows whose squared Euclidean distance is the classifier's distance."""
    pose, vel = mode_features(joints, skip=config.skip_frames, fps=fps, span=config.velocity_span)
    n = pose.shape[0]
    p = pose.reshape(n, -1) / np.sqrt(pose[0].size)  # sum of squares = mean over pose numbers
    v = vel.reshape(n, -1) * np.sqrt(config.velocity_weight / vel[0].size)
    return np.concatenate([p, v], axis=1)


def _sq_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(na, D), (nb, D) -> (na, nb) squared Euclidean distances."""
    d = (a * a).sum(1)[:, None] + (b * b).sum(1)[None, :] - 2.0 * a @ b.T
    return np.maximum(d, 0.0)


def fit_default_classifier(benchmark: MultimodalBenchmark, *, per_mode: int = 12, seed: int = 12345,
                           config: ClassifierConfig = ClassifierConfig()) -> ModeClassifier:
    """A classifier over every procedural mode, from ``per_mode`` clean instances with one extra second
    of frames each (sliding windows give the phase tolerance). About a second on one CPU core."""
    templates = benchmark.templates(MODES, per_mode=per_mode, seed=seed, extra_frames=int(benchmark.fps))
    return ModeClassifier.fit(templates, window=benchmark.future_frames, fps=benchmark.fps, config=config)


@lru_cache(maxsize=4)
def default_classifier(benchmark: MultimodalBenchmark = MultimodalBenchmark()) -> ModeClassifier:
    """:func:`fit_default_classifier` with its defaults, built once per benchmark configuration."""
    return fit_default_classifier(benchmark)


# --- scores ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class MultimodalScores:
    """Scores of K sampled futures per sequence.

    Attributes:
        coverage: mean over sequences of the share of valid future modes hit by at least one sample.
        precision: share of samples whose mode is valid for their context.
        distribution_tv: mean over contexts of the total-variation distance between the sampled mode
            frequencies (invalid and unknown pooled) and the true probabilities; 0 is perfect, 1 worst.
        labels: (n, K) the classifier's mode name per sample.
    """

    coverage: float
    precision: float
    distribution_tv: float
    labels: np.ndarray


def coverage_from_labels(labels: np.ndarray, contexts: Sequence[str], benchmark: MultimodalBenchmark) -> float:
    """Mean share of each sequence's valid modes that appear among its K labels. labels: (n, K)."""
    shares = []
    for row, context in zip(np.asarray(labels), contexts):
        valid = benchmark.valid_modes(context)
        shares.append(len(valid.keys() & set(row.tolist())) / len(valid))
    return float(np.mean(shares))


def precision_from_labels(labels: np.ndarray, contexts: Sequence[str], benchmark: MultimodalBenchmark) -> float:
    """Share of all labels that are valid modes of their sequence's context. labels: (n, K)."""
    hits = [np.isin(row, list(benchmark.valid_modes(c))) for row, c in zip(np.asarray(labels), contexts)]
    return float(np.mean(np.stack(hits)))


def distribution_tv_from_labels(labels: np.ndarray, contexts: Sequence[str],
                                benchmark: MultimodalBenchmark) -> float:
    """Mean over contexts of the total variation between label frequencies and true probabilities."""
    labels = np.asarray(labels)
    contexts = np.asarray(contexts)
    tvs = []
    for context in dict.fromkeys(contexts.tolist()):
        rows = labels[contexts == context].ravel()
        valid = benchmark.valid_modes(context)
        freq = {m: float(np.mean(rows == m)) for m in valid}
        other = 1.0 - sum(freq.values())
        tvs.append(0.5 * (sum(abs(freq[m] - p) for m, p in valid.items()) + other))
    return float(np.mean(tvs))


def score_futures(samples: np.ndarray, contexts: Sequence[str], *, classifier: ModeClassifier | None = None,
                  benchmark: MultimodalBenchmark = MultimodalBenchmark()) -> MultimodalScores:
    """Classify K futures per sequence and score them.

    Args:
        samples: (n, K, F, 17, 3) sampled futures in world coordinates.
        contexts: n context names (``BenchmarkBatch.context``).
        classifier: a fitted :class:`ModeClassifier` with window F; None uses :func:`default_classifier`.
        benchmark: gives the valid modes of each context.
    """
    if classifier is None:
        classifier = default_classifier(benchmark)
    samples = np.asarray(samples)
    if samples.ndim != 5 or samples.shape[2] != classifier.window:
        raise InputError(f"samples must be (n, K, {classifier.window}, 17, 3), got {samples.shape}")
    if samples.shape[0] != len(contexts):
        raise InputError(f"{samples.shape[0]} sample groups but {len(contexts)} contexts")
    n, K = samples.shape[:2]
    labels = classifier.predict(samples.reshape((n * K,) + samples.shape[2:])).reshape(n, K)
    return MultimodalScores(
        coverage=coverage_from_labels(labels, contexts, benchmark),
        precision=precision_from_labels(labels, contexts, benchmark),
        distribution_tv=distribution_tv_from_labels(labels, contexts, benchmark),
        labels=labels,
    )


def mode_coverage(samples: np.ndarray, contexts: Sequence[str], *, classifier: ModeClassifier | None = None,
                  benchmark: MultimodalBenchmark = MultimodalBenchmark()) -> float:
    """Share of the valid future modes hit by at least one of K samples, averaged over sequences.
    samples: (n, K, F, 17, 3)."""
    return score_futures(samples, contexts, classifier=classifier, benchmark=benchmark).coverage


def mode_precision(samples: np.ndarray, contexts: Sequence[str], *, classifier: ModeClassifier | None = None,
                   benchmark: MultimodalBenchmark = MultimodalBenchmark()) -> float:
    """Share of samples whose mode is valid for their context. samples: (n, K, F, 17, 3)."""
    return score_futures(samples, contexts, classifier=classifier, benchmark=benchmark).precision
