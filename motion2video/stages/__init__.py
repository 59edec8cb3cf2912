"""The stages every application composes, each in one place.

- :mod:`~motion2video.stages.clips`: load a user's clip for a model (one loader per input kind);
- :mod:`~motion2video.stages.sampling`: sample K futures of an observed clip;
- :mod:`~motion2video.stages.structure`: draw structure (one ``renderer_for(layout, style)`` table);
- :mod:`~motion2video.stages.generation`: generate frames with the keypoint-conditioned frame generator;
- :mod:`~motion2video.stages.reference`: the reference appearance image and its pose;
- writing video is :mod:`motion2video.formats.video`.

Stages import the core, the renderers, the models and the frame generator; never an application.
"""
