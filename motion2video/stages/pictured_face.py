"""The face a reference photo shows, found at the photo's own resolution, to draw over the generated heads.

The body pose puts the head; the face detector (BlazeFace, :mod:`motion2video.pose.facemesh`) looks for a face in a
square around it, cut from the photo as the user gave it (not the picture resized for the generator, where a
full-body photo's face is some 20 px tall), and the face mesh's landmarks on that face give its matte
(:func:`motion2video.generator.head_paste.face_matte`). A person photographed from behind shows no face: nothing
is found, and the generator's own head stays.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from motion2video.core.camera import affine_matrix
from motion2video.core.skeletons import HEAD, NECK, THORAX
from motion2video.generator.head_paste import (
    HeadMoves, compose_affine, face_matte, face_triangles, head_moves, lay_moved_face, pixel_index_affine,
)

# The square searched for the face: centred between the nose and head joints, this many times the thorax-to-head
# distance (about a head's height: the face fills a third of it, as BlazeFace's short-range model expects).
SEARCH_SCALE = 3.0
MIN_SEARCH_PX = 32  # a smaller square holds no face the landmark model can read
# A detection counts only when its centre lies within this share of the square's side from the square's centre
# (a face beside the head, another person's, is not this person's).
MAX_OFFSET = 0.3


@dataclass(frozen=True)
class PicturedFace:
    """A face cut from a reference photo.

    Attributes:
        image: (h, w, 3) uint8 the square around the head at the photo's own resolution.
        matte: (h, w) float32 in [0, 1] the face in it (:func:`~motion2video.generator.head_paste.face_matte`).
        to_reference: (2, 3) affine map from ``image`` pixels to the reference picture's (the generator's input).
        landmarks: (468, 2) the face mesh's landmarks in ``image`` pixels.
        score: the face mesh's face-presence probability.
    """

    image: np.ndarray
    matte: np.ndarray
    to_reference: np.ndarray
    landmarks: np.ndarray
    score: float


def face_mesh():
    """The process's shared :class:`motion2video.pose.facemesh.FaceMesh` without the eye model (the matte needs the
    face's outline only)."""
    from motion2video.pose.facemesh import shared_face_mesh

    return shared_face_mesh(num_threads=1, refine_eyes=False)


def head_square(points: np.ndarray) -> tuple[int, int, int]:
    """(x0, y0, side) integer square around the head of (17, 2) canonical joints (pixels): centred between the nose
    and head joints, :data:`SEARCH_SCALE` times the thorax-to-head distance (at least :data:`MIN_SEARCH_PX`)."""
    pts = np.asarray(points, np.float64)
    centre = 0.5 * (pts[NECK] + pts[HEAD])
    side = max(MIN_SEARCH_PX, int(round(SEARCH_SCALE * np.linalg.norm(pts[HEAD] - pts[THORAX]))))
    x0, y0 = (np.round(centre - side / 2)).astype(int)
    return int(x0), int(y0), side


def cut_square(picture: np.ndarray, square: tuple[int, int, int]) -> np.ndarray:
    """(side, side, 3) the square (x0, y0, side) of a picture, its border replicated where the square leaves it."""
    x0, y0, side = square
    return cv2.warpAffine(picture, affine_matrix(1.0, np.array([-x0, -y0], np.float64)), (side, side),
                          flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)


