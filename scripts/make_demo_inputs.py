"""Write the committed demo inputs: procedural body and face motions as .npz, real CMU excerpts, and their README.

    .venv/bin/python scripts/make_demo_inputs.py --out demo_inputs
    .venv/bin/python scripts/make_demo_inputs.py --out demo_inputs --real-mocap ../shared/data/mocap  # + CMU clips
    .venv/bin/python scripts/make_demo_inputs.py --out demo_inputs --reference   # + reference images

Every file is a pure function of the tables below (fixed seeds, fixed excerpts), so running the script again
gives the same arrays. ``--real-mocap`` also cuts the real CMU excerpts (:data:`REAL_DEMOS`) out of the mocap
folder (read with ``load_motion`` at 25 fps, so on the canonical skeleton). ``--reference`` also renders the
reference appearance images with the Anny renderers (``renderers/body.py`` BodyRenderer,
``renderers/face.py`` FaceRenderer).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

from motion2video.data.face_dynamics import generate_face
from motion2video.data.procedural import ModeSpec, generate
from motion2video.core.errors import InputError
from motion2video.formats.npz import save_face_npz, save_motion_npz

FPS = 25.0
SEED = 0
# file name -> (modes with seconds, description)
BODY_DEMOS: dict[str, tuple[tuple[tuple[str, float] | ModeSpec, ...], str]] = {
    "walk_to_run.npz": ((("walk", 2.4), ("run", 2.4)), "walks forward, then speeds up into a run"),
    "wave.npz": ((("stand", 0.8), ("wave", 3.2)), "stands, then waves with the right hand"),
    "jump.npz": ((("stand", 0.8), ModeSpec("jump", 2.5, phase=0.0), ("stand", 0.8)),
                 "stands, crouches and jumps in place twice, stands"),
    "squat_punch_turn.npz": ((("squat", 2.4), ("punch", 2.0), ("turn", 2.0)),
                             "a squat, a left-right punch combination, then turns in place to its left"),
}
FACE_DEMOS: dict[str, tuple[tuple[tuple[str, float], ...], str]] = {
    "smile.npz": ((("neutral", 1.0), ("smile", 2.0)), "neutral face breaking into a smile"),
    "blink_talk.npz": ((("blink", 1.6), ("talk", 3.2)), "rapid blinks, then talking (irregular syllables)"),
    "nod_turn.npz": ((("nod", 2.0), ("turn", 3.2)), "nods, then turns the head left and right"),
}
REFERENCE_SIZES = (256, 128)
# Real CMU excerpts: file name -> (clip in the mocap folder, first frame and frames at FPS, description). Both
# clips are held out of the frame generator's training data (motion2video.generator.specs.is_test_clip).
REAL_DEMOS: dict[str, tuple[str, int, int, str]] = {
    "cmu_walk.npz": ("cmu/07_04.bvh", 0, 90, "CMU subject 7, trial 4 (\"slow walk\"): walks forward about 3 m"),
    "cmu_jump.npz": ("cmu/16_02.bvh", 20, 75, "CMU subject 16, trial 2 (\"jump\"): stands, crouches, jumps up "
                     "in place (pelvis 0.5 m higher at the top), lands and stands"),
}


COMMAND = ".venv/bin/python scripts/make_demo_inputs.py --out demo_inputs"
REAL_COMMAND = COMMAND + " --real-mocap ../shared/data/mocap"


def readme_text() -> str:
    """The README of the demo folder (lists every file and the command that made it)."""
    lines = [
        "# Demo inputs",
        "",
        "Small procedural motions for demos and tests, written by `scripts/make_demo_inputs.py` from",
        "`motion2video.data.procedural.generate` (body) and `motion2video.data.face_dynamics.generate_face`",
        f"(face), at {FPS:g} fps with seed {SEED}. Regenerate them (same arrays) with:",
        "",
        "```",
        COMMAND,
        "```",
        "",
        "## Body motions (canonical H36M-17, world metres, z up, facing -y at the start)",
        "",
        "Keys: `joints` (T, 17, 3) float32, `fps`, `skeleton` (`h36m-17`), `label` (modes joined by `>`).",
        "",
        "| file | modes (seconds) | frames | content |",
        "| --- | --- | --- | --- |",
    ]
    for name, (modes, what) in BODY_DEMOS.items():
        lines.append(f"| `{name}` | {_modes_text(modes)} | {_frames(modes)} | {what} |")
    lines += [
        "",
        "## Real motion capture (CMU Graphics Lab Motion Capture Database)",
        "",
        "Excerpts of two real captures, read with `motion2video.formats.io.load_motion` (so on the canonical",
        f"skeleton) at {FPS:g} fps and trimmed; same keys as the body motions above, with the source in `label`.",
        "Regenerate them (same arrays) from the mocap folder beside the repository with:",
        "",
        "```",
        REAL_COMMAND,
        "```",
        "",
        "| file | source clip | frames (at 25 fps) | content |",
        "| --- | --- | --- | --- |",
    ]
    for name, (clip, start, frames, what) in REAL_DEMOS.items():
        lines.append(f"| `{name}` | `{clip}` | {start}-{start + frames - 1} ({frames}) | {what} |")
    lines += [
        "",
        "Terms: CMU places no restrictions on the use of the original dataset (\"free for use in research and",
        "commercial projects worldwide\"; later wording: \"You may include this data in commercially-sold products,",
        "but you may not resell this data directly, even in converted form\"), so these excerpts may ship inside a",
        "product; do not sell the clips themselves. Credit, as CMU asks: *The data used in this project was obtained",
        "from mocap.cs.cmu.edu. The database was created with funding from NSF EIA-0196217.* (The licence evidence",
        "is kept beside the clips, in `LICENSE-CMU.txt` of the mocap folder.)",
        "",
        "## Face motions (52 ARKit coefficients + head axis-angle + head translation)",
        "",
        "Keys: `face` (T, 58) float32, `fps`, `identity` (JSON of Anny phenotype values; `{}` = Anny's",
        "defaults), `label`. Head pose convention: see `motion2video/data/face_dynamics.py`.",
        "",
        "| file | modes (seconds) | frames | content |",
        "| --- | --- | --- | --- |",
    ]
    for name, (modes, what) in FACE_DEMOS.items():
        lines.append(f"| `{name}` | {_modes_text(modes)} | {_frames(modes)} | {what} |")
    lines += [
        "",
        "## Reference appearance images",
        "",
        "`reference_body.png` (256x256) and `reference_body_128.png` (a frame of `walk_to_run.npz` rendered",
        "with the Anny body renderer) and `reference_face.png` (the neutral first frame of `smile.npz`, Anny",
        "face renderer) come from",
        "`scripts/make_demo_inputs.py --reference`; they need the Anny model cache and take a while, so the",
        "plain command above does not make them. Beside each image, `<image>.pose.npz` holds the pose it shows",
        "(body: `points` (17, 2) joints in its pixels and `camera_joints` (17, 3), the same joints in 3D in the",
        "camera's axes; face: `face` (58,) params, `identity` and the camera that rendered it), which",
        "`motion2video synthesize` uses as the reference structure.",
        "",
        "- `jobs.jsonl`: three batch jobs over these files (docs/cli.md's `motion2video batch demo_inputs/jobs.jsonl` "
        "example; input paths are relative to the repository root, where the command runs).",
        "",
    ]
    return "\n".join(lines)


def _pairs(modes) -> list[tuple[str, float]]:
    return [(m.mode, m.seconds) if isinstance(m, ModeSpec) else m for m in modes]


def _modes_text(modes) -> str:
    return " > ".join(f"{m} ({s:g})" for m, s in _pairs(modes))


def _frames(modes) -> int:
    return int(round(sum(s for _, s in _pairs(modes)) * FPS))


def write_motions(out: Path) -> list[Path]:
    """Write every body and face demo and the README into ``out``. Returns the written paths."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, (modes, _) in BODY_DEMOS.items():
        written.append(save_motion_npz(generate(list(modes), fps=FPS, seed=SEED), out / name))
    for name, (modes, _) in FACE_DEMOS.items():
        written.append(save_face_npz(generate_face(list(modes), fps=FPS, seed=SEED), out / name))
    readme = out / "README.md"
    readme.write_text(readme_text(), encoding="utf-8")
    written.append(readme)
    return written


