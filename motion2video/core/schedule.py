"""The learning-rate schedule of both training loops (motion models: :mod:`motion2video.models.training`; the frame
generator: :mod:`motion2video.generator.training`). Pure: no torch, no state."""

from __future__ import annotations

import math


def learning_rate(step: int, config) -> float:
    """Linear warm-up over ``config.warmup_steps``, then cosine decay from ``config.lr`` to
    ``config.lr * config.final_lr_fraction`` at ``config.steps``.

    Args:
        step: 0-based optimisation step.
        config: any settings object with ``steps``, ``warmup_steps``, ``lr`` and ``final_lr_fraction``
            (``TrainConfig`` and ``TrainFramesConfig`` use the same names).
    """
    if step < config.warmup_steps:
        return config.lr * (step + 1) / config.warmup_steps
    span = max(config.steps - config.warmup_steps, 1)
    progress = min((step - config.warmup_steps) / span, 1.0)
    low = config.lr * config.final_lr_fraction
    return low + 0.5 * (config.lr - low) * (1.0 + math.cos(math.pi * progress))
