"""Synthetic appearance data for the frame generator, with real ground truth.

Each *sequence* is one identity (Anny phenotype, skin tone, clothing colours per region), one background (a
crop of an image shipped in ``skimage.data``), one light and one camera, rendered over a few frames of a real
capture: a mocap clip through the body IK for bodies, an ARKit capture with head pose from the
face-dynamics module for faces. A *pair* is two frames of one sequence: the reference frame, its structure,
the target structure and the true target frame (same identity, background and camera).

Structures:
- body: 17 Gaussian heatmaps + 16 limb maps (33 channels) drawn from the 2D joints projected with the
  camera that rendered the frame;
- face: the rendered shaded grey face mesh (1 channel), in the frame's pose and expression.

Control points for the limb-warp baseline: the 2D joints (body) or projected face-mesh vertices (face).

Splits: held-out identities (drawn from a different seed stream) and held-out clips (a fixed rule on the
file name, :func:`is_test_clip`) form the test split.

Sequences are generated into a cache directory the user chooses, as npz shards (never committed):
``CACHE/<domain>-<size>-<split>-<hash>/shard-00000.npz`` + ``spec.json``; an interrupted generation resumes
at the first missing shard.
"""

from __future__ import annotations

import hashlib
import json
import os
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from motion2video.atomic import save_npz
from motion2video.errors import InputError
from motion2video.skeletons import H36M_17

SPLITS = ("train", "test")
BODY_STRUCTURE_CHANNELS = H36M_17.num_joints + len(H36M_17.bones)  # 17 heatmaps + 16 limbs = 33
FACE_STRUCTURE_CHANNELS = 1
DATA_VERSION = 2  # 2: person masks stored, patterned clothing, 24 backgrounds


def structure_channels(domain: str) -> int:
    """Number of structure channels the generator takes for ``domain``."""
    if domain == "body":
        return BODY_STRUCTURE_CHANNELS
    if domain == "face":
        return FACE_STRUCTURE_CHANNELS
    raise ValueError(f"unknown domain {domain!r}")


def default_data_root() -> Path:
    """``../shared/data`` beside the repository root (where the real captures live on this machine)."""
    return Path(__file__).resolve().parents[2].parent / "shared" / "data"


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/motion2video/frames`` (``~/.cache/...``): outside the repository."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "motion2video" / "frames"


# --- structures -----------------------------------------------------------------------------------------

def heatmap_sigma(size: int) -> float:
    """Gaussian heatmap sigma in pixels for an image of ``size`` pixels (2 px at 128)."""
    return 2.0 * size / 128.0


def limb_thickness(size: int) -> int:
    """Limb-map line width in pixels (3 at 128, 6 at 256)."""
    return max(2, int(round(3 * size / 128)))


def body_structures(points: np.ndarray, size: int) -> np.ndarray:
    """Body structure maps from 2D joints.

    Args:
        points: (B, 17, 2) canonical h36m-17 joints in pixels (x right, y down).
        size: image width = height.
    Returns:
        (B, 33, size, size) float32 in [0, 1]: 17 Gaussian heatmaps then 16 limb maps (skeleton.bones order).
    """
    from renderers.skeleton import gaussian_heatmaps, render_limb_maps

    points = np.asarray(points, np.float64)
    if points.ndim != 3 or points.shape[1:] != (H36M_17.num_joints, 2):
        raise ValueError(f"points must be (B, 17, 2), got {points.shape}")
    sigma = heatmap_sigma(size)
    heat = np.stack([gaussian_heatmaps(p, (size, size), sigma) for p in points])  # (B, 17, H, W)
    limbs = render_limb_maps(points, H36M_17, (size, size), thickness=limb_thickness(size))  # (B, 16, H, W)
    return np.concatenate([heat, limbs], axis=1)


def face_structures(images: np.ndarray) -> np.ndarray:
    """Face structure maps from rendered shaded face meshes: (B, H, W) uint8 -> (B, 1, H, W) float32."""
    images = np.asarray(images)
    if images.ndim != 3:
        raise ValueError(f"face structure images must be (B, H, W), got {images.shape}")
    return images[:, None].astype(np.float32) / 255.0


# --- sequences and pairs --------------------------------------------------------------------------------

