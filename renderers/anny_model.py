"""One Anny body model per process, and the rest-pose facts the mesh renderers need.

Anny (NAVER, Apache-2.0) is a MakeHuman-based body model in PyTorch: 13,718 vertices, 27,420 triangles,
104 bones, 52 ARKit facial actions (in :data:`motion2video.core.motion.ARKIT_NAMES` order) and 6 phenotype
parameters. Its frame is the project's world frame: metres, z up, the body faces -y, its left side is +x.

Building the model the first time on a machine takes ~40 s and writes a cache under ``~/.cache/anny`` (a line on
stderr says so before it starts); afterwards it takes ~1 s. :func:`get_anny` builds it once per process and every
renderer shares it.

Body regions (for colouring, :func:`region_weights`) come from the skinning weights: each vertex takes the
region of its dominant bone (:data:`BONE_REGION_RULES`); then straight cut lines on the rest pose (waist,
neckline, sleeves, hairline, iris) and the mouth (a lip ellipse, Anny's mouth-cavity segmentation) refine
them, with soft weights across each cut so interpolated vertex colours draw straight edges.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Mapping

import numpy as np

from motion2video.core.skeletons import h36m_body_points

if TYPE_CHECKING:  # pragma: no cover
    import anny as _anny_t

PHENOTYPE_NAMES: tuple[str, ...] = ("gender", "age", "muscle", "weight", "height", "proportions")

# Anny bone whose rest head is each canonical H36M-17 joint's nearest point (canonical order); the torso and
# head joints are then put on Human3.6M's body points (core.skeletons.h36m_body_points, skeleton version 2).
H36M_17_BONES: tuple[str, ...] = (
    "root",                                              # 0 pelvis
    "upperleg01.R", "lowerleg01.R", "foot.R",            # 1-3 right hip, knee, ankle
    "upperleg01.L", "lowerleg01.L", "foot.L",            # 4-6 left hip, knee, ankle
    "spine03", "spine01", "neck01", "head",              # 7 spine, 8 thorax, 9 neck, 10 head (skull base)
    "upperarm01.L", "lowerarm01.L", "wrist.L",           # 11-13 left shoulder, elbow, wrist
    "upperarm01.R", "lowerarm01.R", "wrist.R",           # 14-16 right shoulder, elbow, wrist
)

# Region labels, in the order of the integer codes returned by :func:`vertex_regions`.
REGION_NAMES: tuple[str, ...] = ("skin", "top", "trousers", "shoes", "hair", "eyes", "iris", "lips", "mouth")
SKIN, TOP, TROUSERS, SHOES, HAIR, EYES, IRIS, LIPS, MOUTH = range(len(REGION_NAMES))
SLEEVE_LENGTH = 0.55  # short sleeves end this fraction of the way from shoulder to elbow
IRIS_HALF_ANGLE_DEG = 28.0  # angular radius of the iris seen from the eyeball centre
LIP_HALF_WIDTH_RATIO = 1.4  # lip ellipse half-width / the upper lip core's half-width
LOWER_LIP_HEIGHT = 0.011  # metres from the mouth line to the bottom of the lower lip
CUT_WIDTH = 0.015  # metres over which colours blend across a clothing cut line

# Dominant-bone name prefix -> region (first match wins; bones matching nothing are skin).
BONE_REGION_RULES: tuple[tuple[str, int], ...] = (
    ("eye.", EYES),
    ("foot.", SHOES), ("toe", SHOES),
    ("root", TROUSERS), ("pelvis.", TROUSERS), ("upperleg", TROUSERS), ("lowerleg", TROUSERS),
    ("spine05", TROUSERS),
    ("spine", TOP), ("clavicle", TOP), ("shoulder01", TOP), ("upperarm", TOP),
)

MAX_CACHED_PHENOTYPES = 64  # rest models kept by anny_rest (each ~0.5 MB)
_LOCK = threading.Lock()
_MODEL: "_anny_t.Anny | None" = None
_REST_CACHE: dict[tuple[float, ...], "AnnyRest"] = {}


def get_anny() -> "_anny_t.Anny":
    """The process-wide Anny model (``facial_actions="all"``, ``local_changes="none"``), built on first use.

    Its default pose parameterization is Anny's; every call in this package passes
    ``pose_parameterization="world"`` explicitly.
    """
    global _MODEL
    with _LOCK:
        if _MODEL is None:
            _init_warp_quietly()
            import anny
            import torch

            with _cache_build_lock(), torch.no_grad():
                model = anny.Anny(facial_actions="all", local_changes="none")
            model.eval()
            if list(model.phenotype_labels) != list(PHENOTYPE_NAMES):
                raise RuntimeError(f"unexpected Anny phenotype labels {model.phenotype_labels}")
            _check_facial_actions(model)
            _MODEL = model
    return _MODEL


def cache_folder() -> Path:
    """Where Anny keeps the model data it builds on first use (``~/.cache/anny``, or ``$ANNY_CACHE_DIR``)."""
    from anny.paths import get_anny_cache_path

    return Path(get_anny_cache_path())


def cache_built(folder: Path) -> bool:
    """Whether Anny's cache in ``folder`` holds its built model data (its ``.safetensors`` files)."""
    return folder.is_dir() and any(folder.rglob("*.safetensors"))


