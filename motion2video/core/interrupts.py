"""Ctrl-C and SIGTERM kept until they have stopped the command.

Python raises the KeyboardInterrupt of a signal at whatever line runs next. When that line is inside a finaliser
(``__del__``, e.g. OpenGL freeing a buffer), Python prints the exception and drops it; inside a library's bare
``except:`` it is dropped without a word. Either way the command would run on to the end (a SIGINT'd mesh render
that exited 0, seen once under load). So the CLI's signal handlers (:mod:`motion2video.cli`) record every
interrupt here (:func:`note`) before raising it, and ``main`` forgets it (:func:`clear`) once it has stopped the
command; long loops call :func:`raise_pending` at safe points (every chunk a video writer encodes), so an interrupt
that was dropped on its way stops the command there. A finaliser's drop is also answered by sending the signal
again (the CLI's unraisable hook).

The state is one class, or None: the interrupt that arrived and has not stopped the command yet.
"""

from __future__ import annotations

_pending: type[KeyboardInterrupt] | None = None
_raised = 0  # interrupts raised so far (by a signal handler or by raise_pending)


def note(kind: type[KeyboardInterrupt]) -> None:
    """Record that an interrupt of class ``kind`` (KeyboardInterrupt or a subclass) arrived and is being raised."""
    global _pending, _raised
    _pending = kind
    _raised += 1


def pending() -> type[KeyboardInterrupt] | None:
    """The class of the interrupt that arrived and has not stopped the command yet, or None."""
    return _pending


def raised() -> int:
    """How many interrupts were raised so far: one raised after another was dropped makes this grow."""
    return _raised


def clear() -> None:
    """The interrupt has stopped the command (or the command starts or ends): nothing is pending any more."""
    global _pending
    _pending = None


def raise_pending() -> None:
    """Raise again the interrupt that arrived and was dropped on its way, if there is one: call at a point where
    stopping is safe. It stays pending until the command has stopped (:func:`clear`), so it is raised again
    at the next such point should it be dropped again."""
    if _pending is not None:
        note(_pending)
        raise _pending()