@dataclass
class FrameSequences:
    """Rendered sequences of one domain.

    Attributes:
        domain: ``"body"`` or ``"face"``.
        images: (N, T, H, W, 3) uint8 frames.
        points: (N, T, K, 2) float32 control points in pixels (body: the 17 joints; face: mesh vertices).
        structure_images: (N, T, H, W) uint8 rendered shaded face meshes (face), or None (body: structures
            are drawn from ``points``).
        identity: (N,) int64 identity index (unique within a split).
        clip: (N,) str, the capture each sequence comes from.
        start: (N,) int64, the first source frame of each sequence.
        masks: (N, T, H, W) bool silhouettes of the person (rendered), or None (old caches).
    """

    domain: str
    images: np.ndarray
    points: np.ndarray
    structure_images: np.ndarray | None
    identity: np.ndarray
    clip: np.ndarray
    start: np.ndarray
    masks: np.ndarray | None = None

    def __post_init__(self) -> None:
        n, t, h, w, c = self.images.shape
        if c != 3 or h != w:
            raise ValueError(f"images must be (N, T, S, S, 3), got {self.images.shape}")
        if self.points.shape[:2] != (n, t) or self.points.shape[-1] != 2:
            raise ValueError(f"points must be (N, T, K, 2) matching images, got {self.points.shape}")
        if (self.domain == "face") != (self.structure_images is not None):
            raise ValueError("face sequences need structure_images; body sequences must not have them")
        if self.structure_images is not None and self.structure_images.shape != (n, t, h, w):
            raise ValueError(f"structure_images must be {(n, t, h, w)}, got {self.structure_images.shape}")
        if self.masks is not None and self.masks.shape != (n, t, h, w):
            raise ValueError(f"masks must be {(n, t, h, w)}, got {self.masks.shape}")

    @property
    def num_sequences(self) -> int:
        return int(self.images.shape[0])

    @property
    def frames_per_sequence(self) -> int:
        return int(self.images.shape[1])

    @property
    def image_size(self) -> int:
        return int(self.images.shape[2])

    def summary(self) -> dict:
        return {
            "domain": self.domain,
            "sequences": self.num_sequences,
            "frames_per_sequence": self.frames_per_sequence,
            "image_size": self.image_size,
            "identities": int(len(np.unique(self.identity))),
            "clips": sorted({str(c) for c in self.clip}),
        }

    @staticmethod
    def concatenate(parts: list["FrameSequences"]) -> "FrameSequences":
        if not parts:
            raise ValueError("nothing to concatenate")
        face = parts[0].structure_images is not None
        masked = all(p.masks is not None for p in parts)
        return FrameSequences(
            domain=parts[0].domain,
            images=np.concatenate([p.images for p in parts]),
            points=np.concatenate([p.points for p in parts]),
            structure_images=np.concatenate([p.structure_images for p in parts]) if face else None,
            identity=np.concatenate([p.identity for p in parts]),
            clip=np.concatenate([p.clip for p in parts]),
            start=np.concatenate([p.start for p in parts]),
            masks=np.concatenate([p.masks for p in parts]) if masked else None,
        )


@dataclass
class FramePairs:
    """A batch of (reference, target) pairs with everything the generator and the baselines need.

    Attributes:
        ref_images, tgt_images: (B, H, W, 3) uint8.
        ref_points, tgt_points: (B, K, 2) float32 control points, pixels.
        ref_structures, tgt_structures: (B, S, H, W) float32 structure maps.
        ref_masks, tgt_masks: (B, H, W) bool person silhouettes, or None when the sequences have none.
    """

    ref_images: np.ndarray
    tgt_images: np.ndarray
    ref_points: np.ndarray
    tgt_points: np.ndarray
    ref_structures: np.ndarray
    tgt_structures: np.ndarray
    ref_masks: np.ndarray | None = None
    tgt_masks: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.ref_images.shape[0])


