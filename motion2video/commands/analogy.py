"""`motion2video analogy`: A is to B as C is to D (MT-VAE analogy-based motion transfer)."""

from __future__ import annotations

import argparse

from motion2video.apps.analogy import STYLES, AnalogySettings, analogy_to_files
from motion2video.commands.common import (add_bvh_argument, add_command, add_motion_input_arguments,
                                          add_video_output_arguments, set_threads)

DESCRIPTION = """\
Analogy-based motion transfer (MT-VAE, Sec. 4.2): the transformation latent of A followed by B, decoded from
C's context, gives D. Body and face models.
"""

EXAMPLES = """\
examples:
  motion2video analogy --model mtvae-add ../shared/data/mocap/cmu/131_01.bvh ../shared/data/mocap/cmu/131_01.bvh \\
      ../shared/data/mocap/cmu/01_01.bvh --a-start 400 --c-start 1200 -o out/analogy.mp4
  motion2video analogy --model runs/mtvae-add.safetensors walk.bvh run.bvh other_walk.bvh --style mesh \\
      -o out/analogy_mesh.mp4 --npz out/analogy.npz
  motion2video analogy --model mtvae-add-face ../shared/data/face/livelinkface/alex_rom_3.csv \\
      ../shared/data/face/livelinkface/alex_rom_3.csv ../shared/data/face/llv/dao.csv --a-start 2195 \\
      -o out/face_start_smiling.mp4   # A -> B: the capture starts smiling; C: another face, real head pose

A is --observed frames of the first clip from --a-start, B the --horizon frames that follow it (by default
the frames right after A when B is the same file, else from --b-start), C --observed frames of the third
clip from --c-start (frame numbers count each file's own frames). z is the posterior mean of A -> B; D is
decoded from C with it. The video shows A then B (left) and C then the generated D (right, framed red).
B from another file is rotated and moved to continue A. Clips at other frame rates are resampled to the
model's rate.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "analogy", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--model", required=True, help="latent model checkpoint or shipped name (mtvae-add, ...)")
    p.add_argument("a", metavar="A", help="clip of the window before the transition")
    p.add_argument("b", metavar="B", help="clip of the window after it (often A's file)")
    p.add_argument("c", metavar="C", help="clip to transfer the transition to")
    p.add_argument("--a-start", type=int, default=0, help="A's first frame (default 0)")
    p.add_argument("--b-start", type=int, default=None,
                   help="B's first frame (default: right after A's window when B is A's file, else 0)")
    p.add_argument("--c-start", type=int, default=0, help="C's first frame (default 0)")
    p.add_argument("--observed", type=int, default=None, help="frames of A and C (default: the model's, 16)")
    p.add_argument("--horizon", type=int, default=None, help="frames of B and D (default: the model's, 48)")
    p.add_argument("--style", choices=STYLES, default="skeleton",
                   help="skeleton maps or Anny bodies (body models; face models draw the Anny face)")
    add_video_output_arguments(p, npz_help="also write A->B, C->D and z to this .npz")
    add_motion_input_arguments(p)
    add_bvh_argument(p, "re-enactment (C then the generated D: DIR/analogy_1.bvh)")


def run(args: argparse.Namespace) -> int:
    set_threads(args.threads)
    settings = AnalogySettings(model=args.model, a=args.a, b=args.b, c=args.c, output=args.output,
                               a_start=args.a_start, b_start=args.b_start, c_start=args.c_start,
                               observed=args.observed, horizon=args.horizon, style=args.style, size=args.size,
                               npz=args.npz, character=args.character, input_fps=args.input_fps,
                               rig_map=args.rig_map, bvh=args.bvh)
    files = analogy_to_files(settings)
    result = files.result
    print(f"wrote {files.video} (A:B::C:D with {files.label}; {result.observed} observed + "
          f"{result.cd.shape[0] - result.observed} generated frames, {files.width}x{files.height}, "
          f"{result.fps:g} fps{'' if result.consecutive else '; B placed after A'})")
    if files.npz is not None:
        print(f"wrote {files.npz}")
    if files.bvh:
        print(f"wrote {files.bvh[0]}")
    return 0