def pictured_face(picture: np.ndarray, points: np.ndarray, *, to_reference: np.ndarray | None = None,
                  person: np.ndarray | None = None) -> PicturedFace | None:
    """The face of the person whose body joints are ``points``, or None when the detector finds no face near the
    head (a person seen from behind, a face too small to read) or the face mesh doubts it (presence below
    :data:`motion2video.pose.facemesh.MIN_PRESENCE`).

    Args:
        picture: (H, W, 3) uint8 the photo at its own resolution.
        points: (17, 2) the body's canonical joints in ``picture`` pixels.
        to_reference: (2, 3) affine map from ``picture`` pixels to the reference picture's (None: the same).
        person: (H_ref, W_ref) float in [0, 1] the person in the reference picture's pixels (a segmentation or the
            picture's alpha), or None: the matte keeps only the person, a reference pixel inside its outline (the
            landmarks' hull of a face turned aside reaches past the far cheek onto the background, and the outline's
            pixels at the reference's resolution are half background).
    """
    from motion2video.pose.facemesh import MIN_PRESENCE, detection_roi

    square = head_square(points)
    x0, y0, side = square
    crop = np.ascontiguousarray(cut_square(np.asarray(picture, np.uint8), square))
    mesh = face_mesh()
    centre = np.array([side / 2, side / 2])
    near = [d for d in mesh.detect(crop) if np.linalg.norm(d.centre - centre) <= MAX_OFFSET * side]
    if not near:
        return None
    found = mesh.landmarks(crop, detection_roi(near[0]))
    if found.score < MIN_PRESENCE:
        return None
    to_ref = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]) if to_reference is None else np.asarray(to_reference,
                                                                                                  np.float64)
    crop_to_picture = np.array([[1.0, 0.0, x0], [0.0, 1.0, y0]])
    to_ref = np.vstack([to_ref, [0, 0, 1]]) @ np.vstack([crop_to_picture, [0, 0, 1]])
    matte = face_matte(found.xy, crop.shape[:2])
    if person is not None:  # the person's mask a pixel inside its outline, from the reference's pixels to the square's
        core = cv2.erode((np.asarray(person) > 0.5).astype(np.uint8), np.ones((3, 3), np.uint8)).astype(np.float32)
        back = cv2.invertAffineTransform(pixel_index_affine(to_ref[:2]))
        matte = matte * cv2.warpAffine(core, back, (side, side), flags=cv2.INTER_LINEAR,
                                       borderMode=cv2.BORDER_REPLICATE)
    return PicturedFace(crop, matte.astype(np.float32), to_ref[:2], found.xy, found.score)


def reference_face(reference) -> PicturedFace | None:
    """The face of a body :class:`motion2video.stages.reference.Reference`, found in its source picture (the photo at
    its own resolution, :attr:`~motion2video.stages.reference.Reference.source`); None without a pose or a face."""
    if reference.pose is None or reference.pose.kind != "body":
        return None
    size = reference.image.shape[0]
    points = np.asarray(reference.pose.points, np.float64) * (size / reference.pose.width, size / reference.pose.height)
    k, offset = reference.source_scale, np.asarray(reference.source_offset, np.float64)
    picture = reference.image if reference.source is None else reference.source
    to_reference = np.array([[k, 0.0, offset[0]], [0.0, k, offset[1]]])
    person = None if reference.person is None else reference.person.mask
    return pictured_face(picture, (points - offset) / k, to_reference=to_reference, person=person)


def landmarks_in_reference(face: PicturedFace) -> np.ndarray:
    """(468, 2) the face's landmarks in the reference picture's pixels."""
    return face.landmarks @ face.to_reference[:, :2].T + face.to_reference[:, 2]


@lru_cache(maxsize=1)
def landmark_triangles() -> np.ndarray:
    """(T, 3) int the triangles of the face mesh's landmarks (:func:`motion2video.generator.head_paste.face_triangles`
    of their points on Anny's head at rest)."""
    from motion2video.pose.face_anny import load_correspondence
    from motion2video.pose.facemesh import NUM_LANDMARKS
    from renderers import anny_model

    points = load_correspondence().points(anny_model.anny_rest().vertices)[:NUM_LANDMARKS]
    return face_triangles(points)


