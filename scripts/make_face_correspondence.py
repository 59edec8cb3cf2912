"""Build ``motion2video/pose/data/face_anny_landmarks.npz``: MediaPipe's 468 face-mesh landmarks on Anny's head.

The neutral default head is rendered frontally at 512 x 512 with the face renderer's close-up camera; the face
mesh runs on the render (detector, then the landmark model twice, the second time on the ROI of its own
landmarks, as in tracking); each landmark's ray is cut with the head's skin triangles
(:func:`motion2video.pose.face_anny.surface_points`). Writes the table and a picture of the landmarks on the
render (``--picture``) to check it.

    PYOPENGL_PLATFORM=osmesa python scripts/make_face_correspondence.py [--picture out/face_anny_landmarks.png]
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.motion import FACE_DIM, FaceMotion
from motion2video.pose.face_anny import CORRESPONDENCE_FILE, skin_triangles, surface_points
from motion2video.pose.facemesh import FaceMesh, detection_roi
from renderers import anny_model
from renderers.face import FaceRenderer, FaceStyle

SIZE = 512


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(CORRESPONDENCE_FILE))
    parser.add_argument("--picture", default=None, help="also write the landmarks drawn on the render (.png)")
    args = parser.parse_args(argv)

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
    corr = surface_points(lm.xy, uvz[:, :2], uvz[:, 2], triangles, out.vertex_visible[0] & on_skin)
    save_npz(args.output, {"vertices": corr.vertices.astype(np.int32), "weights": corr.weights.astype(np.float32)})
    hits = int((corr.weights[:, 0] < 1.0).sum())
    print(f"wrote {args.output}: {len(corr.vertices)} landmarks, {hits} on a skin triangle, "
          f"{len(corr.vertices) - hits} on the nearest visible skin vertex; face presence {lm.score:.3f}")
    if args.picture:
        back = uvz[:, :2][corr.vertices]  # (468, 3, 2)
        drawn = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
        for p, q in zip(lm.xy, np.einsum("lkd,lk->ld", back, corr.weights)):
            cv2.circle(drawn, (int(p[0]), int(p[1])), 2, (0, 160, 0), -1)
            cv2.circle(drawn, (int(q[0]), int(q[1])), 1, (0, 0, 255), -1)
        cv2.imwrite(args.picture, drawn)
        print(f"wrote {args.picture}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
