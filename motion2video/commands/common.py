"""What several sub-commands share: registering a sub-command, common options, and argument checks."""

from __future__ import annotations

import argparse
from typing import Callable

from motion2video.core.errors import InputError

RIGID_BONES_HELP = ("keep the observed bone lengths in every future frame (3D body models: the models' own futures "
                    "stretch and shrink limbs by several per cent; rigid ones are about 3%% further from the truth)")
FIT_VIEW_HELP = ("body frames: when the motion leaves the reference picture (a jump's head above the top), zoom the "
                 "picture out (its border replicated) so that every frame shows the whole person")
THREADS_HELP = ("torch CPU threads (default 1: the small recurrent models and the frame generator ran 3-40x faster "
                "single-threaded on 2 shared cores)")


def add_command(sub: argparse._SubParsersAction, name: str, run: Callable[[argparse.Namespace], int], *,
                description: str, examples: str) -> argparse.ArgumentParser:
    """Register the sub-command ``name`` and return its parser, for the caller to add its arguments.

    Its line in ``motion2video --help`` is :data:`motion2video.cli.SUMMARIES`'s. ``description`` is the paragraph
    at the top of its own ``--help``: a module writes it wrapped in a triple-quoted string, and its line breaks and
    indentation are joined into single spaces here (``--help`` prints it as one line, which the terminal wraps). ``examples`` is the block after the options, printed exactly as written. ``run(args)`` is
    what :func:`motion2video.cli.main` calls with the parsed arguments.
    """
    parser = sub.add_parser(name, description=" ".join(description.split()), epilog=examples,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.set_defaults(run=run)
    return parser


CHARACTER_HELP = ("DeepMimic motion files: their character file (default: humanoid3d_character.txt beside or above "
                  "the motion, ../characters/humanoid3d.txt as in the DeepMimic repository, else the standard "
                  "humanoid3d character shipped with motion2video)")
INPUT_FPS_HELP = ("the input's true frame rate, for files that state none or a wrong one (an OpenPose folder: 25 "
                  "by default; joint arrays .npy: "
                  "20 fps for (T, 22, 3) SMPL/HumanML3D joints, 50 for H36M-17 ones, by default)")


RIG_MAP_HELP = ("BVH files of a rig whose joint names do not tell the body points: a JSON file naming them, body point "
                "-> joint name, e.g. {\"left_hip\": \"Thigh.L\", \"head\": \"Head:end\"} (points: pelvis, right_hip, "
                "right_knee, right_ankle, left_hip, left_knee, left_ankle, spine, thorax, neck, head, left_shoulder, "
                "left_elbow, left_wrist, right_shoulder, right_elbow, right_wrist; the rest still come from the names)")


def add_motion_input_arguments(parser: argparse.ArgumentParser) -> None:
    """``--character FILE``, ``--rig-map FILE`` and ``--input-fps FPS``: how the commands that read motion files
    read them."""
    parser.add_argument("--character", metavar="FILE", default=None, help=CHARACTER_HELP)
    parser.add_argument("--rig-map", metavar="FILE", default=None, help=RIG_MAP_HELP)
    # Where --fps means nothing else (every command but render, whose --fps is the output rate), it is another
    # spelling of --input-fps: an OpenPose folder's true rate is what users pass as --fps.
    names = ["--input-fps"] + (["--fps"] if "--fps" not in parser._option_string_actions else [])
    parser.add_argument(*names, dest="input_fps", metavar="FPS", type=float, default=None, help=INPUT_FPS_HELP)


BVH_HELP = ("also write each {what} as a BVH file into this folder (a standard Hips-rooted hierarchy, metres, "
            "y up, 25 fps; 3D body models only; opens in Blender: File > Import > Motion Capture (.bvh))")


REFERENCE_POSE_HELP = ("the reference image's pose file (default: IMAGE.pose.npz beside the image; without one the pose "
                       "is estimated)")
CROP_PERSON_HELP = ("cut the reference photo to a square around its person (with a margin) first, so that a person "
                    "small in a large photo fills the generator's frame")


def add_reference_photo_arguments(parser: argparse.ArgumentParser) -> None:
    """``--reference-pose FILE``, ``--crop-person`` and ``--fit-view``: how the commands that draw a reference photo
    (``synthesize``, ``transfer``) read it and keep its person in view; ``--reference`` itself is the caller's."""
    parser.add_argument("--reference-pose", default=None, help=REFERENCE_POSE_HELP)
    parser.add_argument("--crop-person", action="store_true", help=CROP_PERSON_HELP)
    parser.add_argument("--fit-view", action="store_true", help=FIT_VIEW_HELP)


def add_bvh_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--bvh DIR``: one BVH file per ``what`` (future, re-enactment, ...)."""
    parser.add_argument("--bvh", metavar="DIR", default=None, help=BVH_HELP.format(what=what))


def add_video_output_arguments(parser: argparse.ArgumentParser, *, npz_help: str) -> None:
    """``--size`` (cell size, default 256), ``-o/--output`` (the video), ``--npz`` (``npz_help`` says what it
    holds) and ``--threads``: the output options of the commands that write a grid of motion cells."""
    parser.add_argument("--size", type=int, default=256, help="cell width and height in pixels (default 256)")
    parser.add_argument("-o", "--output", required=True, help="output video (.mp4 or .gif)")
    parser.add_argument("--npz", default=None, help=npz_help)
    add_threads_argument(parser)


def check_at_least(option: str, value: int, minimum: int = 1) -> None:
    """InputError ``"--option must be >= minimum, got value"`` when ``value`` is below ``minimum``."""
    if value < minimum:
        raise InputError(f"{option} must be >= {minimum}, got {value}")


def add_threads_argument(parser: argparse.ArgumentParser) -> None:
    """``--threads N`` (default 1)."""
    parser.add_argument("--threads", type=int, default=1, help=THREADS_HELP)


def set_threads(threads: int) -> None:
    """Check ``--threads`` and apply it to torch (InputError when below 1)."""
    # Imported here, not at the top: `motion2video doctor` imports this module and must run where torch is missing.
    import torch

    check_at_least("--threads", threads)
    torch.set_num_threads(threads)
