"""`motion2video pose`: the pose of a person in a photo (reference pose file) or a video (motion npz)."""

from __future__ import annotations

import argparse

import numpy as np

from motion2video.apps.pose import FacePoseFile, PoseSettings, VideoPoseFile, estimate_pose_file
from motion2video.commands.common import add_command
from motion2video.core.errors import InputError
from motion2video.pose.estimate import parse_person
from motion2video.stages.people import frame_ranges

DESCRIPTION = """\
Estimate the pose of one person with the bundled BlazePose full model (no download). A photo gives its
reference pose file (IMAGE.pose.npz: the canonical H36M-17 joints in its pixels), which synthesize and
transfer read beside the image. A video (.mp4, .avi, .mov, ...) gives a motion .npz at the video's own frame
rate: 3D joints (metres, z up, floor at 0; every motion command reads them), the 2D joints in the video's
pixels (joints_2d), per-joint confidence, which frames were interpolated and which the tracker was unsure of
(unsure: printed, and a boolean per frame). Frames without the person at the ends are trimmed; gaps inside are
interpolated (the count is printed). --person picks one of several people: the largest (default) or an index
counted left to right in the first frame with people; a video follows that ONE person in every frame by the
colours of their torso and the motion of their pelvis, so a passer-by is not taken for them. The 3D root moves
in depth with the person's apparent size (a 60 degree field of view across the frame is assumed). --overlay
draws the joints on the input so you can check them. A video's track is cached by the file's contents (in
~/.cache/motion2video, as every command that reads a video caches it), so a second run reads it back.

--face tracks a face video instead (MediaPipe's face detector, 468-point face mesh and eye model, bundled) and
fits the Anny head to every frame: the output is a face motion .npz (the 52 ARKit coefficients and the head pose per
frame, the file every face command reads), with the 2D landmarks, a per-frame confidence and the fit's
re-projection error beside them. Frames without the face at the ends are trimmed; gaps inside are
interpolated. --overlay then draws the tracked landmarks (green) and the fitted head's (red) on the video.
"""

EXAMPLES = """\
examples:
  motion2video pose ../shared/data/photos/skier.jpg -o out/skier.pose.npz --overlay out/skier_pose.png
  motion2video pose ../shared/data/photos/three_walking.jpg -o out/walker.pose.npz --person 0
  motion2video pose ../shared/data/video/dancer.avi -o out/dancer.npz --overlay out/dancer_pose.mp4
  motion2video pose --face ../shared/data/video/face_talking_woman.mp4 -o out/woman_face.npz
  motion2video render out/woman_face.npz --style face -o out/woman_face.mp4
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "pose", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("input", help="a photo (.png, .jpg, ...) or a video (.mp4, .avi, .mov, .mkv, .webm)")
    p.add_argument("-o", "--output", required=True,
                   help="output .npz: a photo's reference pose file (name it IMAGE.pose.npz beside the image for "
                        "synthesize to find it) or a video's motion file")
    p.add_argument("--person", default="largest",
                   help="which person: 'largest' (default) or an index counted left to right (0 = leftmost)")
    p.add_argument("--face", action="store_true",
                   help="the input is a face video: write its face motion (52 ARKit coefficients + head pose)")
    p.add_argument("--overlay", default=None,
                   help="also write the joints drawn on the input: a .png for a photo, an .mp4 for a video")


def run(args: argparse.Namespace) -> int:
    try:
        person = parse_person(args.person)
    except ValueError as err:
        raise InputError(str(err)) from None
    result = estimate_pose_file(PoseSettings(input=args.input, output=args.output, person=person,
                                             overlay=args.overlay, face=args.face), note=print)
    if isinstance(result, FacePoseFile):
        track = result.track
        trimmed_end = track.video_frames - track.first_frame - track.num_frames
        print(f"wrote {result.output} ({track.num_frames} frames at {track.motion.fps:g} fps, "
              f"{track.width}x{track.height}; {track.gaps} gap frames interpolated; trimmed {track.first_frame} "
              f"frames at the start and {trimmed_end} at the end of {track.video_frames}; landmarks re-projected "
              f"from the fitted head within {100 * float(np.median(track.relative_error())):.2f}% of the face size "
              "(median))")
    elif isinstance(result, VideoPoseFile):
        pose = result.pose
        trimmed_end = pose.video_frames - pose.first_frame - pose.num_frames
        print(f"wrote {result.output} ({pose.num_frames} frames at {pose.fps:g} fps, {pose.width}x{pose.height}; "
              f"{pose.gaps} gap frames interpolated; trimmed {pose.first_frame} frames at the start and "
              f"{trimmed_end} at the end of {pose.video_frames})")
        if pose.unsure_frames:
            print(f"unsure of the person in {pose.unsure_frames} frames (video frames "
                  f"{frame_ranges(pose.unsure, pose.first_frame)}): another person near them, a jump or a "
                  "low presence; gaps among them are interpolated (the npz's `unsure` marks them all)")
        else:
            print("followed one person in every frame: no unsure frames")
    else:
        photo = result.photo
        which = "the largest" if person == "largest" else f"person {person} from the left"
        print(f"found {photo.people} {'person' if photo.people == 1 else 'people'}; took {which}")
        print(f"wrote {result.output} (17 joints in {photo.pose.width}x{photo.pose.height} pixels, mean confidence "
              f"{photo.pose.confidence.mean():.2f})")
        if result.output.resolve() != result.expected.resolve():
            print(f"note: synthesize and transfer look for {result.expected.name} beside the image; "
                  f"pass --reference-pose {result.output} to use this file")
    if result.overlay is not None:
        print(f"wrote {result.overlay}")
    return 0
