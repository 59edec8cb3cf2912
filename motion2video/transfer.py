"""Old import path of behaviour transfer, kept for existing callers: the code lives in :mod:`motion2video.apps.transfer`, its protocol in :mod:`motion2video.evaluation.transfer`, the shared parts in :mod:`motion2video.stages`."""

from motion2video.apps.transfer import *  # noqa: F401,F403
from motion2video.evaluation.transfer import *  # noqa: F401,F403
from motion2video.stages.clips import LoadedClip, load_clip, model_frame  # noqa: F401
from motion2video.stages.latents import (  # noqa: F401
    behavior_latents,
    behavior_model,
    decode_sequences,
    encode_sequences,
    reenact,
)
from motion2video.stages.structure import (  # noqa: F401
    ALT_FACE_COLOURS,
    ALT_FACE_IDENTITY,
    SOURCE_LOOK,
    TARGET_LOOK,
    body_style,
    iter_sequence,
    render_sequence,
)
from motion2video.stages.video import iter_mark_segments, mark_segments  # noqa: F401
