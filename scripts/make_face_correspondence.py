"""Build ``motion2video/pose/data/face_anny_landmarks.npz``: the tracked face points on Anny's head (and, with
``--shapes``, ``face_shape_targets.npz``: the face shape targets of :mod:`motion2video.pose.face_shape`).

The neutral default head is rendered frontally at 512 x 512 with the face renderer's close-up camera; the face
mesh runs on the render (detector, then the landmark model twice, the second time on the ROI of its own
landmarks, as in tracking); each landmark's ray is cut with the head's skin triangles
(:func:`motion2video.pose.face_anny.surface_points`); the two iris centres are the eyeballs' front-most
vertices. Writes the table and a picture of the landmarks on the
render (``--picture``) to check it.

    PYOPENGL_PLATFORM=osmesa python scripts/make_face_correspondence.py [--picture out/face_anny_landmarks.png]
    python scripts/make_face_correspondence.py --shapes

``--shapes`` builds Anny once with its local changes (MakeHuman's MPFB2 targets, CC0) and keeps the targets named by
:data:`motion2video.pose.face_shape.SHAPE_PAIRS`, a left and a right target summed where the name starts with "*".
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.motion import FACE_DIM, FaceMotion
from motion2video.pose.face_anny import CORRESPONDENCE_FILE, skin_triangles, surface_points
from motion2video.pose.face_shape import SHAPE_FILE, SHAPE_PAIRS, target_names
from motion2video.pose.facemesh import FaceMesh, detection_roi
from renderers import anny_model
from renderers.face import FaceRenderer, FaceStyle, face_landmark_vertices

SIZE = 512


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(CORRESPONDENCE_FILE))
    parser.add_argument("--picture", default=None, help="also write the landmarks drawn on the render (.png)")
    parser.add_argument("--shapes", action="store_true", help=f"build {SHAPE_FILE.name} instead")
    args = parser.parse_args(argv)
    if args.shapes:
        return write_shape_targets(SHAPE_FILE)

    renderer = FaceRenderer(FaceStyle(size=(SIZE, SIZE), background=(200, 200, 200)))
    face = FaceMotion(np.zeros((1, FACE_DIM)), 30.0)
    out = renderer.render_with_masks(face, vertices=True)
    image = out.frames[0]
    mesh = FaceMesh()
    detections = mesh.detect(image)
    if not detections:
        raise SystemExit("the face detector finds no face on the Anny render")
    lm = mesh.landmarks(image, detection_roi(detections[0]))
    lm = mesh.landmarks(image, lm.next_roi())
    rest = anny_model.anny_rest()
    uvz = out.camera.project(rest.vertices)  # (V, 3)
    triangles = skin_triangles()
    on_skin = np.zeros(len(rest.vertices), bool)
    on_skin[triangles.ravel()] = True
    mesh = surface_points(lm.xy, uvz[:, :2], uvz[:, 2], triangles, out.vertex_visible[0] & on_skin)
    pupils = face_landmark_vertices(rest)[:2]  # the right and left eyeballs' front-most vertices
    vertices = np.concatenate([mesh.vertices, np.stack([pupils, pupils, pupils], axis=1)])  # (470, 3)
    weights = np.concatenate([mesh.weights, np.tile([1.0, 0.0, 0.0], (2, 1))])
    save_npz(args.output, {"vertices": vertices.astype(np.int32), "weights": weights.astype(np.float32)})
    hits = int((mesh.weights[:, 0] < 1.0).sum())
    iris_gap = np.linalg.norm(lm.iris - uvz[pupils, :2], axis=1)
    print(f"wrote {args.output}: {len(mesh.vertices)} mesh landmarks, {hits} on a skin triangle, "
          f"{len(mesh.vertices) - hits} on the nearest visible skin vertex, and the 2 pupils ({iris_gap.max():.1f} "
          f"pixels from the tracked iris centres); face presence {lm.score:.3f}")
    if args.picture:
        back = uvz[:, :2][vertices]  # (470, 3, 2)
        drawn = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
        for p, q in zip(lm.points(), np.einsum("lkd,lk->ld", back, weights)):
            cv2.circle(drawn, (int(p[0]), int(p[1])), 2, (0, 160, 0), -1)
            cv2.circle(drawn, (int(q[0]), int(q[1])), 1, (0, 0, 255), -1)
        cv2.imwrite(args.picture, drawn)
        print(f"wrote {args.picture}")
    return 0


def write_shape_targets(path) -> int:
    """Write the face shape targets (see the module docstring) to ``path``."""
    import anny
    import torch

    with torch.no_grad():
        model = anny.Anny(facial_actions="none", local_changes="default")
    labels = list(model.blendshape_labels)
    shapes = model.blendshapes.double().cpu().numpy()  # (S, V, 3)

    def target(name: str) -> np.ndarray:
        if name.startswith("*"):
            return sum(shapes[labels.index(f"local_change:{side}-{name[1:]}")] for side in "lr")
        return shapes[labels.index(f"local_change:{name}")]

    table = np.stack([target(name) for pair in SHAPE_PAIRS for name in pair]).astype(np.float32)  # (K, V, 3)
    save_npz(path, {"names": np.array(target_names()), "shapes": table}, compressed=True)
    print(f"wrote {path}: {len(table)} targets, largest displacement {1000 * np.abs(table).max():.1f} mm")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
