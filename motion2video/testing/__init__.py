"""Golden-frame testing for projects that render motion: ``from motion2video.testing import assert_frames_match``
(defined in :mod:`~motion2video.testing.golden`, with the metrics and the synthetic test motions); the pytest
fixture ``golden_frames`` is :mod:`motion2video.testing.pytest_plugin`."""

from __future__ import annotations

import importlib

# public name -> the module that defines it (loaded on first use, as the package's own names are)
_PUBLIC = {"assert_frames_match": "motion2video.testing.golden"}

__all__ = list(_PUBLIC)


def __getattr__(name: str):
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'motion2video.testing' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
