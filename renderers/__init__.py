"""Motion -> pictures. No learning code here.

Every renderer follows :class:`renderers.base.Renderer`: ``render(...) -> (T, H, W, 3) uint8``, ``close()``,
and use as a context manager. All of them project with :mod:`motion2video.core.camera`.
"""
