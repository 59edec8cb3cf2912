"""Old import path, kept so existing code and checkpoints' callers work: everything lives in :mod:`motion2video.core.atomic`."""

from motion2video.core.atomic import *  # noqa: F401,F403