def make_pairs(seqs: FrameSequences, index: np.ndarray, *, flip: np.ndarray | None = None,
               crop: int = 0, rng: np.random.Generator | None = None) -> FramePairs:
    """Gather pairs from sequences.

    Args:
        seqs: the sequences.
        index: (B, 3) int rows (sequence, reference frame, target frame).
        flip: (B,) bool, mirror the pair left-right (augmentation); body joints swap left/right names so
            the structure channels keep their meaning.
        crop: when > 0, cut a ``crop`` x ``crop`` window holding both poses out of each pair
            (:func:`crop_origins`, placed with ``rng``); control points shift with it and structures are
            drawn at the crop size.
        rng: places the crops (required with ``crop``).
    Returns:
        The pairs, structures computed for the (possibly flipped, cropped) frames.
    """
    index = np.asarray(index, np.int64).reshape(-1, 3)
    s, r, t = index[:, 0], index[:, 1], index[:, 2]
    size = seqs.image_size
    ref_img, tgt_img = seqs.images[s, r], seqs.images[s, t]  # (B, H, W, 3)
    ref_pts, tgt_pts = seqs.points[s, r].astype(np.float32), seqs.points[s, t].astype(np.float32)  # (B, K, 2)
    ref_face = tgt_face = None
    ref_mask = tgt_mask = None
    if seqs.masks is not None:
        ref_mask, tgt_mask = seqs.masks[s, r], seqs.masks[s, t]  # (B, H, W)
    if seqs.structure_images is not None:
        ref_face, tgt_face = seqs.structure_images[s, r], seqs.structure_images[s, t]  # (B, H, W)
    if flip is not None and np.any(flip):
        f = np.asarray(flip, bool)
        ref_img, tgt_img = ref_img.copy(), tgt_img.copy()
        ref_img[f], tgt_img[f] = ref_img[f, :, ::-1], tgt_img[f, :, ::-1]
        ref_pts, tgt_pts = ref_pts.copy(), tgt_pts.copy()
        for pts in (ref_pts, tgt_pts):
            pts[f, :, 0] = size - pts[f, :, 0]
            if seqs.domain == "body":
                pts[f] = pts[f][:, H36M_17.mirror_permutation()]
        if ref_face is not None:
            ref_face, tgt_face = ref_face.copy(), tgt_face.copy()
            ref_face[f], tgt_face[f] = ref_face[f, :, ::-1], tgt_face[f, :, ::-1]
        if ref_mask is not None:
            ref_mask, tgt_mask = ref_mask.copy(), tgt_mask.copy()
            ref_mask[f], tgt_mask[f] = ref_mask[f, :, ::-1], tgt_mask[f, :, ::-1]
    if crop:
        if rng is None:
            raise ValueError("make_pairs needs an rng to place crops")
        origins = crop_origins(rng, ref_pts, tgt_pts, size=size, crop=crop)  # (B, 2)

        def cut(a: np.ndarray) -> np.ndarray:  # (B, H, W, ...) -> (B, crop, crop, ...)
            return np.stack([x[y0:y0 + crop, x0:x0 + crop] for x, (x0, y0) in zip(a, origins)])

        ref_img, tgt_img = cut(ref_img), cut(tgt_img)
        ref_pts = ref_pts - origins[:, None, :].astype(np.float32)
        tgt_pts = tgt_pts - origins[:, None, :].astype(np.float32)
        if ref_face is not None:
            ref_face, tgt_face = cut(ref_face), cut(tgt_face)
        if ref_mask is not None:
            ref_mask, tgt_mask = cut(ref_mask), cut(tgt_mask)
        size = crop
    if seqs.domain == "body":
        ref_st, tgt_st = body_structures(ref_pts, size), body_structures(tgt_pts, size)
    else:
        ref_st, tgt_st = face_structures(ref_face), face_structures(tgt_face)
    masks = (None, None) if ref_mask is None else (np.ascontiguousarray(ref_mask), np.ascontiguousarray(tgt_mask))
    return FramePairs(np.ascontiguousarray(ref_img), np.ascontiguousarray(tgt_img), ref_pts, tgt_pts,
                      ref_st, tgt_st, *masks)


