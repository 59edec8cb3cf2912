"""Old import path of the ``synthesize`` application, kept for existing callers: the code lives in :mod:`motion2video.apps.synthesize` and the stages it composes."""

from motion2video.apps.synthesize import *  # noqa: F401,F403
