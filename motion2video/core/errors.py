"""The one exception type the CLI turns into a one-line message and exit code 2.

Raise :class:`InputError` for anything a user can fix (a missing file, a malformed clip, a bad option);
let programming errors propagate as ordinary exceptions so they keep their traceback.
"""

from __future__ import annotations

from pathlib import Path


class InputError(ValueError):
    """Bad user input. ``str(err)`` is a single line naming the file (when there is one) and the problem."""

    def __init__(self, problem: str, path: str | Path | None = None) -> None:
        self.path = None if path is None else str(path)
        self.problem = " ".join(str(problem).split())  # always one line
        super().__init__(f"{self.path}: {self.problem}" if self.path else self.problem)


CHECKPOINT_FORMAT_VERSION = 1  # the safetensors metadata layout this motion2video writes and reads


def check_format_version(metadata: dict, path: str | Path, *, supported: int = CHECKPOINT_FORMAT_VERSION) -> int:
    """The checkpoint format version recorded in safetensors ``metadata`` (``format_version``; files written
    before it existed are version 1). InputError naming ``path`` when it is not a number or is newer than
    ``supported`` (a file from a future motion2video)."""
    raw = metadata.get("format_version", "1")
    try:
        version = int(raw)
    except (TypeError, ValueError):
        raise InputError(f"damaged checkpoint metadata: format_version {raw!r} is not a number", path) from None
    if version > supported:
        raise InputError(f"checkpoint format version {version} is newer than this motion2video reads (up to "
                         f"{supported}): it was written by a later version; upgrade motion2video", path)
    if version < 1:
        raise InputError(f"damaged checkpoint metadata: format_version {version}", path)
    return version