def crop_origins(rng: np.random.Generator, ref_points: np.ndarray, tgt_points: np.ndarray, *, size: int,
                 crop: int) -> np.ndarray:
    """Top-left corners of ``crop`` x ``crop`` training crops that hold both poses of each pair.

    The crop is placed uniformly among the positions that contain the bounding box of the pair's control
    points (clipped to the image); when the box is larger than the crop, the crop is centred on it.

    Args:
        ref_points, tgt_points: (B, K, 2) pixels.
        size: image size; crop <= size.
    Returns:
        (B, 2) int64 (x0, y0).
    """
    pts = np.concatenate([ref_points, tgt_points], axis=1)  # (B, 2K, 2)
    lo = np.clip(np.floor(pts.min(axis=1)), 0, size)  # (B, 2)
    hi = np.clip(np.ceil(pts.max(axis=1)), 0, size)
    # Origins with x0 <= lo and x0 + crop >= hi, inside [0, size - crop].
    first = np.clip(hi - crop, 0, size - crop)
    last = np.clip(lo, 0, size - crop)
    centred = np.clip(np.round(0.5 * (lo + hi) - crop / 2), 0, size - crop)
    u = rng.random(first.shape)
    origin = np.where(first <= last, np.floor(first + u * (last - first + 1)), centred)
    return np.minimum(origin, size - crop).astype(np.int64)


def sample_pair_index(rng: np.random.Generator, seqs: FrameSequences, batch_size: int) -> np.ndarray:
    """(batch_size, 3) random (sequence, reference, target) rows with reference != target."""
    t = seqs.frames_per_sequence
    s = rng.integers(0, seqs.num_sequences, batch_size)
    r = rng.integers(0, t, batch_size)
    tgt = (r + rng.integers(1, t, batch_size)) % t  # never equal to r
    return np.stack([s, r, tgt], axis=1)


def evaluation_pair_index(seqs: FrameSequences) -> np.ndarray:
    """The fixed evaluation pairs: in every sequence, frame 0 is the reference and each later frame a
    target; pairs whose two frames are byte-identical are left out (PSNR would be infinite)."""
    rows = []
    for s in range(seqs.num_sequences):
        for t in range(1, seqs.frames_per_sequence):
            if not np.array_equal(seqs.images[s, 0], seqs.images[s, t]):
                rows.append((s, 0, t))
    return np.asarray(rows, np.int64).reshape(-1, 3)


# --- splits, identities, backgrounds ---------------------------------------------------------------------

def is_test_clip(name: str) -> bool:
    """Held-out clip rule: about one file in five, chosen by a CRC of its relative path (stable when
    clips are added)."""
    return zlib.crc32(Path(name).as_posix().encode()) % 5 == 0


@dataclass(frozen=True)
class Identity:
    """One synthetic person: Anny phenotype values in [0, 1] and colours (RGB floats in [0, 1])."""

    phenotype: tuple[tuple[str, float], ...]
    skin: tuple[float, float, float]
    top: tuple[float, float, float]
    trousers: tuple[float, float, float]
    shoes: tuple[float, float, float]
    hair: tuple[float, float, float]
    iris: tuple[float, float, float]
    top_pattern: "ClothingPattern | None" = None
    trousers_pattern: "ClothingPattern | None" = None


PATTERN_KINDS = ("stripes", "vertical-stripes", "checks")


@dataclass(frozen=True)
class ClothingPattern:
    """A procedural two-colour pattern on a clothing region, defined on the rest-pose mesh (so it moves
    with the body).

    Attributes:
        kind: one of :data:`PATTERN_KINDS` (horizontal bands, vertical bands, or a checkerboard).
        colour: the second colour (RGB in [0, 1]); the region's own colour is the first.
        period: pattern period in metres on the rest mesh.
        phase: offset in periods.
    """

    kind: str
    colour: tuple[float, float, float]
    period: float
    phase: float = 0.0

    def weights(self, rest_vertices: np.ndarray) -> np.ndarray:
        """(V,) weight of the second colour per vertex in [0, 1] for (V, 3) rest vertices (z up, metres);
        band edges are softened over about a tenth of a period so the mesh does not alias them."""
        x, y, z = (np.asarray(rest_vertices, np.float64)[:, i] / self.period + self.phase for i in range(3))
        if self.kind == "stripes":
            wave = np.sin(2 * np.pi * z)
        elif self.kind == "vertical-stripes":
            wave = np.sin(2 * np.pi * (x + 0.5 * y))
        elif self.kind == "checks":
            wave = np.sin(2 * np.pi * z) * np.sin(2 * np.pi * (x + 0.5 * y))
        else:
            raise ValueError(f"unknown pattern kind {self.kind!r}")
        return 0.5 + 0.5 * np.tanh(3.0 * wave)


