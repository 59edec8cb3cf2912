"""`motion2video sample`: K sampled futures of a clip as a grid video (and an npz)."""

from __future__ import annotations

import argparse

from motion2video.apps.sample import STYLES, SampleSettings, sample_to_files
from motion2video.commands.common import (RIGID_BONES_HELP, add_bvh_argument, add_command,
                                          add_motion_input_arguments, add_threads_argument, check_at_least,
                                          set_threads)
from motion2video.data.licences import licence_table

DESCRIPTION = """\
Observe the first --observed frames of a clip (from --start), sample K futures from a checkpoint or shipped
model, and write the grid video (observed frames framed green, futures red) and optionally the samples as npz.
"""

EXAMPLES = """\
examples:
  motion2video sample --model mtvae-add ../shared/data/mocap/cmu/08_01.bvh --samples 6 -o out/futures.mp4
  motion2video sample --model runs/cvae.safetensors walk.npz --samples 9 --observed 16 --horizon 60 \\
      --seed 3 -o out/cvae.mp4 --npz out/cvae.npz
  motion2video sample --model mtvae-add ../shared/data/mocap/mass/mass_walk.bvh --samples 4 --style mesh -o out/mesh.mp4
  motion2video sample --model mtvae-add-face ../shared/data/face/llv/dao.csv --samples 4 -o out/face.mp4
  motion2video sample --model zero-velocity ../shared/data/mocap/cmu/08_01.bvh --samples 1 -o out/zv.mp4

Every cell of the grid plays the observed frames framed in green, then one sampled future framed in red.
--model also takes the baselines' names (zero-velocity, last-step, sequence-motion) for a body clip, and
mirror-periodic for a 3D body clip (the observed motion repeated every half-period, mirrored; one half-period per
future, spread over 0.32-0.64 s; --samples 1 takes the one that best fits the observed frames), and settle (the
last step continued, slowing to rest; one decay time per future, spread over 0.04-0.64 s).

shipped motion models (model cards in motion2video/weights/NAME.md):
  mixture-periodic 3D body: the best sampler (lowest best-of-50 error over actions, held out and validation,
                  docs/results.md): its futures come from mtvae-add-dlow, mixer-cvae-dlow, mirror-periodic and
                  settle (34%, 34%, 24%, 8%; with 5 futures the third is mirror-periodic's, the walk's own steps)
  mixture-dlow    3D body: the previous best, mtvae-add-dlow's and mixer-cvae-dlow's futures in turn
  mtvae-add-dlow  3D body: DLow over MT-VAE (the best sampler of one decoder)
  mtvae-add       3D body: MT-VAE, the model mtvae-add-dlow samples from
  lcpvae          3D body: LCP-VAE, a learned condition-dependent prior
  behavior        3D body: the behaviour model (flow samples; transfer re-enacts with it)
  mixer-cvae-dlow 3D body: DLow over a CVAE with a DCT + MLP-mixer decoder (no better than
                  mtvae-add-dlow on the macro average)
  mixer-cvae      3D body: that CVAE, sampled from its prior
  mtvae-add-2d    2D keypoints in a virtual camera
  mtvae-add-face  ARKit face coefficients + head pose
  mixture-periodic-bandai  3D body: mixture-periodic's recipe trained on the corpus joined with Bandai-Namco's
                  (mocap + bandai; NON-COMMERCIAL, CC BY-NC 4.0 data): its futures come from
                  mtvae-add-dlow-bandai, mixer-cvae-dlow-bandai, mirror-periodic and settle; better on waves,
                  raised hands and runs, behind mixture-periodic on held-out CMU subjects
  mtvae-add-dlow-bandai   3D body: its DLow part over mtvae-add-bandai (NON-COMMERCIAL)
  mixer-cvae-dlow-bandai  3D body: its DLow part over mixer-cvae-bandai (NON-COMMERCIAL)
  mtvae-add-bandai        3D body: MT-VAE trained likewise (NON-COMMERCIAL)
  mixer-cvae-bandai       3D body: the DCT + MLP-mixer CVAE trained likewise (NON-COMMERCIAL)

""" + licence_table()


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "sample", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--model", required=True, help="checkpoint path, shipped model name, or a baseline name")
    p.add_argument("input", help="observed clip: .bvh / motion .npz / a video of a person (body models; 2D body "
                   "models also an OpenPose JSON folder), .csv / FaceMotion .npz (face)")
    p.add_argument("--samples", type=int, required=True, help="K futures to sample (>= 1)")
    p.add_argument("--observed", type=int, default=None, help="observed frames (default: the model's, 16)")
    p.add_argument("--horizon", type=int, default=None, help="future frames (default: the model's, 48)")
    p.add_argument("--start", type=int, default=0, help="first observed frame of the clip (default 0)")
    p.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    p.add_argument("--rigid-bones", action="store_true", help=RIGID_BONES_HELP)
    p.add_argument("-o", "--output", required=True, help="output video (.mp4 or .gif)")
    p.add_argument("--npz", default=None, help="also write observed + futures to this .npz")
    p.add_argument("--style", choices=STYLES, default="skeleton",
                   help="skeleton maps or the Anny body mesh (body models; face models draw the Anny face)")
    p.add_argument("--size", type=int, default=256, help="cell width and height in pixels (default 256)")
    add_threads_argument(p)
    add_motion_input_arguments(p)
    add_bvh_argument(p, "future (observed frames then the future: DIR/sample_1.bvh, ...)")


def run(args: argparse.Namespace) -> int:
    set_threads(args.threads)
    check_at_least("--samples", args.samples)
    settings = SampleSettings(model=args.model, input=args.input, output=args.output, samples=args.samples,
                              observed=args.observed, horizon=args.horizon, start=args.start, seed=args.seed,
                              rigid_bones=args.rigid_bones, npz=args.npz, style=args.style, size=args.size,
                              character=args.character, input_fps=args.input_fps, rig_map=args.rig_map,
                              bvh=args.bvh)
    result = sample_to_files(settings)
    fc = result.forecast
    print(f"wrote {result.video} ({args.samples} futures of {fc.futures.shape[1]} frames after "
          f"{fc.observed.shape[0]} observed, {result.width}x{result.height}, {fc.fps:g} fps)")
    if result.npz is not None:
        print(f"wrote {result.npz}")
    if result.bvh:
        print(f"wrote {len(result.bvh)} BVH files to {args.bvh} ({result.bvh[0].name} ...)")
    return 0
