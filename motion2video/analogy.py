"""Old import path of the MT-VAE analogy, kept for existing callers: the code lives in :mod:`motion2video.apps.analogy`, its known-answer protocol in :mod:`motion2video.evaluation.analogy`, the latent operations in :mod:`motion2video.stages.latents`."""

from motion2video.apps.analogy import *  # noqa: F401,F403
from motion2video.evaluation.analogy import *  # noqa: F401,F403
from motion2video.stages.latents import analogy_model, analogy_windows, stitch_after  # noqa: F401
