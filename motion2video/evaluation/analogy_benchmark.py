"""The known-answer analogy (MT-VAE, Sec. 4.2): A -> B is a procedural clip in which mode X turns into mode Y
at B's first frame; C is another instance of X (another speed range and body height); the nearest-template
mode classifier of :mod:`motion2video.data.multimodal` labels D (:func:`known_answer_labels`).
:func:`procedural_transition_dataset` is the matching training data (the multimodal benchmark's context ->
future transitions).
"""

from __future__ import annotations

import numpy as np

from motion2video.models.checkpoint import ModelBundle
from motion2video.data.dataset import (
    MULTIMODAL_SOURCE,
    DatasetConfig,
    MotionDataset,
    build_dataset,
    multimodal_clips,
)
from motion2video.data.multimodal import MultimodalBenchmark, default_classifier
from motion2video.data.procedural import BodyParams, ModeSpec, generate
from motion2video.stages.latents import analogy_windows


def procedural_analogy_case(x: str, y: str, *, seed: int, fps: float = 25.0, observed: int = 16,
                            future: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """One known-answer analogy: A -> B where mode X turns into mode Y, and another instance C of mode X.

    A/B use speed in [0.85, 1.0] and body height in [1.55, 1.72] m; C uses speed in [1.0, 1.15] and height
    in [1.72, 1.9] m, with its own phase, so C is never the same instance.

    Returns:
        ab (observed + future, 17, 3) and c (observed, 17, 3) float32 world joints.
    """
    rng = np.random.default_rng(seed)
    s_ab, s_c = rng.uniform(0.85, 1.0), rng.uniform(1.0, 1.15)
    h_ab, h_c = rng.uniform(1.55, 1.72), rng.uniform(1.72, 1.9)
    obs_s, fut_s = observed / fps, future / fps
    ab = generate([ModeSpec(x, obs_s, speed=s_ab, phase=rng.uniform()),
                   ModeSpec(y, fut_s, speed=s_ab, phase=rng.uniform(0.0, 0.15))],
                  fps=fps, params=BodyParams(height=h_ab), variation=0.0).joints
    c = generate([ModeSpec(x, obs_s, speed=s_c, phase=rng.uniform())], fps=fps, params=BodyParams(height=h_c),
                 variation=0.0).joints
    return ab[:observed + future], c[:observed]


def procedural_transition_dataset(num_sequences: int, *, seed: int) -> MotionDataset:
    """Training data for the known-answer analogy: ``num_sequences`` sequences of the multimodal benchmark
    (:func:`motion2video.data.dataset.multimodal_clips`: a context mode, then a future mode from the first
    future frame; 16 + 48 frames at 25 fps) drawn and split with ``seed``, one window each, no speed
    augmentation (it would move the transition inside the window)."""
    config = DatasetConfig(observed=16, future=48, stride=64, speed=0.0, val_fraction=0.05, test_fraction=0.05,
                           split_seed=seed)
    return build_dataset(MULTIMODAL_SOURCE, config, clips=multimodal_clips(config, count=num_sequences))


def known_answer_labels(bundle: ModelBundle, x: str, y: str, *, seeds,
                        benchmark: MultimodalBenchmark = MultimodalBenchmark()) -> np.ndarray:
    """Mode-classifier labels of D for :func:`procedural_analogy_case` (X -> Y) at every seed: (len(seeds),) str."""
    cases = [procedural_analogy_case(x, y, seed=int(s), fps=benchmark.fps, observed=benchmark.observed_frames,
                                     future=benchmark.future_frames) for s in seeds]
    ab = np.stack([a for a, _ in cases])
    c = np.stack([c for _, c in cases])
    _, d, _, _ = analogy_windows(bundle, ab, c, observed=benchmark.observed_frames,
                                 horizon=benchmark.future_frames)
    return default_classifier(benchmark).predict(d)
