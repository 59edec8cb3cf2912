"""Options several sub-commands share."""

from __future__ import annotations

import argparse
from pathlib import Path

from motion2video.errors import InputError

THREADS_HELP = ("torch CPU threads (default 1: the small recurrent models and the frame generator ran 3-40x faster "
                "single-threaded on 2 shared cores)")


def check_video_and_npz(output: str | Path, npz: str | Path | None) -> Path:
    """Validate ``-o OUT.mp4|.gif`` and an optional ``--npz OUT.npz`` before any work; returns the video path."""
    from motion2video.atomic import check_output_path
    from motion2video.video import VIDEO_SUFFIXES

    out = check_output_path(output, VIDEO_SUFFIXES)
    if npz is not None:
        check_output_path(npz, (".npz",))
    return out


def add_threads_argument(parser: argparse.ArgumentParser) -> None:
    """``--threads N`` (default 1)."""
    parser.add_argument("--threads", type=int, default=1, help=THREADS_HELP)


def set_threads(threads: int) -> None:
    """Check ``--threads`` and apply it to torch (InputError when below 1)."""
    import torch

    if threads < 1:
        raise InputError(f"--threads must be >= 1, got {threads}")
    torch.set_num_threads(threads)