def real_motion(mocap: Path, name: str):
    """The excerpt ``name`` of :data:`REAL_DEMOS` cut out of the mocap folder ``mocap`` (a Motion at FPS)."""
    from motion2video.core.motion import Motion
    from motion2video.formats.io import load_motion

    clip, start, frames, _ = REAL_DEMOS[name]
    motion = load_motion(mocap / clip, target_fps=FPS)
    if not isinstance(motion, Motion) or start + frames > motion.num_frames:
        raise InputError(f"expected a body capture of at least {start + frames} frames at {FPS:g} fps",
                         mocap / clip)
    cut = motion.slice(start, frames)
    return Motion(cut.joints.astype("float32"), FPS, cut.skeleton, cut.source,
                  f"CMU {clip} frames {start}-{start + frames - 1} at {FPS:g} fps")


def write_real_motions(out: Path, mocap: Path) -> list[Path]:
    """Write the real CMU excerpts (:data:`REAL_DEMOS`) from the mocap folder ``mocap`` into ``out``."""
    if not (mocap / "manifest.csv").is_file():
        raise InputError("not a mocap folder (no manifest.csv): give the folder holding cmu/ and manifest.csv",
                         mocap)
    out.mkdir(parents=True, exist_ok=True)
    return [save_motion_npz(real_motion(mocap, name), out / name) for name in REAL_DEMOS]


