"""`motion2video app`: the local web app (Gradio, the optional extra ``.[app]``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from motion2video.commands.common import add_command, check_at_least
from motion2video.core.errors import InputError


DESCRIPTION = """\
Serve the web app on this machine and print its address: drop a photo (or pick a demo one), pick a bundled clip
or upload a motion file or a video, the motion and frame models and the number of futures, press Animate, watch
the futures play beside their structure and download the mp4, npz and BVH files. Behaviour transfer has its own
tab. It calls the same Python API as the commands; bad input shows the same one-line message. Needs Gradio:
pip install -e ".[app]".
"""

EXAMPLES = """\
examples:
  motion2video app                       # then open http://127.0.0.1:7860
  motion2video app --port 8000 --frame-model frames-body-128 --samples 2
  motion2video app --host 0.0.0.0        # serve other machines on your network too (no login: trusted networks only)
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "app", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=7860, help="port (default 7860; 0: the first free one from 7860)")
    p.add_argument("--motion-model", default="mixture-periodic", help="the motion model the page starts with")
    p.add_argument("--frame-model", default="frames-body-mesh-256", help="the frame model the page starts with")
    p.add_argument("--samples", type=int, default=3, help="the number of futures the page starts with (default 3)")
    p.add_argument("--horizon", type=int, default=48, help="the future frames the page starts with (default 48)")
    p.add_argument("--max-video-seconds", type=float, default=30.0,
                   help="refuse uploaded videos longer than this (default 30)")
    p.add_argument("--work-dir", default=None, help="folder for each run's files (default: a new temporary folder)")


def run(args: argparse.Namespace) -> int:
    check_at_least("--samples", args.samples)
    check_at_least("--horizon", args.horizon)
    if not 0 <= args.port <= 65535:
        raise InputError(f"--port must be in 0..65535, got {args.port}")
    if args.max_video_seconds <= 0:
        raise InputError(f"--max-video-seconds must be > 0, got {args.max_video_seconds:g}")
    try:
        from motion2video.apps.web import AppSettings, serve
    except ModuleNotFoundError as err:
        if err.name != "gradio":
            raise
        raise InputError('the web app needs Gradio: pip install -e ".[app]"') from None
    serve(AppSettings(host=args.host, port=args.port, motion_model=args.motion_model, frame_model=args.frame_model,
                      samples=args.samples, horizon=args.horizon, max_video_seconds=args.max_video_seconds,
                      work_dir=None if args.work_dir is None else Path(args.work_dir)))
    return 0
