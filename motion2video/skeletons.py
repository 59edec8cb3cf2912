"""Old import path, kept so existing code and checkpoints' callers work: everything lives in :mod:`motion2video.core.skeletons`."""

from motion2video.core.skeletons import *  # noqa: F401,F403
