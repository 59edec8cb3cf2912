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