def build_note(folder: Path) -> str | None:
    """The line said on stderr before Anny builds its cache in ``folder``; None when it is built already."""
    if cache_built(folder):
        return None
    return (f"building the Anny body model's cache in {folder}: once per machine, about 40 s on an idle 2-core "
            "machine (minutes on a busy one), about 0.8 GB ...")


@contextmanager
def _cache_build_lock() -> Iterator[None]:
    """Held while Anny is constructed: one process builds the cache (with a line on stderr before and after)
    while any other waits for it instead of building the same files beside it (parallel test workers, batch
    workers on a fresh machine)."""
    import fcntl
    import sys
    import time

    folder = cache_folder()
    folder.parent.mkdir(parents=True, exist_ok=True)
    with open(folder.parent / f".{folder.name}.build.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            note = build_note(folder)
            if note is not None:
                print(f"motion2video: {note}", file=sys.stderr, flush=True)
            start = time.perf_counter()
            yield
            if note is not None:
                print(f"motion2video: the Anny cache is built ({time.perf_counter() - start:.0f} s)",
                      file=sys.stderr, flush=True)
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _init_warp_quietly() -> None:
    """Initialise NVIDIA Warp (Anny's skinning kernels) without its console output: its greeting and
    kernel-load lines go to stdout at the INFO level, and its native CUDA probe writes a warning straight to
    file descriptor 2 on machines without a GPU driver (this project's default). Warnings and errors of Warp
    itself still show."""
    import warp

    warp.config.log_level = warp.LOG_WARNING
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            warp.init()
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _check_facial_actions(model) -> None:
    from motion2video.core.motion import ARKIT_NAMES

    if tuple(model.facial_action_labels) != ARKIT_NAMES:
        raise RuntimeError("Anny's facial_action_labels differ from motion2video.core.motion.ARKIT_NAMES")


def bone_names() -> tuple[str, ...]:
    """The 104 Anny bone names in model order (parents before children)."""
    return tuple(get_anny().bone_labels)


def bone_parents() -> np.ndarray:
    """(104,) int parent index per bone, -1 for the root."""
    parents = np.asarray(get_anny().bone_parents, dtype=np.int64).copy()
    parents[0] = -1
    return parents


def bone_index(name: str) -> int:
    """Index of an Anny bone by name; raises KeyError listing a few names when unknown."""
    names = bone_names()
    if name not in names:
        raise KeyError(f"unknown Anny bone {name!r}; e.g. {', '.join(names[:8])}, ...")
    return names.index(name)


def phenotype_vector(phenotype: Mapping[str, float] | None) -> tuple[float, ...]:
    """The 6 phenotype values in :data:`PHENOTYPE_NAMES` order (missing ones 0.5); raises ValueError on
    unknown names or values outside [0, 1]."""
    phenotype = dict(phenotype or {})
    unknown = set(phenotype) - set(PHENOTYPE_NAMES)
    if unknown:
        raise ValueError(f"unknown Anny phenotype(s) {sorted(unknown)}; known: {', '.join(PHENOTYPE_NAMES)}")
    values = tuple(float(phenotype.get(name, 0.5)) for name in PHENOTYPE_NAMES)
    for name, v in zip(PHENOTYPE_NAMES, values):
        if not 0.0 <= v <= 1.0:
            raise ValueError(f"phenotype {name} must be in [0, 1], got {v}")
    return values


@dataclass(frozen=True)
class AnnyRest:
    """Anny's rest (A-)pose for one phenotype.

    Attributes:
        vertices: (V, 3) float64 rest vertices, metres.
        bone_heads: (104, 3) float64 bone head positions.
        bone_poses: (104, 4, 4) float64 rest world pose of each bone (pass back with
            ``pose_parameterization="world"`` to get ``vertices``).
        joints17: (17, 3) float64 the canonical H36M-17 joints: the bone heads of :data:`H36M_17_BONES` put on
            Human3.6M's body points (:func:`~motion2video.core.skeletons.h36m_body_points`).
        phenotype: the 6 phenotype values used.
    """

    vertices: np.ndarray
    bone_heads: np.ndarray
    bone_poses: np.ndarray
    joints17: np.ndarray
    phenotype: tuple[float, ...]


def anny_rest(phenotype: Mapping[str, float] | None = None) -> AnnyRest:
    """Rest vertices, bone heads and bone poses for a phenotype (cached per phenotype)."""
    import torch

    values = phenotype_vector(phenotype)
    with _LOCK:
        cached = _REST_CACHE.get(values)
    if cached is not None:
        return cached
    model = get_anny()
    with torch.no_grad():
        out = model(phenotype_kwargs=dict(zip(PHENOTYPE_NAMES, values)), pose_parameterization="world")
    heads = out["rest_bone_heads"][0].double().cpu().numpy()
    idx = [bone_index(n) for n in H36M_17_BONES]
    rest = AnnyRest(
        vertices=out["rest_vertices"][0].double().cpu().numpy(),
        bone_heads=heads,
        bone_poses=out["rest_bone_poses"][0].double().cpu().numpy(),
        joints17=h36m_body_points(heads[idx][None], shoulder_band=None)[0],  # Anny keeps its own shoulders
        phenotype=values,
    )
    for arr in (rest.vertices, rest.bone_heads, rest.bone_poses, rest.joints17):
        arr.setflags(write=False)
    with _LOCK:
        if len(_REST_CACHE) >= MAX_CACHED_PHENOTYPES:  # drop the oldest entry
            _REST_CACHE.pop(next(iter(_REST_CACHE)))
        _REST_CACHE[values] = rest
    return rest


_FACES: np.ndarray | None = None
_DOMINANT: np.ndarray | None = None


def triangles() -> np.ndarray:
    """(27420, 3) int64 triangle vertex indices (Anny's triangulated faces, counter-clockwise outside)."""
    global _FACES
    if _FACES is None:
        faces = get_anny().get_triangular_faces().cpu().numpy().astype(np.int64)
        faces.setflags(write=False)
        _FACES = faces
    return _FACES


def dominant_bones() -> np.ndarray:
    """(V,) int64 index of the bone with the largest skinning weight for each vertex."""
    global _DOMINANT
    if _DOMINANT is None:
        model = get_anny()
        weights = model.vertex_bone_weights.cpu().numpy()  # (V, 9)
        indices = model.vertex_bone_indices.cpu().numpy()  # (V, 9)
        best = indices[np.arange(len(indices)), np.argmax(weights, axis=1)].astype(np.int64)
        best.setflags(write=False)
        _DOMINANT = best
    return _DOMINANT


HEAD_BONE = "head"  # the head region: vertices whose dominant bone is this bone or one below it (the eyes)


def head_vertices() -> np.ndarray:
    """(V,) bool: vertices whose dominant bone is :data:`HEAD_BONE` or a descendant of it (the skull, face,
    eyes, hair; not the neck)."""
    parents = bone_parents()
    inside = np.zeros(len(parents), dtype=bool)
    inside[bone_index(HEAD_BONE)] = True
    for b in range(len(parents)):  # parents come before children
        if parents[b] >= 0 and inside[parents[b]]:
            inside[b] = True
    return inside[dominant_bones()]


HAND_BONES = ("wrist", "metacarpal", "finger")  # a hand's bones, by name prefix (each with its side's suffix)


def hand_vertices(side: str) -> np.ndarray:
    """(V,) bool: the vertices of one hand (``side`` "L" or "R", the body's own left or right) whose dominant bone
    is its wrist, a metacarpal or a finger bone."""
    if side not in ("L", "R"):
        raise ValueError(f"side must be 'L' or 'R', got {side!r}")
    names = bone_names()
    hand = np.array([n.endswith(f".{side}") and n.startswith(HAND_BONES) for n in names])
    return hand[dominant_bones()]


def head_submesh() -> tuple[np.ndarray, np.ndarray]:
    """The head's own triangles: (H,) int64 indices of :func:`head_vertices` into the full mesh and (F, 3)
    int64 triangles (those with all three corners on the head) indexing that subset."""
    keep = head_vertices()
    ids = np.flatnonzero(keep)
    remap = np.full(len(keep), -1, dtype=np.int64)
    remap[ids] = np.arange(len(ids))
    faces = triangles()
    faces = faces[keep[faces].all(axis=1)]
    return ids, remap[faces]


def bone_region(name: str) -> int:
    """Region code of a bone by :data:`BONE_REGION_RULES`."""
    for prefix, region in BONE_REGION_RULES:
        if name.startswith(prefix):
            return region
    return SKIN


def _ramp(signed: np.ndarray, width: float) -> np.ndarray:
    """0 -> 1 linear ramp of a signed distance over ``width`` centred on 0 (same shape)."""
    return np.clip(signed / width + 0.5, 0.0, 1.0)


def region_weights(rest: AnnyRest | None = None) -> np.ndarray:
    """(V, R) soft region weights per vertex (rows sum to 1, R = len(REGION_NAMES)).

    The dominant bone gives a first region (:data:`BONE_REGION_RULES`); then, on the rest pose, clean
    cut lines replace the jagged bone borders: the waist (a horizontal plane a little above ``spine04``'s
    head) splits top from trousers, the neckline (a plane tilted down to the front just below ``neck01``)
    splits top from skin, the sleeves end at :data:`SLEEVE_LENGTH` of the upper arm, head vertices above
    the brow or behind the ears become hair, and each eyeball gets a dark iris disc. Across each cut the
    weights ramp over :data:`CUT_WIDTH`, so that per-vertex colours interpolated over the triangles draw
    a straight edge instead of the mesh's zigzag.
    """
    rest = rest or anny_rest()
    v = rest.vertices  # (V, 3)
    H = rest.bone_heads
    names = bone_names()
    dominant = dominant_bones()
    by_bone = np.array([bone_region(n) for n in names], dtype=np.int64)
    weights = np.eye(len(REGION_NAMES))[by_bone[dominant]]  # (V, R) one-hot

    def on(*prefixes: str) -> np.ndarray:
        """(V,) whether each vertex's dominant bone name starts with one of the prefixes."""
        return np.array([n.startswith(prefixes) for n in names])[dominant]

    def split(mask: np.ndarray, high: np.ndarray, high_region: int, low_region: int) -> None:
        """Vertices in mask: weight ``high`` on high_region, the rest on low_region."""
        weights[mask] = 0.0
        weights[mask, high_region] = high[mask]
        weights[mask, low_region] += 1.0 - high[mask]

    # Waist: horizontal plane.
    waist_z = H[bone_index("spine04")][2] + 0.02
    split(on("root", "pelvis.", "spine", "upperleg"), _ramp(v[:, 2] - waist_z, CUT_WIDTH), TOP, TROUSERS)
    # Neckline: a plane lower at the front (-y) than at the back.
    neck = H[bone_index("neck01")]
    line_z = neck[2] - 0.015 + 0.6 * (v[:, 1] - neck[1])  # (V,)
    split(on("spine01", "spine02", "clavicle", "shoulder01", "neck"), _ramp(v[:, 2] - line_z, CUT_WIDTH),
          SKIN, TOP)
    # Sleeves: a fraction of the way from shoulder to elbow.
    for side in ("L", "R"):
        shoulder, elbow = H[bone_index(f"upperarm01.{side}")], H[bone_index(f"lowerarm01.{side}")]
        axis = elbow - shoulder
        length = float(np.linalg.norm(axis))
        along = (v - shoulder) @ axis / length  # (V,) metres from the shoulder along the upper arm
        arm = on(f"upperarm01.{side}", f"upperarm02.{side}", f"lowerarm01.{side}", f"shoulder01.{side}")
        split(arm, _ramp(along - SLEEVE_LENGTH * length, CUT_WIDTH), SKIN, TOP)
    # Hair: head vertices above the brow, or behind the ears above the nape.
    head = H[bone_index("head")]
    eye_l, eye_r = H[bone_index("eye.L")], H[bone_index("eye.R")]
    eye_mid = 0.5 * (eye_l + eye_r)  # (3,)
    # The hairline: 5 cm above the eyes at the front, dropping towards the ears further back.
    hairline = eye_mid[2] + 0.05 - 0.6 * np.maximum(v[:, 1] - (eye_mid[1] + 0.03), 0.0)  # (V,)
    above_brow = _ramp(v[:, 2] - hairline, CUT_WIDTH)
    behind = np.minimum(_ramp(v[:, 1] - (head[1] + 0.015), CUT_WIDTH), _ramp(v[:, 2] - head[2], CUT_WIDTH))
    split(on("head"), np.maximum(above_brow, behind), HAIR, SKIN)
    # Eyes: white eyeballs with a dark iris disc facing forward (-y).
    for side, centre in (("L", eye_l), ("R", eye_r)):
        rel = v - centre  # (V, 3)
        cos_forward = -rel[:, 1] / np.maximum(np.linalg.norm(rel, axis=1), 1e-9)
        angle = np.degrees(np.arccos(np.clip(cos_forward, -1.0, 1.0)))  # (V,) from the eye's forward axis
        split(on(f"eye.{side}"), _ramp(IRIS_HALF_ANGLE_DEG - angle, 6.0), IRIS, EYES)
    # Lips: an ellipse around the mouth line, sized from the upper lip; mouth cavity and tongue inside.
    lips = lip_weights(rest)
    weights *= (1.0 - lips)[:, None]
    weights[:, LIPS] += lips
    inside = mouth_vertices()
    weights[inside] = 0.0
    weights[inside, MOUTH] = 1.0
    return weights


def _facial_displacement(name: str) -> np.ndarray:
    """(V,) length of the displacement of one facial action's blendshape at weight 1, metres."""
    model = get_anny()
    index = list(model.blendshape_labels).index(f"facial_action:{name}")
    return np.linalg.norm(model.blendshapes[index].double().cpu().numpy(), axis=1)


def lip_weights(rest: AnnyRest | None = None) -> np.ndarray:
    """(V,) soft lip mask in [0, 1].

    Anny has no lip label, so the lips are an ellipse in the front (x, z) plane: its upper half reaches
    the top of the upper lip (the vertices that ``mouthRollUpper`` moves most), its lower half
    :data:`LOWER_LIP_HEIGHT` below the mouth line (the lowest of those vertices), its half-width
    :data:`LIP_HALF_WIDTH_RATIO` times the upper lip's; only vertices near the front of the face count.
    """
    rest = rest or anny_rest()
    v = rest.vertices
    roll = _facial_displacement("mouthRollUpper")
    upper = roll > 0.45 * roll.max()  # (V,) the upper lip's core
    z_line, z_top = v[upper, 2].min(), v[upper, 2].max()
    y_front = v[upper, 1].min()
    centre_x = float(np.median(v[upper, 0]))
    half_width = LIP_HALF_WIDTH_RATIO * np.abs(v[upper, 0] - centre_x).max()
    half_height = np.where(v[:, 2] > z_line, 1.1 * (z_top - z_line), LOWER_LIP_HEIGHT)  # (V,)
    e = ((v[:, 0] - centre_x) / half_width) ** 2 + ((v[:, 2] - z_line) / half_height) ** 2
    front = v[:, 1] < y_front + 0.025
    return _ramp(1.0 - e, 0.3) * front * (dominant_bones() == bone_index("head"))


_MOUTH: np.ndarray | None = None


def mouth_vertices() -> np.ndarray:
    """(K,) int64 vertices of the mouth cavity and tongue (Anny's body-part segmentation)."""
    global _MOUTH
    if _MOUTH is None:
        from anny.face_segmentation import get_face_segmentation_mask

        model = get_anny()
        face_mask = get_face_segmentation_mask(model, ["mouth_cavity", "tongue"]).cpu().numpy()  # (F,)
        faces = model.faces.cpu().numpy()
        _MOUTH = np.unique(faces[face_mask].ravel()).astype(np.int64)
    return _MOUTH


def vertex_regions(rest: AnnyRest | None = None) -> np.ndarray:
    """(V,) int8 region code per vertex (indices into :data:`REGION_NAMES`): the largest of
    :func:`region_weights`."""
    return np.argmax(region_weights(rest), axis=1).astype(np.int8)


def vertex_colors(palette: np.ndarray, rest: AnnyRest | None = None) -> np.ndarray:
    """(V, 3) float sRGB colours in [0, 1] from a (R, 3) uint8 palette (one colour per region), blended
    across the cut lines by :func:`region_weights`."""
    palette = np.asarray(palette, dtype=np.float64) / 255.0  # (R, 3)
    return np.clip(region_weights(rest) @ palette, 0.0, 1.0)