def sample_pattern(rng: np.random.Generator, base: tuple[float, float, float]) -> ClothingPattern | None:
    """A pattern for a garment of colour ``base``: none (flat) one time in four, else stripes or checks in
    a contrasting colour with a period of 8 to 16 cm."""
    if rng.random() < 0.25:
        return None
    kind = PATTERN_KINDS[int(rng.integers(len(PATTERN_KINDS)))]
    lum = float(np.dot(base, (0.3, 0.59, 0.11)))
    colour = _hsv_colour(rng, v_range=(0.05, 0.35) if lum > 0.5 else (0.7, 0.98))
    return ClothingPattern(kind=kind, colour=colour, period=float(rng.uniform(0.08, 0.16)),
                           phase=float(rng.uniform(0, 1)))


PHENOTYPE_KEYS = ("gender", "age", "muscle", "weight", "height", "proportions")

# Skin tones from light to dark (sRGB, 0..1), interpolated between.
SKIN_TONES = np.array([
    [0.96, 0.80, 0.69], [0.90, 0.72, 0.58], [0.80, 0.60, 0.45], [0.65, 0.46, 0.33],
    [0.50, 0.34, 0.23], [0.36, 0.24, 0.16],
])

HAIR_COLOURS = np.array([[0.08, 0.06, 0.05], [0.28, 0.19, 0.12], [0.45, 0.30, 0.17], [0.75, 0.60, 0.38],
                         [0.55, 0.22, 0.10], [0.60, 0.60, 0.60]])
IRIS_COLOURS = np.array([[0.24, 0.17, 0.12], [0.35, 0.25, 0.15], [0.25, 0.40, 0.55], [0.30, 0.42, 0.28]])


def _hsv_colour(rng: np.random.Generator, *, s_range=(0.25, 0.9), v_range=(0.2, 0.95)) -> tuple[float, ...]:
    import colorsys

    h = rng.uniform(0, 1)
    s = rng.uniform(*s_range)
    v = rng.uniform(*v_range)
    return tuple(float(c) for c in colorsys.hsv_to_rgb(h, s, v))


def sample_identity(rng: np.random.Generator) -> Identity:
    """A random identity: phenotype in a plausible adult range, a skin tone, clothing colours."""
    pheno = {
        "gender": rng.uniform(0.0, 1.0),
        "age": rng.uniform(0.35, 0.75),
        "muscle": rng.uniform(0.2, 0.8),
        "weight": rng.uniform(0.2, 0.8),
        "height": rng.uniform(0.3, 0.8),
        "proportions": rng.uniform(0.3, 0.7),
    }
    x = rng.uniform(0, len(SKIN_TONES) - 1)
    i = min(int(x), len(SKIN_TONES) - 2)
    skin = (1 - (x - i)) * SKIN_TONES[i] + (x - i) * SKIN_TONES[i + 1]
    top = _hsv_colour(rng)
    trousers = _hsv_colour(rng, v_range=(0.15, 0.8))
    return Identity(
        phenotype=tuple((k, float(pheno[k])) for k in PHENOTYPE_KEYS),
        skin=tuple(float(c) for c in skin),
        top=top,
        trousers=trousers,
        shoes=_hsv_colour(rng, s_range=(0.0, 0.6), v_range=(0.05, 0.6)),
        hair=tuple(float(c) for c in HAIR_COLOURS[rng.integers(len(HAIR_COLOURS))] * rng.uniform(0.8, 1.1)),
        iris=tuple(float(c) for c in IRIS_COLOURS[rng.integers(len(IRIS_COLOURS))]),
        top_pattern=sample_pattern(rng, top),
        trousers_pattern=sample_pattern(rng, trousers),
    )


def identities(split: str, count: int, *, seed: int = 0) -> list[Identity]:
    """``count`` identities of a split; train and test come from different seed streams (held out)."""
    if split not in SPLITS:
        raise ValueError(f"split must be one of {SPLITS}")
    rng = np.random.default_rng([seed, SPLITS.index(split), 7001])
    return [sample_identity(rng) for _ in range(count)]


# Images shipped inside scikit-image (no download): textures and scenes without people.
BACKGROUND_IMAGES = ("brick", "grass", "gravel", "rocket", "coffee", "chelsea", "hubble_deep_field",
                     "immunohistochemistry", "moon", "cell", "clock", "coins", "page", "text", "horse", "retina",
                     "colorwheel", "microaneurysms", "logo", "checkerboard", "binary_blobs", "cat")
