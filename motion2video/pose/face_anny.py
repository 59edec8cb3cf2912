"""The Anny head at the tracked face points: the correspondence table and what the fit needs.

The table (``pose/data/face_anny_landmarks.npz``, built by ``scripts/make_face_correspondence.py``) gives
each tracked point a point on Anny's head: three vertex indices and barycentric weights. It was made once
from a frontal render of the neutral default head (512 x 512, the face renderer's close-up camera): the face
mesh (its eyes refined by the eye model) was run on the render, and each of its 468 landmarks' camera ray was
cut with the head's skin triangles (the eyeballs left out, so that the eyelid landmarks sit on the lids); the
nearest triangle hit gives the point, and a ray through the eye opening takes the nearest visible skin vertex.
The two iris centres are the pupils: the front-most vertex of each eyeball
(:func:`renderers.face.face_landmark_vertices`), which Anny's eyeLook* shapes move.

Renderer geometry (:func:`renderers.face.head_bone_poses`): a head vertex ``v`` (skinned to the ``head``
bone) is drawn at ``R v + c(R) + T``, the rotation spread over the neck turning the skull about the upper
neck; :func:`head_offset` gives ``c(R)``, so that a fitted rigid head pose becomes the face motion's
translation ``T``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from motion2video.core.motion import ARKIT_NAMES
from renderers import anny_model
from renderers.face import head_bone_poses

CORRESPONDENCE_FILE = Path(__file__).resolve().parent / "data" / "face_anny_landmarks.npz"


@dataclass(frozen=True)
class Correspondence:
    """Face-mesh landmarks on Anny's surface.

    Attributes:
        vertices: (470, 3) int64 Anny vertex indices (the face mesh's 468 landmarks, then the two iris centres).
        weights: (470, 3) float64 barycentric weights (rows sum to 1).
    """

    vertices: np.ndarray
    weights: np.ndarray

    def points(self, vertices: np.ndarray) -> np.ndarray:
        """(..., 470, 3) the points of (..., V, 3) Anny vertices."""
        return np.einsum("...lkd,lk->...ld", vertices[..., self.vertices, :], self.weights)


def load_correspondence(path: str | Path = CORRESPONDENCE_FILE) -> Correspondence:
    """The shipped table (see the module docstring)."""
    with np.load(path, allow_pickle=False) as data:
        return Correspondence(data["vertices"].astype(np.int64), data["weights"].astype(np.float64))


def surface_points(xy: np.ndarray, uv: np.ndarray, depth: np.ndarray, triangles: np.ndarray,
                   visible: np.ndarray) -> Correspondence:
    """Cut each image point's camera ray with a mesh: the nearest triangle containing it in the image.

    Args:
        xy: (L, 2) image points, pixels.
        uv: (V, 2) projected vertices, pixels; depth: (V,) their camera depth.
        triangles: (F, 3) vertex indices of the triangles that may be hit.
        visible: (V,) bool vertices on the front surface; a point no triangle contains takes the nearest of
            them in the image.
    Returns:
        the :class:`Correspondence` of the L points.
    """
    a, b, c = uv[triangles[:, 0]], uv[triangles[:, 1]], uv[triangles[:, 2]]  # (F, 2) each
    v0, v1 = b - a, c - a
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]  # (F,)
    ok = np.abs(den) > 1e-12
    tri_depth = depth[triangles].mean(axis=1)
    vis_ids = np.flatnonzero(visible)
    ids = np.zeros((len(xy), 3), np.int64)
    weights = np.zeros((len(xy), 3))
    for i, p in enumerate(xy):
        d = p - a  # (F, 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            w1 = (d[:, 0] * v1[:, 1] - v1[:, 0] * d[:, 1]) / den
            w2 = (v0[:, 0] * d[:, 1] - d[:, 0] * v0[:, 1]) / den
        inside = ok & (w1 >= 0) & (w2 >= 0) & (w1 + w2 <= 1)
        if inside.any():
            f = np.flatnonzero(inside)[np.argmin(tri_depth[inside])]
            ids[i] = triangles[f]
            weights[i] = (1 - w1[f] - w2[f], w1[f], w2[f])
        else:
            k = vis_ids[np.argmin(np.linalg.norm(uv[vis_ids] - p, axis=1))]
            ids[i] = k
            weights[i] = (1.0, 0.0, 0.0)
    return Correspondence(ids, weights)


def skin_triangles() -> np.ndarray:
    """(F, 3) Anny triangles of the head's skin: every corner skinned mostly to ``head`` (not the eyes)."""
    dominant = anny_model.dominant_bones()
    on_head = dominant == anny_model.bone_index("head")
    faces = anny_model.triangles()
    return faces[on_head[faces].all(axis=1)]


@dataclass(frozen=True)
class HeadBasis:
    """The head model at the landmarks for one phenotype.

    Attributes:
        neutral: (L, 3) rest positions, metres.
        basis: (52, L, 3) displacement of each ARKit blendshape at weight 1, :data:`ARKIT_NAMES` order.
    """

    neutral: np.ndarray
    basis: np.ndarray


@lru_cache(maxsize=4)
def head_basis(phenotype: tuple[float, ...] | None = None) -> HeadBasis:
    """:class:`HeadBasis` at the shipped correspondence for a phenotype (None: Anny's default)."""
    corr = load_correspondence()
    pheno = None if phenotype is None else dict(zip(anny_model.PHENOTYPE_NAMES, phenotype))
    rest = anny_model.anny_rest(pheno)
    model = anny_model.get_anny()
    labels = list(model.blendshape_labels)
    shapes = model.blendshapes.double().cpu().numpy()  # (S, V, 3)
    basis = np.stack([corr.points(shapes[labels.index(f"facial_action:{name}")]) for name in ARKIT_NAMES])
    return HeadBasis(corr.points(rest.vertices), basis)


def head_offset(rotations: np.ndarray, phenotype: dict[str, float] | None = None) -> np.ndarray:
    """(T, 3) ``c(R)``: where the face renderer puts a head vertex ``v`` is ``R v + c(R) + T``.

    Args:
        rotations: (T, 3) head axis-angle, world axes.
    """
    rest = anny_model.anny_rest(phenotype)
    rotations = np.asarray(rotations, np.float64)
    poses = head_bone_poses(rest, rotations, np.zeros_like(rotations))  # (T, 104, 4, 4)
    k = anny_model.bone_index("head")
    G = poses[:, k, :3, :3] @ rest.bone_poses[k, :3, :3].T  # (T, 3, 3) the total rotation R
    return poses[:, k, :3, 3] - np.einsum("tij,j->ti", G, rest.bone_heads[k])


def posed_landmarks(expressions: np.ndarray, rotations: np.ndarray, translations: np.ndarray,
                    phenotype: dict[str, float] | None = None, batch: int = 32) -> np.ndarray:
    """(T, 470, 3) the tracked points on Anny's full forward (skinning included), as the face renderer
    poses the head: what the re-projection error is measured on.

    Args:
        expressions: (T, 52); rotations, translations: (T, 3).
    """
    import torch

    rest = anny_model.anny_rest(phenotype)
    model = anny_model.get_anny()
    corr = load_correspondence()
    poses = head_bone_poses(rest, rotations, translations)
    used = np.unique(corr.vertices)
    local = np.searchsorted(used, corr.vertices)
    out = np.zeros((len(expressions), len(corr.vertices), 3))
    pheno = dict(zip(anny_model.PHENOTYPE_NAMES, rest.phenotype))
    for start in range(0, len(expressions), batch):
        stop = min(start + batch, len(expressions))
        with torch.no_grad():
            res = model(torch.as_tensor(poses[start:stop], dtype=model.dtype), phenotype_kwargs=pheno,
                        facial_actions=torch.as_tensor(np.asarray(expressions[start:stop]), dtype=model.dtype),
                        pose_parameterization="world")
        verts = res["vertices"][:, torch.as_tensor(used)].double().cpu().numpy()  # (b, U, 3)
        out[start:stop] = np.einsum("blkd,lk->bld", verts[:, local], corr.weights)
    return out
