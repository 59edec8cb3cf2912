"""motion2video: human motion in, video out.

The public API, importable from here::

    from motion2video import load_model, sample, synthesize, transfer, analogy, estimate_pose
    from motion2video import load_motion, save_motion, render_motion, iter_frames, write_video, read_video
    from motion2video import Motion, FaceMotion, InputError

The pipeline: ``load_model``, ``sample`` (K futures of a clip), ``synthesize`` (futures as video of a photo's
person), ``transfer`` (behaviour transfer), ``analogy`` (A : B :: C : D) and ``estimate_pose`` (a person in a photo
or video), with their typed results ``Futures``, ``Synthesis``, ``Transfer``, ``Analogy`` and ``Pose``, are in
:mod:`motion2video.apps.api`. Each name is the one defined in its layer (see docs/architecture.md):
``load_motion`` / ``save_motion`` in
:mod:`motion2video.formats.io`, ``render_motion`` / ``iter_frames`` in :mod:`motion2video.apps.render`,
``write_video`` in :mod:`motion2video.formats.video`, ``Motion`` / ``FaceMotion`` in :mod:`motion2video.core.motion`,
``InputError`` in :mod:`motion2video.core.errors`. They load on first use, so ``import motion2video`` stays cheap
(no OpenCV, no renderer, no torch).
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

# public name -> the module that defines it
_PUBLIC = {
    "load_model": "motion2video.apps.api",
    "sample": "motion2video.apps.api",
    "synthesize": "motion2video.apps.api",
    "transfer": "motion2video.apps.api",
    "analogy": "motion2video.apps.api",
    "estimate_pose": "motion2video.apps.api",
    "Futures": "motion2video.apps.api",
    "Synthesis": "motion2video.apps.api",
    "Transfer": "motion2video.apps.api",
    "Analogy": "motion2video.apps.api",
    "Pose": "motion2video.apps.api",
    "load_motion": "motion2video.formats.io",
    "save_motion": "motion2video.formats.io",
    "render_motion": "motion2video.apps.render",
    "iter_frames": "motion2video.apps.render",
    "write_video": "motion2video.formats.video",
    "read_video": "motion2video.formats.video",
    "Motion": "motion2video.core.motion",
    "FaceMotion": "motion2video.core.motion",
    "InputError": "motion2video.core.errors",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str):
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'motion2video' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
