"""`motion2video ...`: a thin command line. Each sub-command lives in ``motion2video/commands/<name>.py``
with two functions, ``add_parser(subparsers)`` and ``run(args) -> int``; this file only dispatches and turns
:class:`~motion2video.core.errors.InputError` into a one-line message with exit code 2.

The command modules import their applications (and with them torch, OpenCV, the renderers) at their top, so the
CLI imports only the module of the sub-command a command line names; ``motion2video --help`` lists the commands
from :data:`SUMMARIES` without importing any."""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading

from motion2video import __version__
from motion2video.core import interrupts
from motion2video.core.errors import InputError

# Every sub-command's line in `motion2video --help`, in the order listed there. The table is here, not in the command
# modules, so that `--help` lists the commands without importing them (and with them torch and the renderers).
SUMMARIES = {
    "render": ("render a motion file (BVH, DeepMimic, exp-map text, npz, OpenPose JSON folder, Live Link Face CSV) or "
               "the person of a video to mp4/GIF"),
    "pose": ("estimate a person's pose in a photo (reference pose file) or a video (motion .npz), BlazePose; --face: "
             "a face video's face motion"),
    "train": "train a motion model (pred-lstm, cvae, mtvae-concat, mtvae-add, lcpvae, behavior)",
    "evaluate": "score a motion model and the zero-velocity / last-step / sequence-motion baselines",
    "sample": "sample K futures of a clip from a motion model and render them as a grid video",
    "train-frames": "train the keypoint-conditioned frame generator (body or face)",
    "evaluate-frames": "score a frame generator against copy-reference and limb-warp on held-out pairs",
    "synthesize": "sample K futures of a clip and render them as RGB video of a reference person",
    "transfer": "re-enact the behaviour of one clip from another clip's posture (behaviour model)",
    "analogy": "transfer the transition A -> B to C (MT-VAE analogy): A : B :: C : D",
    "corpus-stats": "print minutes per source, action and split of a mocap folder as the trainer uses it",
    "batch": ("run many render/sample/synthesize jobs (JSONL job file, or a folder/glob and a template) on a process "
              "pool or Ray, resumable, with results.jsonl and an HTML gallery"),
    "doctor": "check the installation: torch, ffmpeg, GL backends, the Anny cache, the shipped checkpoints",
    "app": "start the local web app: animate a photo with a clip or a video, transfer a behaviour (needs .[app])",
}

# Sub-command modules (motion2video/commands/<name>.py), in the same order.
COMMANDS = tuple(name.replace("-", "_") for name in SUMMARIES)


def named_command(argv: list[str]) -> str | None:
    """The sub-command module a command line names (its first argument that is not an option, when it is one of
    :data:`COMMANDS` with ``-`` for ``_``), or None."""
    first = next((arg for arg in argv if not arg.startswith("-")), None)
    module = None if first is None else first.replace("-", "_")
    return module if module in COMMANDS else None


def _top_parser() -> tuple[argparse.ArgumentParser, argparse._SubParsersAction]:
    parser = argparse.ArgumentParser(
        prog="motion2video",
        description="Human motion in, video out.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"motion2video {__version__}")
    return parser, parser.add_subparsers(dest="command", metavar="COMMAND")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every sub-command, or of ``command`` alone (a module name of :data:`COMMANDS`): only the
    modules of the parsers built are imported."""
    parser, sub = _top_parser()
    for name in COMMANDS if command is None else (command,):
        importlib.import_module(f"motion2video.commands.{name}").add_parser(sub)
    return parser


def listing_parser() -> argparse.ArgumentParser:
    """The parser of a command line that names no sub-command (``--help``, ``--version``, a misspelt command):
    every sub-command listed with its summary, none imported."""
    parser, sub = _top_parser()
    for name, summary in SUMMARIES.items():
        sub.add_parser(name, help=summary)
    return parser


REDELIVER_DELAY_S = 0.01  # an interrupt dropped by a finaliser is sent again this much later

_finished = threading.Event()  # set once main() has its result: an interrupt sent again after it is not sent


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every ``finally`` and atomic writer cleans up on the way out."""


def _raise_terminated(signum, frame) -> None:
    interrupts.note(Terminated)  # kept until main has it: a library that drops it meets it again (raise_pending)
    raise Terminated()


def _raise_interrupted(signum, frame) -> None:
    interrupts.note(KeyboardInterrupt)
    raise KeyboardInterrupt()


def _send_again(sig: int, raised: int) -> None:
    """The timer of :func:`_redeliver_interrupts`: the signal again, unless an interrupt was raised since the
    dropped one (``raised``: :func:`motion2video.core.interrupts.raised` then; at a ``raise_pending`` point, or
    by another signal) or the command has ended."""
    if interrupts.pending() is not None and interrupts.raised() == raised and not _finished.is_set():
        os.kill(os.getpid(), sig)


def _redeliver_interrupts(unraisable) -> None:
    """``sys.unraisablehook``: a SIGTERM or Ctrl-C that arrives while Python runs a finaliser (``__del__``, e.g.
    OpenGL freeing a buffer) is printed and dropped by Python, and the command would run on to the end. It stays
    recorded (:mod:`motion2video.core.interrupts`: the video writers raise it at their next chunk), and the signal
    is sent again, so it stops the command at the next ordinary line; other unraisable errors are printed as
    usual."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        terminated = isinstance(unraisable.exc_value, Terminated)
        if interrupts.pending() is None:  # raised by a handler of Python's own rather than this module's
            interrupts.note(Terminated if terminated else KeyboardInterrupt)
        # From another thread a moment later: sent from here, it would be handled inside this hook and dropped again.
        timer = threading.Timer(REDELIVER_DELAY_S, _send_again,
                                (signal.SIGTERM if terminated else signal.SIGINT, interrupts.raised()))
        timer.daemon = True
        timer.start()
        return
    sys.__unraisablehook__(unraisable)


def install_signal_handlers() -> None:
    """SIGTERM raises :class:`Terminated` and Ctrl-C KeyboardInterrupt (unless SIGINT is ignored, as in a
    background job); an interrupt swallowed by a finaliser is delivered again. Main thread only (Python allows
    signal handlers there alone)."""
    if threading.current_thread() is threading.main_thread():
        _finished.clear()
        interrupts.clear()
        signal.signal(signal.SIGTERM, _raise_terminated)
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, _raise_interrupted)
        sys.unraisablehook = _redeliver_interrupts


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    command = named_command(argv)
    parser = listing_parser() if command is None else build_parser(command)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    install_signal_handlers()
    try:
        return int(args.run(args) or 0)
    except InputError as err:
        print(f"motion2video {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as err:  # SIGINT (Ctrl-C) or SIGTERM: outputs and temporary files are gone
        _finished.set()  # before the message: a re-sent signal from here on is not sent
        terminated = isinstance(err, Terminated)
        print(f"motion2video {args.command}: {'terminated (SIGTERM)' if terminated else 'interrupted (SIGINT)'}; "
              "no partial output left", file=sys.stderr)
        return 143 if terminated else 130
    finally:
        _finished.set()  # a signal sent again from now on would kill the interpreter as it exits
        interrupts.clear()


if __name__ == "__main__":
    sys.exit(main())
