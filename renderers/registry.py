"""Which renderer draws which layout in which style, decided in one table (the structure stage,
:mod:`motion2video.stages.structure`, and the frame generator's training data both use it).

:data:`RENDERERS` maps (layout, style) to a factory; :func:`renderer_for` builds the renderer and wraps it in a
:class:`StructureRenderer`, whose :meth:`~StructureRenderer.draw` hands it a sequence the way it takes one
(joint arrays for skeletons and heatmaps, a :class:`~motion2video.core.motion.Motion` for the Anny body, a
:class:`~motion2video.core.motion.FaceMotion` for the Anny face). Where the person stands in the picture (the
camera or 2D framing) is the caller's: each application frames its cells its own way.

Layouts: ``body3d`` (T, 17, 3) world metres, ``body2d`` (T, 17, 2) pixels, ``face`` (T, 58) parameters.
Styles: ``skeleton`` and ``heatmap`` (bodies), ``mesh`` (3D bodies), ``face`` and ``structure`` (faces: the
shaded Anny face, or its grey structure render on black, the frame generator's face input). Face models are
always drawn with the Anny face: ``skeleton`` and ``mesh`` mean ``face`` for them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np

from motion2video.core.camera import ImageFraming
from motion2video.core.errors import InputError
from motion2video.core.motion import FaceMotion, Motion

LAYOUTS = ("body3d", "body2d", "face")
STYLES = ("skeleton", "heatmap", "mesh", "face", "structure")
# Places the framing of already placed 2D points: out = in (pixels stay where they are).
PIXELS = ImageFraming(1.0, (0.0, 0.0))
CHUNK = 32  # frames per drawn chunk of skeletons and heatmaps when streaming


def _skeleton(size: int, **options):
    from renderers.skeleton import SkeletonRenderer, SkeletonStyle

    return SkeletonRenderer(style=SkeletonStyle(size=(size, size), **options))


def _heatmap(size: int, **options):
    from renderers.skeleton import HeatmapRenderer, HeatmapStyle

    return HeatmapRenderer(style=HeatmapStyle(size=(size, size), **options))


def _body_mesh(size: int, **options):
    from renderers.body import BodyRenderer, BodyStyle

    return BodyRenderer(BodyStyle(size=(size, size), **options))


def _face(size: int, **options):
    from renderers.face import FaceRenderer, FaceStyle

    return FaceRenderer(FaceStyle(size=(size, size), **options))


def _face_structure(size: int, **options):
    from renderers.face import FaceRenderer, FaceStyle

    return FaceRenderer(FaceStyle(size=(size, size), **{"style": "structure", "background": (0, 0, 0), **options}))


# The one renderer dispatch: (layout, style) -> factory(size, **style fields) -> renderer.
RENDERERS: dict[tuple[str, str], Callable] = {
    ("body3d", "skeleton"): _skeleton,
    ("body2d", "skeleton"): _skeleton,
    ("body3d", "heatmap"): _heatmap,
    ("body2d", "heatmap"): _heatmap,
    ("body3d", "mesh"): _body_mesh,
    ("face", "face"): _face,
    ("face", "structure"): _face_structure,
    ("face", "skeleton"): _face,
    ("face", "mesh"): _face,
}


def layout_of(motion: Motion | FaceMotion) -> str:
    """The layout of a loaded motion: ``face``, ``body3d`` or ``body2d``."""
    if isinstance(motion, FaceMotion):
        return "face"
    return "body3d" if motion.dim == 3 else "body2d"


@dataclass
class StructureRenderer:
    """A renderer with the layout and style it draws (a context manager, like the renderers).

    Attributes:
        layout, style: the table key it was built for.
        renderer: the :mod:`renderers` object (for its own methods: ``camera_for``, ``render_with_masks``).
    """

    layout: str
    style: str
    renderer: object

    def as_input(self, seq, fps: float, identity: dict | None = None):
        """(T, ...) array -> what the renderer takes; Motion and FaceMotion objects pass through."""
        if isinstance(seq, (Motion, FaceMotion)):
            return seq
        if self.layout == "face":
            return FaceMotion(seq, fps, dict(identity or {}))
        if self.style == "mesh":
            return Motion(seq, fps)
        return seq

    def draw(self, seq, fps: float = 25.0, *, identity: dict | None = None, **placement) -> np.ndarray:
        """Draw a sequence: (T, 17, D) joints, (T, 58) face parameters, or a Motion / FaceMotion.

        Args:
            fps: the sequence's rate (meshes and faces).
            identity: the face's Anny identity (face layouts).
            placement: ``camera=`` / ``framing=`` / ``skeleton=`` / ``progress=`` as the renderer takes them.
        Returns:
            (T, H, W, 3) uint8.
        """
        return self.renderer.render(self.as_input(seq, fps, identity), **placement)

    def iter_draw(self, seq, fps: float = 25.0, *, identity: dict | None = None, chunk: int = CHUNK,
                  **placement) -> Iterator[np.ndarray]:
        """:meth:`draw` as a stream of (t, H, W, 3) uint8 chunks, only one chunk in memory at a time.

        Skeletons and heatmaps are drawn ``chunk`` frames at a time; the Anny body and face stream through
        their renderer's ``iter_frames`` (its batch size), fitting the camera over the whole sequence first
        when none is given, so the frames equal :meth:`draw`'s. ``progress=`` is not taken here: the caller
        counts the chunks it consumes.
        """
        item = self.as_input(seq, fps, identity)
        if isinstance(item, (Motion, FaceMotion)):
            yield from self.renderer.iter_frames(item, camera=placement.get("camera"))
            return
        for start in range(0, len(item), chunk):
            yield self.renderer.render(item[start:start + chunk], **placement)

    def close(self) -> None:
        self.renderer.close()

    def __enter__(self) -> "StructureRenderer":
        self.renderer.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        self.renderer.__exit__(*exc)


def check_style(layout: str, style: str) -> None:
    """InputError when ``style`` cannot draw ``layout`` (the one place this is decided)."""
    if layout not in LAYOUTS:
        raise ValueError(f"unknown layout {layout!r}; one of {', '.join(LAYOUTS)}")
    if (layout, style) in RENDERERS:
        return
    if style == "mesh" and layout == "body2d":
        raise InputError("--style mesh needs a 3D body model; this model predicts 2D keypoints")
    choices = sorted({s for (lay, s) in RENDERERS if lay == layout})
    raise InputError(f"unknown style {style!r} for {layout} motion; choose one of {', '.join(choices)}")


def renderer_for(layout: str, style: str, *, size: int, **options) -> StructureRenderer:
    """The renderer that draws ``layout`` in ``style`` at ``size`` x ``size`` pixels.

    Args:
        options: fields of the renderer's style dataclass (palette, phenotype, colours, azimuth_deg, ...).
    Raises:
        InputError: the style cannot draw the layout.
    """
    check_style(layout, style)
    return StructureRenderer(layout, style, RENDERERS[(layout, style)](int(size), **options))
