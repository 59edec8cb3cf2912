"""`motion2video synthesize`: observed clip + reference image -> K futures as RGB videos."""

from __future__ import annotations

import argparse
import sys

from motion2video.apps.synthesize import SynthesisConfig, synthesize
from motion2video.commands.common import (RIGID_BONES_HELP, add_command, add_motion_input_arguments,
                                          add_reference_photo_arguments, check_at_least)
from motion2video.core.errors import InputError
from motion2video.data.licences import licence_table

DESCRIPTION = """\
Observe the first --observed frames of a clip, sample K futures with a motion model, render their structure
and turn it into frames of the reference person with a frame generator.
"""

EXAMPLES = """\
examples:
  motion2video synthesize --motion-model mtvae-add --frame-model frames-body-128 demo_inputs/walk_to_run.npz \\
      --reference demo_inputs/reference_body_128.png --samples 5 -o out/futures_body.mp4
  motion2video synthesize --motion-model mtvae-add-face --frame-model frames-face-128 demo_inputs/smile.npz \\
      --reference demo_inputs/reference_face.png --samples 4 --seed 3 -o out/futures_face.mp4
  motion2video synthesize --motion-model runs/mtvae.safetensors --frame-model runs/frames.safetensors \\
      ../shared/data/mocap/cmu/08_01.bvh --reference me.png --reference-pose me.pose.npz --samples 3 \\
      --observed 16 --horizon 60 -o out/me.mp4
  motion2video synthesize --motion-model mixture-periodic --frame-model frames-body-mesh-256 \\
      ../shared/data/video/dancer.avi --reference ../shared/data/photos/skier.jpg --crop-person --samples 3 \\
      -o out/skier_dances.mp4

Writes OUT.mp4 (every cell plays the observed frames framed green, then one sampled future framed red),
OUT-structure.mp4 (the same grid of the structures the generator was given) and OUT-sheet.png (reference,
its structure, observed frames, and a row of future frames per sample): all three, or none on an error.

The reference image is padded to a square and resized to the generator's size when needed (with a note);
grey-scale images become RGB, RGBA images are composited over white. Its pose is read from IMAGE.pose.npz
when that exists (or --reference-pose); otherwise a body pose is estimated in the image (BlazePose, with a
note), a picture with nobody in it is refused (exit 2), and a person cut by the picture's edge gets a note (the
picture is extended, its edge repeated, where the joints lie beyond it). A face reference without a pose file is
assumed to show the first observed pose. A video as the
observed clip has its person's pose estimated (cached in ~/.cache/motion2video/pose by the file's hash).

""" + licence_table()


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "synthesize", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--motion-model", required=True, help="motion checkpoint path or shipped name (mtvae-add, ...)")
    p.add_argument("--frame-model", required=True,
                   help="frame-generator checkpoint path or shipped name (frames-body-128, frames-face-128)")
    p.add_argument("input", help="observed clip: .bvh / motion .npz / a video of a person (.mp4, .avi, .mov: its "
                   "pose is estimated and cached) (body), FaceMotion .npz / .csv or a video of a face (its face "
                   "tracked and cached) (face)")
    p.add_argument("--reference", required=True, help="reference appearance image (PNG, JPEG, ...); face models: "
                   "any portrait, the head fitted to its face")
    add_reference_photo_arguments(p)
    p.add_argument("--samples", type=int, required=True, help="K futures to sample (>= 1)")
    p.add_argument("-o", "--output", required=True, help="output video OUT.mp4 (also OUT-structure.mp4, OUT-sheet.png)")
    p.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    p.add_argument("--observed", type=int, default=None, help="observed frames (default: the motion model's)")
    p.add_argument("--horizon", type=int, default=None, help="future frames (default: the motion model's)")
    p.add_argument("--start", type=int, default=0, help="first observed frame of the clip (default 0)")
    p.add_argument("--rigid-bones", action="store_true", help=RIGID_BONES_HELP)
    p.add_argument("--batch-size", type=int, default=4, help="generator frames per forward pass (default 4)")
    p.add_argument("--size", type=int, default=None,
                   help="output frame size (default: the frame model's); a warp body model (frames-body-128) "
                   "keeps the reference background at this size and generates the person at its own size")
    p.add_argument("--threads", type=int, default=None,
                   help="torch threads for the frame generator (default: half the cores, 1 to 4; sampling uses 1)")
    add_motion_input_arguments(p)


def run(args: argparse.Namespace) -> int:
    check_at_least("--samples", args.samples)
    check_at_least("--batch-size", args.batch_size)
    if args.size is not None and not 32 <= args.size <= 1024:
        raise InputError(f"--size must be in 32..1024, got {args.size}")
    if args.threads is not None:
        check_at_least("--threads", args.threads)
    if args.observed is not None:
        check_at_least("--observed", args.observed, minimum=2)
    if args.horizon is not None:
        check_at_least("--horizon", args.horizon)
    config = SynthesisConfig(samples=args.samples, observed=args.observed, horizon=args.horizon, start=args.start,
                             seed=args.seed, batch_size=args.batch_size, generator_threads=args.threads,
                             size=args.size, rigid_bones=args.rigid_bones, character=args.character,
                             rig_map=args.rig_map, input_fps=args.input_fps, crop_person=args.crop_person, fit_view=args.fit_view)
    result = synthesize(motion_model=args.motion_model, frame_model=args.frame_model, input_path=args.input,
                        reference=args.reference, output=args.output, config=config,
                        reference_pose=args.reference_pose)
    for note in result.notes:
        print(f"motion2video synthesize: note: {note}", file=sys.stderr)
    t = result.timings
    print(f"wrote {result.video} ({result.samples} futures of {result.horizon} frames after {result.observed} "
          f"observed, {result.frames[2]}x{result.frames[1]}, {result.fps:g} fps), {result.structure_video} and "
          f"{result.sheet} in {t['total']:.1f} s (sampling {t['sampling']:.1f}, structures {t['structures']:.1f}, "
          f"generation {t['generation']:.1f}, encoding {t['encoding']:.1f})")
    return 0
