"""Learned motion models and baselines; importing this package registers every model by name.

See :mod:`motion2video.models.base` for the interface, ``MODEL_REGISTRY`` and ``build_model``.
"""

from motion2video.models import (  # noqa: F401  (importing registers the models)
    baselines, behavior, blocks, cvae, dlow, flow, lcpvae, mixer, mixer_cvae, mixture, mtvae, periodic, pred_lstm,
    settle,
)