def lay_face(frame: np.ndarray, face: PicturedFace, head: HeadMoves, row: int, *, affine: np.ndarray | None = None,
             within: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 3) uint8 ``frame``, target ``row`` of ``head``, with the pictured face laid over the part of it the
    target shows (:func:`motion2video.generator.head_paste.lay_moved_face`).

    Args:
        frame: (H, W, 3) uint8 in the reference picture's pixels (the output's).
        affine: (2, 3) reference pixels -> the target's, the head's move when it is not ``head``'s own (the keypoint
            warp moves the head by its head segment); None: ``head.affines[row]``.
        within: (H, W) float in [0, 1] the generated person's matte, or None.
    """
    move = head.affines[row] if affine is None else np.asarray(affine, np.float64)
    moved = landmarks_in_reference(face) @ move[:, :2].T + move[:, 2]
    return lay_moved_face(frame, face.image, face.matte, compose_affine(move, face.to_reference), moved,
                          head.offsets[row], landmark_triangles(), head.shown[row], float(head.weights[row]),
                          within=within)


def face_moves(face: PicturedFace, ref_uv: np.ndarray, tgt_uv: np.ndarray, tgt_visible: np.ndarray, *, rest
               ) -> HeadMoves:
    """Where the pictured face goes in each target and how much of it to lay over
    (:func:`motion2video.generator.head_paste.head_moves`), through the face mesh's correspondence with Anny's head
    (:mod:`motion2video.pose.face_anny`).

    Args:
        face: the pictured face; ref_uv: (V, 2) the body mesh's vertices in the reference, where it samples them;
            tgt_uv: (N, V, 2) the same vertices in each target, in the same pixels; tgt_visible: (N, V) bool;
            rest: the body's :class:`renderers.anny_model.AnnyRest`.
    Returns:
        the :class:`~motion2video.generator.head_paste.HeadMoves` of the N targets (reference pixels -> target
        pixels).
    """
    from motion2video.pose.face_anny import load_correspondence
    from motion2video.pose.facemesh import NUM_LANDMARKS
    from renderers import anny_model

    corr = load_correspondence()
    mesh = slice(0, NUM_LANDMARKS)  # the table's last two rows are the irises, which the landmarks do not hold
    head = np.flatnonzero(anny_model.head_vertices())
    return head_moves(landmarks_in_reference(face), corr.points(rest.vertices)[mesh], corr.vertices[mesh],
                      corr.weights[mesh], ref_uv, tgt_uv, tgt_visible, head_points=rest.vertices[head],
                      head_vertices=head)


def joint_face_moves(face: PicturedFace, placement, reference_points: np.ndarray, *,
                     pictured: np.ndarray | None = None) -> HeadMoves | None:
    """How the pictured face moves and how much of it to lay over in each target of a generator without a body mesh
    (the keypoint warp): Anny's head carried rigidly by the head's axes of the joints
    (:func:`motion2video.generator.head_paste.rigid_head`), the reference's lifted from its 2D joints as the mesh
    generator lifts them (:func:`motion2video.generator.mesh_fit.lift_reference`); a head vertex counts as shown where
    it faces the camera (the head's own back hides the face; an arm in front of it is not seen). The moves are
    :func:`motion2video.generator.head_paste.head_moves`'s, as for the mesh generator (the warp moves the face by its
    own head segment; which landmarks are shown and the weights are the rigid head's).

    Args:
        face: the pictured face; placement: the structures' :class:`motion2video.stages.structure.BodyPlacement`.
        reference_points: (17, 2) the reference's joints in output pixels.
        pictured: (17, 3) the reference picture's own 3D pose (its pose file's ``camera_joints``), or None.
    Returns:
        the :class:`~motion2video.generator.head_paste.HeadMoves` of the N targets; None for a 2D placement (2D
        joints do not say which way the head is turned).
    """
    from motion2video.generator.head_paste import rigid_head
    from motion2video.generator.mesh_fit import lift_reference
    from motion2video.pose.face_anny import load_correspondence
    from motion2video.pose.facemesh import NUM_LANDMARKS
    from renderers import anny_model
    from renderers.mesh import vertex_normals

    if placement.world_observed is None or placement.camera is None:
        return None
    camera, scale, shift = placement.camera, placement.scale, np.asarray(placement.shift, np.float64)
    world = np.concatenate([placement.world_observed, placement.world_futures.reshape(-1, 17, 3)])  # (N, 17, 3)
    lifted = lift_reference(reference_points, world[0], camera, scale, shift, pictured=pictured)
    rest = anny_model.anny_rest()
    head = np.flatnonzero(anny_model.head_vertices())
    points, normals = rigid_head(rest.vertices[head], vertex_normals(rest.vertices, anny_model.triangles())[head],
                                 rest.joints17, np.concatenate([lifted[None], world]))
    uv = camera.project(points.reshape(-1, 3))[:, :2].reshape(len(points), len(head), 2) * scale + shift
    shown = np.einsum("npd,npd->np", normals, np.asarray(camera.position, np.float64) - points) > 0
    corr = load_correspondence()
    mesh = slice(0, NUM_LANDMARKS)  # the table's last two rows are the irises, which the landmarks do not hold
    local = np.searchsorted(head, corr.vertices[mesh])  # the landmarks' vertices among the head's
    if not np.array_equal(head[np.minimum(local, len(head) - 1)], corr.vertices[mesh]):
        raise ValueError("a face landmark lies off Anny's head vertices")
    return head_moves(landmarks_in_reference(face), corr.points(rest.vertices)[mesh], local, corr.weights[mesh], uv[0],
                      uv[1:], shown[1:], head_points=rest.vertices[head], head_vertices=np.arange(len(head)))
