"""`motion2video analogy`: A is to B as C is to D (MT-VAE analogy-based motion transfer)."""

from __future__ import annotations

import argparse

from motion2video.commands.common import (add_bvh_argument, add_command, add_motion_input_arguments,
                                          add_video_output_arguments, check_bvh_output, check_video_and_npz,
                                          set_threads)
from motion2video.core.errors import InputError

HELP = "transfer the transition A -> B to C (MT-VAE analogy): A : B :: C : D"

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
    p = add_command(sub, "analogy", run, help=HELP, description=DESCRIPTION, examples=EXAMPLES)
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
    p.add_argument("--style", choices=("skeleton", "mesh"), default="skeleton",
                   help="skeleton maps or Anny bodies (body models; face models draw the Anny face)")
    add_video_output_arguments(p, npz_help="also write A->B, C->D and z to this .npz")
    add_motion_input_arguments(p)
    add_bvh_argument(p, "re-enactment (C then the generated D: DIR/analogy_1.bvh)")


def run(args: argparse.Namespace) -> int:
    import numpy as np
    from motion2video.apps.analogy import analogy, iter_analogy
    from motion2video.stages.latents import analogy_model
    from renderers.registry import check_style
    from motion2video.models.checkpoint import load_model
    from motion2video.core.atomic import save_npz
    from motion2video.models.baselines import BASELINES
    from motion2video.stages.clips import load_clip
    from motion2video.stages.video import check_cell_size
    from motion2video.formats.video import VideoWriter

    set_threads(args.threads)
    check_cell_size(args.size)
    out = check_video_and_npz(args.output, args.npz)
    if args.model in BASELINES:
        raise InputError(f"analogy needs a latent-variable model (mtvae-add, ...); {args.model!r} is a baseline "
                         "without a latent space")
    bundle = load_model(args.model)
    check_bvh_output(args.bvh, bundle.data_config.layout)
    analogy_model(bundle)  # the wrong kind of model fails before any clip is read
    check_style(bundle.data_config.layout, args.style)  # mesh needs a 3D body model
    options = {"character": args.character, "fps": args.input_fps, "rig_map": args.rig_map}
    a = load_clip(bundle, args.a, **options)
    b = a if args.b == args.a else load_clip(bundle, args.b, **options)
    c = load_clip(bundle, args.c, **options)
    result = analogy(bundle, a, b, c, a_start=args.a_start, b_start=args.b_start, c_start=args.c_start,
                     observed=args.observed, horizon=args.horizon)
    chunks = iter_analogy(result, style=args.style, size=args.size)
    with VideoWriter(out, result.fps) as writer:
        for chunk in chunks:
            writer.write(chunk)
    print(f"wrote {out} (A:B::C:D with {bundle.label}; {result.observed} observed + "
          f"{result.cd.shape[0] - result.observed} generated frames, {writer.width}x{writer.height}, "
          f"{result.fps:g} fps{'' if result.consecutive else '; B placed after A'})")
    if args.npz:
        save_npz(args.npz, {"ab": result.ab, "cd": result.cd, "z": result.z, "observed": np.int64(result.observed),
                            "fps": np.float64(result.fps), "layout": np.str_(result.layout),
                            "model": np.str_(bundle.name)})
        print(f"wrote {args.npz}")
    if args.bvh:
        from motion2video.formats.bvh_write import write_bvh_files

        paths = write_bvh_files(args.bvh, "analogy", result.cd[None], result.fps)
        print(f"wrote {paths[0]}")
    return 0
