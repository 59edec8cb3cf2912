"""`motion2video render`: one motion file -> one mp4 (or GIF) of its structure."""

from __future__ import annotations

import argparse

from motion2video.commands.common import add_command, add_motion_input_arguments
from motion2video.apps.render import STYLES, RenderRequest, render_file

DESCRIPTION = """\
Render a motion clip offscreen: skeleton maps, Gaussian heatmaps, the Anny body mesh, or the Anny face. Body
inputs are converted to the canonical H36M-17 skeleton first. A video's person is found and their 3D pose estimated
(BlazePose, cached by the file's hash, as `motion2video pose` does), then drawn like any body clip.
"""

EXAMPLES = """\
examples:
  motion2video render ../shared/data/mocap/cmu/08_01.bvh -o out/walk_skeleton.mp4
  motion2video render ../shared/data/mocap/mass/mass_kick.bvh -o out/kick_mesh.mp4 --style mesh --size 256
  motion2video render ../shared/data/mocap/deepmimic-cmu/49_06.txt -o out/cartwheel.mp4
  motion2video render ../shared/data/mocap/cmu-bench/test/soccer/soccer_1.txt -o out/soccer.mp4
  motion2video render demo_inputs/walk_to_run.npz -o out/heatmaps.mp4 --style heatmap --start 10 --frames 50
  motion2video render ../shared/data/face/llv/dao.csv -o out/dao_face.mp4 --style face
  motion2video render demo_inputs/smile.npz -o out/smile.gif --style face --fps 12.5
  motion2video render ../shared/data/video/dancer.avi -o out/dancer_mesh.mp4 --style mesh --frames 100
  motion2video render humanml3d_joints.npy -o out/t2m.mp4            # (T, 22, 3) SMPL joints, 20 fps
  motion2video render futures.npy -o out/futures.mp4                 # (K, T, J, 3): a grid of K cells
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "render", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("input", help="a .bvh, DeepMimic motion file (.txt/.json with \"Frames\"), exp-map text file "
                   "(.txt with a skeleton.json beside or above it), .npz (Motion or FaceMotion), joint array .npy "
                   "(or .npz with one array) of shape (T, 22, 3) SMPL, (T, 17, 3) H36M or (K, T, J, 3) futures, "
                   "OpenPose JSON folder, .csv face capture, or a video of a person (.mp4, .avi, .mov, ...: their pose is "
                   "estimated)")
    p.add_argument("-o", "--output", required=True, help="output .mp4 or .gif")
    p.add_argument("--style", choices=STYLES, default="skeleton", help="what to draw (default: skeleton)")
    p.add_argument("--size", type=int, default=256, help="frame width and height in pixels, 32..2048 (default 256)")
    p.add_argument("--fps", type=float, default=None,
                   help="output frame rate; the motion is resampled to it (default: the clip's own rate). An "
                   "OpenPose folder has no rate of its own: --fps is its true rate (default 25)")
    p.add_argument("--start", type=int, default=0, help="first frame to render (default 0)")
    p.add_argument("--frames", type=int, default=None, help="number of frames to render (default: all)")
    p.add_argument("--palette", choices=("leftright", "openpose"), default="leftright",
                   help="skeleton colours: left green / right red / spine blue, or the OpenPose (ControlNet) palette")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_motion_input_arguments(p)


def run(args: argparse.Namespace) -> int:
    request = RenderRequest(
        input=args.input,
        output=args.output,
        style=args.style,
        size=args.size,
        fps=args.fps,
        start=args.start,
        frames=args.frames,
        palette=args.palette,
        progress=not args.no_progress,
        character=args.character,
        rig_map=args.rig_map,
        input_fps=args.input_fps,
    )
    result = render_file(request)
    print(f"wrote {result.path} ({result.num_frames} frames, {result.width}x{result.height}, {result.fps:g} fps)")
    return 0
