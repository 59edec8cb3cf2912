"""Old import path, kept so existing code and checkpoints' callers work: everything lives in :mod:`motion2video.core.camera`."""

from motion2video.core.camera import *  # noqa: F401,F403
