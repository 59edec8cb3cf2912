"""The small protocol every renderer follows."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Renderer(Protocol):
    """Turns a motion (or a batch of structures) into RGB frames.

    ``render`` returns a (T, H, W, 3) uint8 array. ``close`` frees any GL context; renderers are context
    managers so ``with SkeletonRenderer(...) as r:`` releases them.
    """

    def render(self, *args, **kwargs) -> np.ndarray: ...

    def close(self) -> None: ...

    def __enter__(self): ...

    def __exit__(self, *exc) -> None: ...


class RendererBase:
    """Context-manager plumbing shared by the concrete renderers."""

    def close(self) -> None:  # pragma: no cover - overridden where there is something to free
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
