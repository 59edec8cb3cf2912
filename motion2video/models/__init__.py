"""Learned motion models and baselines; importing this package registers every model by name.

See :mod:`motion2video.models.base` for the interface and :data:`MODEL_REGISTRY` / :func:`build_model`.
"""

from motion2video.models import (  # noqa: F401  (importing registers the models)
    baselines, behavior, blocks, cvae, dlow, flow, lcpvae, mixer, mtvae, pred_lstm,
)
from motion2video.models.base import MODEL_REGISTRY, LatentPosterior, LossOutput, build_model, register_model

__all__ = ["MODEL_REGISTRY", "LatentPosterior", "LossOutput", "build_model", "register_model"]
