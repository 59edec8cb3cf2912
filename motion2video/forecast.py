"""Old import path of the ``sample`` application, kept for existing callers: the code lives in :mod:`motion2video.apps.sample`."""

from motion2video.apps.sample import *  # noqa: F401,F403
