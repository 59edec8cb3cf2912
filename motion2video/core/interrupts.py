"""Ctrl-C and SIGTERM that a finaliser swallowed, kept until they are delivered.

Python raises the KeyboardInterrupt of a signal at whatever line runs next. When that line is inside a finaliser
(``__del__``, e.g. OpenGL freeing a buffer), Python prints the exception and drops it, and the command would run
on to the end. The CLI (:mod:`motion2video.cli`) records such an interrupt here (:func:`note_swallowed`) and sends
the signal again; long loops also call :func:`raise_pending` at safe points (every chunk a video writer encodes),
so the interrupt stops the command even if the signal sent again is itself swallowed.

The state is one class, or None: the interrupt that was swallowed and has not been raised again since.
"""

from __future__ import annotations

_pending: type[KeyboardInterrupt] | None = None


def note_swallowed(kind: type[KeyboardInterrupt]) -> None:
    """Record that an interrupt of class ``kind`` (KeyboardInterrupt or a subclass) was dropped by a finaliser."""
    global _pending
    _pending = kind


def pending() -> type[KeyboardInterrupt] | None:
    """The class of the swallowed interrupt not yet delivered, or None."""
    return _pending


def clear() -> None:
    """An interrupt is being raised (or the command is ending): nothing is pending any more."""
    global _pending
    _pending = None


def raise_pending() -> None:
    """Raise the swallowed interrupt, if there is one (and forget it): call at a point where stopping is safe."""
    kind = _pending
    if kind is not None:
        clear()
        raise kind()