PROCEDURAL_BACKGROUNDS = 4  # plus floor-and-wall gradients and tiles drawn here (24 backgrounds in all)


def procedural_backgrounds(size: int = 256) -> list[np.ndarray]:
    """Drawn backgrounds: a wall/floor split, diagonal tiles, a vertical gradient and wooden-like boards,
    (size, size, 3) uint8 each."""
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32) / size
    wall = np.where(yy[..., None] < 0.62, [200, 190, 170], [110, 90, 70]) * (0.8 + 0.2 * yy[..., None])
    tiles = 150 + 70 * ((np.floor(xx * 8 + yy * 8) + np.floor(xx * 8 - yy * 8)) % 2)[..., None] * [1.0, 0.9, 0.7]
    gradient = (60 + 160 * yy[..., None]) * np.array([0.6, 0.8, 1.0])
    boards = (120 + 40 * np.sin(2 * np.pi * (xx * 6 + 0.3 * np.sin(12 * yy))))[..., None] * [1.0, 0.75, 0.5]
    return [np.clip(b, 0, 255).astype(np.uint8) for b in (wall, tiles, gradient, boards)]


def background_images() -> list[np.ndarray]:
    """The background pool: (H, W, 3) uint8 images from ``skimage.data`` (grey ones replicated to RGB)."""
    import skimage.data

    out = []
    for name in BACKGROUND_IMAGES:
        img = np.asarray(getattr(skimage.data, name)())
        if img.dtype == bool:
            img = img.astype(np.uint8) * 255
        if img.ndim == 2:
            img = np.repeat(img[..., None], 3, axis=2)
        out.append(np.ascontiguousarray(img[..., :3]).astype(np.uint8))
    return out + procedural_backgrounds()


def background_crop(rng: np.random.Generator, pool: list[np.ndarray], size: int) -> np.ndarray:
    """A random square crop of a random pool image, resized to ``size``, tinted and dimmed a little
    (grey textures get a colour): (size, size, 3) uint8."""
    import cv2

    img = pool[int(rng.integers(len(pool)))]
    h, w = img.shape[:2]
    side = int(rng.uniform(0.35, 0.9) * min(h, w))
    y0 = int(rng.integers(0, h - side + 1))
    x0 = int(rng.integers(0, w - side + 1))
    crop = cv2.resize(img[y0:y0 + side, x0:x0 + side], (size, size), interpolation=cv2.INTER_AREA)
    tint = rng.uniform(0.55, 1.0, 3) * rng.uniform(0.6, 1.0)
    return np.clip(crop.astype(np.float32) * tint, 0, 255).astype(np.uint8)


# --- dataset specification and the cache ----------------------------------------------------------------

