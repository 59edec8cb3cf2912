"""How the mesh generator does when the reference picture's body is *fitted*, as ``synthesize`` fits it.

    python scripts/measure_fitted_reference.py [--model frames-body-mesh-256] [--clips 08_01,13_42,05_14]
        [--lifts guide,pictured] [--rules 0,1,2,3] [--face aligned|fitted] [--hands colour|off]
        [--json out/fitted_reference.json]

``evaluate-frames --poses`` poses the held-out identities by real CMU clips and gives the generator each reference
frame's exact mesh. ``synthesize`` never has it. It lifts the picture's 2D joints to 3D
(:func:`motion2video.frames.mesh_fit.lift_reference`) and poses Anny's default body on them by IK. It keeps as
shown only the vertices that land on the segmented person (:func:`motion2video.frames.mesh_reference.on_person`).

This script scores the same pairs with the reference's mesh replaced by such a fit:

- the body has Anny's default phenotype;
- the person mask for ``on_person`` is BlazePose's segmentation of the rendered reference, as ``synthesize``
  segments a picture (``--mask exact``: the render's silhouette);
- the joints are lifted in one of two ways:
  - "guide": at the depths of another person's pose (the first frame of ``demo_inputs/cmu_walk.npz``, CMU subject
    7, turned and moved onto the reference's hips), as for a pose file with 2D joints only;
  - "pictured": with the pictured pose's own 3D joints in the camera's axes, as for a pose file that carries them
    (``camera_joints``: BlazePose's world landmarks, or a render's known pose).

Four rules decide which fitted vertices lend their colour: the depth test alone, and ``on_person`` with the mask
eroded by 2 px, by 1 px (both at 256) or as it is (``--rules`` picks some). The fitted face is moved onto
BlazePose's eyes as ``synthesize`` moves it (:func:`motion2video.frames.mesh_reference.align_face`; ``--face fitted``
leaves it where the fit puts it). A fitted hand vertex that lands beside the pictured hand samples the pictured hand
(:func:`motion2video.frames.mesh_reference.hand_colour_sources`; ``--hands off`` leaves it). Here that is applied to
the reference's pixels before the surface completion, where ``synthesize`` applies it after (the completion's test of
a thigh under the hand then sees the moved hand). ``hands_colour_de`` is the mean colour difference (CIE76) over the
target's hand pixels (each silhouette pixel labelled by its nearest visible vertex).

The fit is put in by wrapping ``BodyRenderer.render_with_masks`` for the length of a run: it is the one place that
knows each window's camera. About 1.5 minutes per clip and variant on one thread.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

RULES = {
    "depth test alone": None,
    "on_person, mask eroded 2 px at 256 (shipped until 2026-11-26)": 1,
    "on_person, mask eroded 1 px at 256": 0.5,
    "on_person, mask as it is": 0,
}
LIFTS = ("guide", "pictured")


def other_person(reference: np.ndarray) -> np.ndarray:
    """(17, 3) CMU subject 7's first walking pose, turned and moved so its hips lie along the reference's."""
    from motion2video.formats.io import load_motion

    other = load_motion(REPO / "demo_inputs" / "cmu_walk.npz").joints[0].astype(np.float64)

    def heading(joints):
        across = joints[4] - joints[1]  # right hip -> left hip
        return np.arctan2(across[1], across[0])

    turn = heading(reference) - heading(other)
    c, s = np.cos(turn), np.sin(turn)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return (other - other[0]) @ rot.T + reference[0]


def person_found(out, source: str):
    """The reference frame's person as synthesize finds it in a picture (BlazePose's
    :class:`motion2video.stages.reference.ReferencePerson`: mask, eyes), its mask replaced by the render's exact
    silhouette with ``source`` "exact"; None when BlazePose finds nobody."""
    from dataclasses import replace

    from motion2video.stages.frames import reference_person

    found = reference_person(out.frames[0])
    if found is None or source != "exact":
        return found
    return replace(found, mask=np.asarray(out.masks[0], np.float32))


def fitted_renders(rule: int | None, lift: str, mask: str = "blazepose", face: str = "aligned", with_clip: bool = True,
                   hands: str = "colour"):
    """A wrapper of ``BodyRenderer.render_with_masks`` whose first frame's vertices are those of a fitted body."""
    import renderers.body as body
    from renderers import anny_model
    from motion2video.core.camera import project
    from motion2video.frames import mesh_fit, mesh_reference

    plain = body.BodyRenderer.render_with_masks

    def render(self, motion, **kwargs):
        out = plain(self, motion, **kwargs)
        if out.vertex_uv is None:
            return out
        camera = out.camera
        points = project(motion.joints[0], camera)[:, :2]
        reference = np.asarray(motion.joints[0], np.float64)
        pictured = (reference - np.asarray(camera.position)) @ camera.axes().T if lift == "pictured" else None
        lifted = mesh_fit.lift_reference(points, other_person(reference), camera, 1.0, np.zeros(2),
                                         pictured=pictured)
        # synthesize poses the reference together with the clip (one body size, the clip's neck turn): the window's
        # other frames stand in for the clip
        posed = np.concatenate([lifted[None], np.asarray(motion.joints[1:], np.float64)]) if with_clip else lifted[None]
        track = mesh_fit.render_mesh_track(posed, phenotype={}, camera=camera, transform=(1.0, np.zeros(2)),
                                           size=camera.width, clear_arms=np.arange(len(posed)) > 0)
        person, rest = person_found(out, mask), anny_model.anny_rest({})
        uv, shown = mesh_reference.reference_sampling(  # as synthesize does (stages.mesh_frames.mesh_video)
            track.uv[0], track.visible[0], track.masks[0], person, rest=rest, edge_px=rule, align=face == "aligned")
        if hands == "colour" and person is not None:  # synthesize applies them after the surface completion
            sources = mesh_reference.hand_colour_sources(uv, shown, out.frames[0], person.hands, person.hand_visibility,
                                                         rest=rest)
            uv = uv if sources is None else uv[sources]
        out.vertex_uv[0] = uv
        out.vertex_visible[0] = shown
        return out

    return plain, render


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="frames-body-mesh-256")
    parser.add_argument("--clips", default="08_01,13_42,05_14", help="CMU clips (held out from the frame training)")
    parser.add_argument("--mocap", default=str(REPO.parent / "shared" / "data" / "mocap"))
    parser.add_argument("--json", default=None)
    parser.add_argument("--mask", choices=("blazepose", "exact"), default="blazepose",
                        help="the reference person for on_person: BlazePose's segmentation (as synthesize) or the "
                        "render's exact silhouette")
    parser.add_argument("--lifts", default=",".join(LIFTS), help="guide, pictured or both")
    parser.add_argument("--rules", default=",".join(str(i) for i in range(len(RULES))),
                        help="which of the shown-vertex rules, by index (0: depth test alone, 1: eroded 2 px, "
                        "2: eroded 1 px, 3: the mask as it is, shipped)")
    parser.add_argument("--face", choices=("aligned", "fitted"), default="aligned",
                        help="the fitted face moved onto BlazePose's eyes (frames.mesh_reference.align_face, as "
                        "synthesize does) or left where the fit puts it")
    parser.add_argument("--hands", choices=("colour", "off"), default="colour",
                        help="a fitted hand vertex beside the pictured hand samples the pictured hand "
                        "(frames.mesh_reference.hand_colour_sources, as synthesize does), or not")
    parser.add_argument("--posed", choices=("with-clip", "alone"), default="with-clip",
                        help="pose the fitted reference together with the window's other frames, as synthesize poses "
                        "it with the clip, or on its own (before 2026-11-26, later)")
    args = parser.parse_args(argv)

    import torch

    import renderers.body as body
    from motion2video.frames.checkpoint import load_frame_model
    from motion2video.frames.evaluate import evaluate_sequences, vertex_region_masks
    from renderers import anny_model
    from motion2video.frames.poses import PoseEvalSpec, load_body_clips, render_posed_sequences

    torch.set_num_threads(1)
    model = load_frame_model(args.model).model
    results: dict[str, dict[str, dict[str, float]]] = {}
    for clip in args.clips.split(","):
        clips = load_body_clips(str(Path(args.mocap) / "cmu" / f"{clip}.bvh"))
        rules = [list(RULES.items())[int(i)] for i in args.rules.split(",")]
        for lift, (rule_name, rule) in [(lift, item) for lift in args.lifts.split(",") for item in rules]:
            name = f"{lift} | {rule_name} | face {args.face} | hands {args.hands} | posed {args.posed}"
            plain, render = fitted_renders(rule, lift, args.mask, args.face, args.posed == "with-clip", args.hands)
            body.BodyRenderer.render_with_masks = render
            try:
                posed = render_posed_sequences(clips, PoseEvalSpec.for_size(model.config.image_size,
                                                                            windows_per_clip=4))
            finally:
                body.BodyRenderer.render_with_masks = plain
            seqs = posed.sequences
            frames = seqs.masks.shape[0] * seqs.masks.shape[1]  # every frame of every window
            hand_labels = (anny_model.hand_vertices("L") | anny_model.hand_vertices("R")).astype(np.int64)
            hands = vertex_region_masks(seqs.vertex_uv.reshape(frames, -1, 2).astype(np.float64),
                                        seqs.vertex_visible.reshape(frames, -1),
                                        seqs.masks.reshape(frames, *seqs.masks.shape[2:]),
                                        hand_labels, {"hands": 1})["hands"].reshape(seqs.masks.shape)
            scores = evaluate_sequences(model, seqs, head_masks=posed.head_masks,
                                        region_masks={"hands": hands}).results["generator"]
            row = {k: round(float(v), 3) for k, v in scores.person.items()
                   if k in ("person_psnr", "head_psnr", "person_sharpness", "hands_colour_de")}
            row["psnr"] = round(scores.psnr, 3)
            results.setdefault(clip, {})[name] = row
            print(f"{clip} | {name} | {row}", flush=True)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"model": args.model, "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
