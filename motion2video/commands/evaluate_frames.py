"""`motion2video evaluate-frames`: PSNR / SSIM of a frame generator and the baselines on held-out pairs."""

from __future__ import annotations

import argparse
import json
import sys

from motion2video.commands.common import add_command, check_at_least
from motion2video.evaluation.frame_generators import FrameEvalSettings, evaluate_frame_generator

DESCRIPTION = """\
Render (or reuse from the cache) the held-out split (held-out identities and clips) for the model's domain and
size, and report whole-frame PSNR and SSIM (scikit-image) and person metrics (PSNR, SSIM and sharpness ratio
inside the target's silhouette, PSNR and sharpness where the person moved; for bodies head PSNR and SSIM over
the target's visible head, kept in the cache beside the frames) for the generator, copy-reference, limb-warp
and the previous generator on the same pairs. With --video V (body models): the reconstruction
protocol of FOMM / TPSMM on a real video instead: frame 0 is the reference, the later frames' estimated poses
(BlazePose) drive the generator, the real frames are the truth, all cut to one square around the person; per
method l1 (mean absolute error in [0, 1]), PSNR, SSIM, person PSNR / SSIM / sharpness inside BlazePose's
segmentation of the real frame, and akd (pixels between the poses BlazePose finds on the generated and on the
real frame; akd_missing: generated frames where it finds none). The video is tracked once and cached in
~/.cache/motion2video/pose. --video-start-fraction F takes the targets from the video's tail only (frames from
F of the video on; frame 0 stays the reference): the part train-frames --video --train-fraction F never trains
on.

With --video V and a face model: the talking-head protocol. The face is tracked as pose --face tracks it (face
mesh, the Anny head fitted; cached); frame 0 of the track is the reference, the later frames' fitted head pose
and expressions drive the generator (the fitted head rendered in each frame), the real frames are the truth, all
cut to the close-up square the face generators were trained on. Per method (the generator, copy-reference,
landmark-warp: a piecewise-affine warp on the tracked face points, and the previous face generator): l1, PSNR,
SSIM, head_psnr / head_ssim inside the real face (the hull of its tracked landmarks), and landmark_error (the face
mesh run on the generated and on the real frame: mean distance of its points over the real face's size;
landmark_missing: generated frames where it finds no face). --video-frames and --video-stride choose the frames.

With --poses PATH (a body motion file or a folder of them, any format the readers know), the pairs come from
real motion instead: the frame test split's held-out identities, posed by windows spread evenly over each clip
(--windows per clip, the test split's 9 frames over 1.2 s each), rendered with the Anny body renderer as the
training data is; frame 0 of a window is the reference, every later frame a target whose truth is its render.
These runs also report head_psnr and head_ssim over the target's visible head (the silhouette of Anny's head
vertices). A named baseline still trained on the previous canonical skeleton is left out, with a note.
"""

EXAMPLES = """\
examples:
  motion2video evaluate-frames --model frames-body-128 --json out/eval_frames_body.json
  motion2video evaluate-frames --model out/frames-face-128.safetensors --contact-sheet out/face_sheet.png
  motion2video evaluate-frames --model frames-body-128 --video ../shared/data/video/dancer.avi --json out/dancer.json
  motion2video evaluate-frames --model out/dancer-body-128.safetensors --video ../shared/data/video/dancer.avi \\
      --video-start-fraction 0.8 --json out/dancer_tail.json
  motion2video evaluate-frames --model frames-face-mesh-128 --video ../shared/data/video/face_talking_woman.mp4 \\
      --json out/talking_woman.json --contact-sheet out/talking_woman.png
  motion2video evaluate-frames --model frames-body-128 --poses ../shared/data/mocap/cmu/08_01.bvh --json out/real.json
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "evaluate-frames", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--model", required=True, help="a checkpoint file or a shipped name (frames-body-128)")
    p.add_argument("--json", default=None, help="write the results here as JSON")
    p.add_argument("--cache", default=None,
                   help="directory for the rendered npz shards (default ~/.cache/motion2video/frames)")
    p.add_argument("--data-root", default=None,
                   help="folder with mocap/ and face/ captures (default ../shared/data beside the repository)")
    p.add_argument("--pairs", type=int, default=None, help="evaluate only the first N pairs (default all)")
    p.add_argument("--test-sequences", type=int, default=None,
                   help="render only this many held-out sequences (default 32, 9 frames each: 256 pairs)")
    p.add_argument("--contact-sheet", default=None,
                   help="also write a PNG: reference | target | new | old | copy-reference | limb-warp")
    p.add_argument("--baseline-model", action="append", default=None, metavar="MODEL",
                   help="also score this generator (checkpoint or shipped name) as a named baseline on the same "
                   "pairs; repeatable (default for body models: the previous generator frames-body-128-v1)")
    p.add_argument("--video", default=None,
                   help="a real video of one person: score by the reconstruction protocol (body models) or, for a face "
                   "model, the talking-head protocol on a face video")
    p.add_argument("--video-frames", type=int, default=64,
                   help="--video: later frames scored against frame 0 (default 64, spread over the video)")
    p.add_argument("--video-stride", type=int, default=None,
                   help="--video: video frames between two scored frames (default: spread over the whole video)")
    p.add_argument("--video-start-fraction", type=float, default=0.0, metavar="F",
                   help="--video: take the targets from the tail only, from F of the video's frames on (e.g. 0.8, "
                   "the part train-frames --video leaves out); frame 0 stays the reference (default 0)")
    p.add_argument("--poses", default=None, metavar="PATH",
                   help="pose the held-out identities by the body motion file(s) at PATH (a file or a folder) "
                   "instead of the held-out pairs")
    p.add_argument("--windows", type=int, default=4,
                   help="with --poses: windows per clip, spread evenly over it (default 4, 8 pairs each)")
    p.add_argument("--no-progress", action="store_true", help="hide progress bars")


def run(args: argparse.Namespace) -> int:
    if args.pairs is not None:
        check_at_least("--pairs", args.pairs)
    if args.test_sequences is not None:
        check_at_least("--test-sequences", args.test_sequences)
    check_at_least("--windows", args.windows)
    if args.video is not None:
        check_at_least("--video-frames", args.video_frames)
        if args.video_stride is not None:
            check_at_least("--video-stride", args.video_stride)
    baselines = None if args.baseline_model is None else tuple(args.baseline_model)
    settings = FrameEvalSettings(
        model=args.model, json=args.json, contact_sheet=args.contact_sheet, baseline_models=baselines,
        cache=args.cache, data_root=args.data_root, pairs=args.pairs, test_sequences=args.test_sequences,
        poses=args.poses, windows=args.windows, video=args.video, video_frames=args.video_frames,
        video_stride=args.video_stride, video_start_fraction=args.video_start_fraction,
        progress=not args.no_progress)
    result = evaluate_frame_generator(settings, note=lambda line: print(f"note: {line}", file=sys.stderr))
    print(json.dumps(result.payload, indent=2, sort_keys=True))
    if result.contact_sheet is not None:
        print(f"wrote {result.contact_sheet}")
    return 0
