"""Old import path, kept so existing code works: everything lives in :mod:`motion2video.formats.io`."""

from motion2video.formats.io import *  # noqa: F401,F403
