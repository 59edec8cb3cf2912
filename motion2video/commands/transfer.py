"""`motion2video transfer`: re-enact the behaviour of one clip from another clip's posture (or flow samples)."""

from __future__ import annotations

import argparse
import sys

from motion2video.apps.transfer import STYLES, TransferSettings, transfer_to_files
from motion2video.commands.common import (add_bvh_argument, add_command, add_motion_input_arguments,
                                          add_reference_photo_arguments, add_video_output_arguments, set_threads)

DESCRIPTION = """\
Behaviour transfer (Blattmann et al. 2021): extract the behaviour of SOURCE with the behaviour model's
encoder, re-enact it from TARGET's posture at --target-frame, and write the side-by-side video; --sample N
draws N new behaviours through the normalizing flow instead.
"""

EXAMPLES = """\
examples:
  motion2video transfer --model behavior --behavior ../shared/data/mocap/cmu/131_03.bvh \\
      --target ../shared/data/mocap/cmu/01_01.bvh --target-frame 1200 -o out/transfer.mp4
  motion2video transfer --model runs/behavior.safetensors --behavior jump.bvh --target walk.bvh \\
      --style skeleton --horizon 60 -o out/transfer_skeleton.mp4 --npz out/transfer.npz
  motion2video transfer --model behavior --sample 6 --target ../shared/data/mocap/cmu/08_01.bvh \\
      --seed 3 -o out/flow_samples.mp4
  motion2video transfer --model behavior --behavior jump.bvh --target walk.bvh --style frames \\
      --frame-model frames-body-128 --reference person.png -o out/transfer_frames.mp4

The source's behaviour (--behavior-start, then 1 + horizon frames) is encoded by the behaviour model and
re-enacted from the target's posture at --target-frame (frame numbers count the file's own frames), by
the model's decoder first fitted to the source's limb motion retargeted onto the target's posture and bones
(--adapt-steps; 0 re-enacts with the decoder as trained). The video shows the source (left) and the target
re-enacting it (right; start posture framed green, generated frames red) in another person's appearance: an
Anny body with another phenotype and clothes (mesh), or the frame generator animating --reference (frames;
without --reference the target's start posture is rendered as the reference). The re-enactment's root moves
as the model generates it, relative to the target's start position and heading. Clips at other frame rates are
resampled to the model's rate.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "transfer", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--model", required=True, help="behaviour checkpoint path or shipped model name")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--behavior", metavar="SOURCE", help="clip whose behaviour is transferred")
    source.add_argument("--sample", type=int, metavar="N", help="draw N new behaviours through the flow")
    p.add_argument("--target", required=True, help="clip whose posture re-enacts the behaviour")
    p.add_argument("--target-frame", type=int, default=0, help="the target's start frame (file frames, default 0)")
    p.add_argument("--behavior-start", type=int, default=0, help="first frame of the source's behaviour (default 0)")
    p.add_argument("--horizon", type=int, default=None, help="generated frames (default: the model's, 48)")
    p.add_argument("--adapt-steps", type=int, default=None, metavar="N",
                   help="fit the decoder for N steps to the source retargeted onto the target's posture and bones "
                   "before re-enacting it, so that large, rare limb motions (a jump's arm swing, a kick) come "
                   "across from any posture (default 300, about 6 s; 0: the model as trained)")
    p.add_argument("--style", choices=STYLES, default=None,
                   help="mesh: Anny bodies (default for 3D body and face models); frames: the frame generator "
                   "(default when --reference is given); skeleton: limb maps")
    p.add_argument("--reference", default=None, help="reference image of the target person (--style frames)")
    add_reference_photo_arguments(p)
    p.add_argument("--frame-model", default=None,
                   help="frame-generator checkpoint or shipped name for --style frames (default frames-body-128, "
                   "or frames-face-128 for face models)")
    p.add_argument("--seed", type=int, default=0, help="seed of the flow samples (default 0)")
    add_video_output_arguments(p, npz_help="also write source, re-enactments and latents to this .npz")
    add_motion_input_arguments(p)
    add_bvh_argument(p, "re-enactment (DIR/reenacted_1.bvh, ...)")


def run(args: argparse.Namespace) -> int:
    set_threads(args.threads)
    settings = TransferSettings(
        model=args.model, target=args.target, output=args.output, behavior=args.behavior, sample=args.sample,
        target_frame=args.target_frame, behavior_start=args.behavior_start, horizon=args.horizon,
        adapt_steps=args.adapt_steps, style=args.style, reference=args.reference,
        reference_pose=args.reference_pose, crop_person=args.crop_person, fit_view=args.fit_view,
        frame_model=args.frame_model, seed=args.seed, size=args.size, npz=args.npz, character=args.character,
        input_fps=args.input_fps, rig_map=args.rig_map, bvh=args.bvh)
    files = transfer_to_files(settings,
                              note=lambda line: print(f"motion2video transfer: note: {line}", file=sys.stderr))
    result = files.result
    what = (f"behaviour of {args.behavior}" if args.behavior is not None
            else f"{args.sample} flow-sampled behaviours (seed {args.seed})")
    print(f"wrote {files.video} ({what} re-enacted from {args.target} frame {args.target_frame}: "
          f"{result.reenacted.shape[1] - 1} generated frames, {files.style}, {files.width}x{files.height}, "
          f"{result.fps:g} fps)")
    if files.npz is not None:
        print(f"wrote {files.npz}")
    if files.bvh:
        print(f"wrote {len(files.bvh)} BVH files to {args.bvh} ({files.bvh[0].name} ...)")
    return 0