def _has_module(name: str) -> bool:
    return importlib.util.find_spec(name) is not None


def write_references(out: Path) -> list[Path]:
    """Render the reference appearance images. Raises InputError when a renderer is not available."""
    import imageio.v3 as iio

    if not _has_module("renderers.body"):
        raise InputError("--reference needs renderers/body.py (BodyRenderer), which is not available")
    from renderers.body import BodyRenderer, BodyStyle

    walk = generate(list(BODY_DEMOS["walk_to_run.npz"][0]), fps=FPS, seed=SEED).slice(0, 1)
    written = []
    for size in REFERENCE_SIZES:
        with BodyRenderer(BodyStyle(size=(size, size))) as renderer:
            frame = renderer.render(walk)[0]
        path = out / ("reference_body.png" if size == REFERENCE_SIZES[0] else f"reference_body_{size}.png")
        iio.imwrite(path, frame)
        written.append(path)
    if not _has_module("renderers.face"):
        raise InputError("--reference: renderers/face.py (FaceRenderer) is not available, so "
                         f"reference_face.png was not written (the body references were: {len(written)} files)")
    from renderers.face import FaceRenderer, FaceStyle

    face = generate_face(list(FACE_DEMOS["smile.npz"][0]), fps=FPS, seed=SEED)
    with FaceRenderer(FaceStyle(size=(REFERENCE_SIZES[0], REFERENCE_SIZES[0]))) as renderer:
        frame = renderer.render(face.slice(0, 1))[0]  # the neutral start
    path = out / "reference_face.png"
    iio.imwrite(path, frame)
    written.append(path)
    return written + write_reference_poses(out)


def write_reference_poses(out: Path) -> list[Path]:
    """Write ``<image>.pose.npz`` beside each reference image: the pose it shows, in its pixels (body
    joints, and the 3D joints in the camera's axes) or with the camera that rendered it (face), so ``synthesize``
    knows the reference structure
    exactly (:mod:`motion2video.apps.synthesize`). Needs the Anny renderers; renders one frame per body size."""
    from motion2video.stages.reference import ReferencePose, reference_pose_path, save_reference_pose
    from renderers.body import BodyRenderer, BodyStyle
    from motion2video.core.camera import project
    from renderers.face import FaceRenderer, FaceStyle

    walk = generate(list(BODY_DEMOS["walk_to_run.npz"][0]), fps=FPS, seed=SEED).slice(0, 1)
    written = []
    for size in REFERENCE_SIZES:
        with BodyRenderer(BodyStyle(size=(size, size))) as renderer:
            camera = renderer.render_with_masks(walk).camera
        image = out / ("reference_body.png" if size == REFERENCE_SIZES[0] else f"reference_body_{size}.png")
        joints = np.asarray(walk.joints[0], np.float64)
        pose = ReferencePose("body", size, size, points=project(joints, camera)[:, :2],
                             camera_joints=(joints - np.asarray(camera.position)) @ camera.axes().T)
        written.append(save_reference_pose(reference_pose_path(image), pose))
    face = generate_face(list(FACE_DEMOS["smile.npz"][0]), fps=FPS, seed=SEED).slice(0, 1)
    size = REFERENCE_SIZES[0]
    with FaceRenderer(FaceStyle(size=(size, size))) as renderer:
        camera = renderer.camera_for(face)
    pose = ReferencePose("face", size, size, face=face.params[0], identity=dict(face.identity), camera=camera)
    written.append(save_reference_pose(reference_pose_path(out / "reference_face.png"), pose))
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path("demo_inputs"), help="output folder (default demo_inputs)")
    parser.add_argument("--real-mocap", type=Path, default=None, metavar="FOLDER",
                        help="also cut the real CMU excerpts out of this mocap folder (../shared/data/mocap)")
    parser.add_argument("--reference", action="store_true",
                        help="also render reference_body.png / reference_body_128.png / reference_face.png")
    args = parser.parse_args(argv)
    try:
        paths = write_motions(args.out)
        if args.real_mocap is not None:
            paths += write_real_motions(args.out, args.real_mocap)
        if args.reference:
            paths += write_references(args.out)
    except InputError as err:
        print(f"make_demo_inputs: error: {err}", file=sys.stderr)
        return 2
    total = sum(p.stat().st_size for p in paths)
    print(f"wrote {len(paths)} files to {args.out} ({total / 1024:.0f} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