@dataclass(frozen=True)
class DatasetSpec:
    """What a cached split holds. Two specs with the same fields give the same sequences.

    Attributes:
        domain: ``"body"`` or ``"face"``.
        split: ``"train"`` or ``"test"``.
        image_size: frame size in pixels.
        num_sequences: sequences in the split.
        frames_per_sequence: frames rendered per sequence.
        num_identities: identities in the split (sequences cycle through them).
        window_seconds: each sequence spreads its frames evenly over this much of a capture.
        sequences_per_shard: sequences per npz shard.
        seed: base seed.
    """

    domain: str = "body"
    split: str = "train"
    image_size: int = 128
    num_sequences: int = 240
    frames_per_sequence: int = 12
    num_identities: int = 40
    window_seconds: float = 1.2
    sequences_per_shard: int = 16
    seed: int = 0

    def __post_init__(self) -> None:
        if self.domain not in ("body", "face"):
            raise ValueError(f"domain must be body or face, got {self.domain!r}")
        if self.split not in SPLITS:
            raise ValueError(f"split must be one of {SPLITS}, got {self.split!r}")
        if self.frames_per_sequence < 2:
            raise ValueError("frames_per_sequence must be >= 2")
        if self.num_sequences < 1 or self.num_identities < 1 or self.sequences_per_shard < 1:
            raise ValueError("num_sequences, num_identities and sequences_per_shard must be >= 1")

    @property
    def num_shards(self) -> int:
        return -(-self.num_sequences // self.sequences_per_shard)

    def key(self) -> str:
        blob = json.dumps({**asdict(self), "version": DATA_VERSION}, sort_keys=True).encode()
        return f"{self.domain}-{self.image_size}-{self.split}-{hashlib.sha1(blob).hexdigest()[:10]}"


def default_spec(domain: str, split: str, image_size: int = 128, *, seed: int = 0) -> DatasetSpec:
    """The dataset sizes used for the shipped models (train: 320 sequences x 12 frames of 200 identities;
    test: 32 x 9 of 8 held-out identities)."""
    window = 1.2 if domain == "body" else 4.0  # faces change more slowly than bodies
    if split == "train":
        return DatasetSpec(domain=domain, split=split, image_size=image_size, num_sequences=320,
                           frames_per_sequence=12, num_identities=200, window_seconds=window, seed=seed)
    return DatasetSpec(domain=domain, split=split, image_size=image_size, num_sequences=32,
                       frames_per_sequence=9, num_identities=8, window_seconds=window, sequences_per_shard=8,
                       seed=seed)


def save_shard(path: Path, seqs: FrameSequences) -> None:
    """Write sequences to an npz shard atomically (tmp file + rename)."""
    arrays = dict(images=seqs.images, points=seqs.points.astype(np.float32), identity=seqs.identity,
                  clip=np.asarray(seqs.clip, dtype=str), start=seqs.start, domain=np.asarray(seqs.domain))
    if seqs.structure_images is not None:
        arrays["structure_images"] = seqs.structure_images
    if seqs.masks is not None:
        arrays["masks"] = seqs.masks
    save_npz(path, arrays, compressed=True)


def load_shard(path: Path) -> FrameSequences:
    try:
        with np.load(path, allow_pickle=False) as z:
            return FrameSequences(
                domain=str(z["domain"]), images=z["images"], points=z["points"],
                structure_images=z["structure_images"] if "structure_images" in z.files else None,
                identity=z["identity"], clip=z["clip"], start=z["start"],
                masks=z["masks"] if "masks" in z.files else None,
            )
    except (OSError, KeyError, ValueError, zlib.error) as err:
        raise InputError(f"unreadable cache shard ({type(err).__name__}: {err}); delete it to regenerate",
                         path) from None


def cache_folder(cache_dir: str | Path, spec: DatasetSpec) -> Path:
    return Path(cache_dir) / spec.key()


def load_or_generate(spec: DatasetSpec, *, cache_dir: str | Path, data_root: str | Path | None = None,
                     progress: bool = True) -> FrameSequences:
    """The split described by ``spec``, from the cache, rendering the missing shards first.

    Args:
        spec: what to load.
        cache_dir: the cache directory (created if needed).
        data_root: folder holding ``mocap/`` and ``face/`` (default :func:`default_data_root`).
        progress: show a progress bar while rendering.
    """
    folder = cache_folder(cache_dir, spec)
    folder.mkdir(parents=True, exist_ok=True)
    spec_file = folder / "spec.json"
    if not spec_file.exists():
        spec_file.write_text(json.dumps({**asdict(spec), "version": DATA_VERSION}, indent=1, sort_keys=True))
    shards = [folder / f"shard-{k:05d}.npz" for k in range(spec.num_shards)]
    missing = [k for k, p in enumerate(shards) if not p.is_file()]
    if missing:
        from motion2video.frames.render_data import render_shard, SequenceSource

        source = SequenceSource.create(spec, data_root=data_root)
        try:
            bar = None
            if progress:
                from tqdm import tqdm

                todo = sum(min(spec.sequences_per_shard, spec.num_sequences - k * spec.sequences_per_shard)
                           for k in missing)
                bar = tqdm(total=todo, desc=f"rendering {spec.domain} {spec.split} sequences", unit="seq")
            for k in missing:
                save_shard(shards[k], render_shard(source, k, on_sequence=bar.update if bar else None))
            if bar is not None:
                bar.close()
        finally:
            source.close()
    return FrameSequences.concatenate([load_shard(p) for p in shards])


# --- a toy dataset for unit tests (no renderer) -----------------------------------------------------------

# A standing 2D h36m-17 skeleton in units of body height, origin at the pelvis, y down.
_TOY_REST = np.array([
    [0.0, 0.0], [-0.06, 0.0], [-0.07, 0.24], [-0.07, 0.47], [0.06, 0.0], [0.07, 0.24], [0.07, 0.47],
    [0.0, -0.12], [0.0, -0.26], [0.0, -0.32], [0.0, -0.40],
    [0.11, -0.26], [0.16, -0.10], [0.19, 0.04], [-0.11, -0.26], [-0.16, -0.10], [-0.19, 0.04],
])


def toy_sequences(domain: str = "body", *, num_sequences: int = 8, frames_per_sequence: int = 4,
                  image_size: int = 32, seed: int = 0) -> FrameSequences:
    """A tiny dataset drawn with OpenCV for unit tests of the network, training loop and evaluation.

    Bodies: a 2D stick puppet (thick limbs in identity colours) whose limbs swing between frames, on a
    background crop. Faces: a shaded ellipse head that moves and opens its mouth; its structure image is
    the same drawing in grey. Not a substitute for the rendered data.
    """
    import cv2

    rng = np.random.default_rng([seed, 99])
    pool = background_images()[:3]
    n, t, s = num_sequences, frames_per_sequence, image_size
    images = np.zeros((n, t, s, s, 3), np.uint8)
    struct = np.zeros((n, t, s, s), np.uint8) if domain == "face" else None
    k = H36M_17.num_joints if domain == "body" else 12
    points = np.zeros((n, t, k, 2), np.float32)
    masks = np.zeros((n, t, s, s), bool)
    width = max(1, s // 12)
    for i in range(n):
        bg = background_crop(rng, pool, s)
        ident = sample_identity(rng)
        colours = [tuple(int(255 * c) for c in col) for col in (ident.top, ident.trousers, ident.skin)]
        centre = rng.uniform(0.4, 0.6, 2) * s
        for j in range(t):
            frame = bg.copy()
            if domain == "body":
                pose = _TOY_REST.copy()
                pose[[12, 13, 15, 16, 2, 3, 5, 6]] += rng.normal(0, 0.05, (8, 2))
                pts = centre + pose * 0.8 * s + rng.normal(0, 0.02 * s, 2)
                for b, (pa, ch) in enumerate(H36M_17.bones):
                    col = colours[1] if ch <= 6 else colours[0] if ch <= 8 or ch in (11, 14) else colours[2]
                    cv2.line(frame, tuple(int(v) for v in pts[pa]), tuple(int(v) for v in pts[ch]), col, width + 1)
                cv2.circle(frame, tuple(int(v) for v in pts[10]), width + 1, colours[2], -1)
            else:
                c = centre + rng.normal(0, 0.04 * s, 2)
                angle = rng.uniform(-20, 20)
                axes = (int(0.22 * s), int(0.3 * s))
                mouth = rng.uniform(0.0, 0.08) * s
                grey = np.zeros((s, s), np.uint8)
                for canvas, col, dark in ((frame, colours[2], (40, 20, 20)), (grey, 200, 60)):
                    cv2.ellipse(canvas, tuple(int(v) for v in c), axes, angle, 0, 360, col, -1)
                    m = c + np.array([0.0, 0.15 * s])
                    cv2.ellipse(canvas, tuple(int(v) for v in m), (int(0.08 * s), int(mouth) + 1), angle, 0, 360,
                                dark, -1)
                struct[i, j] = grey
                ang = np.linspace(0, 2 * np.pi, 8, endpoint=False)
                ring = np.stack([axes[0] * np.cos(ang), axes[1] * np.sin(ang)], 1)
                mouth_pts = np.array([[-0.08 * s, 0.15 * s], [0.08 * s, 0.15 * s], [0, 0.15 * s - mouth],
                                      [0, 0.15 * s + mouth]])
                rot = np.deg2rad(angle)
                r = np.array([[np.cos(rot), -np.sin(rot)], [np.sin(rot), np.cos(rot)]])
                pts = c + np.concatenate([ring, mouth_pts]) @ r.T
            images[i, j] = frame
            masks[i, j] = np.any(frame != bg, axis=-1)
            points[i, j] = pts
    return FrameSequences(domain=domain, images=images, points=points, structure_images=struct,
                          identity=np.arange(n, dtype=np.int64), clip=np.array(["toy"] * n),
                          start=np.zeros(n, np.int64), masks=masks)
