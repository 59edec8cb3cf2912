"""What the frame generator's synthetic dataset is made of: the dataset specification, the sequences
container, the train/test split of captures, the identities (phenotype and colours) and the backgrounds.

Split out of :mod:`motion2video.generator.data` so that :mod:`motion2video.generator.render_data` (which renders
sequences) and :mod:`motion2video.generator.data` (which caches them, rendering missing shards) do not import each
other: both import this module.
"""

from __future__ import annotations

import hashlib
import json
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np


SPLITS = ("train", "test")
# 2: person masks stored, patterned clothing, 24 backgrounds; 3: body control points on canonical skeleton
# version 2 (core.skeletons.SKELETON_VERSION), so renders cached with the old joints are not reused
DATA_VERSION = 3
# Face splits with vertices: 2 = the head vertices' front-surface test at 1 cm (renderers.face.
# FACE_VISIBILITY_TOLERANCE_M; it was 2.5 cm); 3 = the mouth cavity's at 2 mm (MOUTH_VISIBILITY_TOLERANCE_M): face
# correspondence cached before either is not reused.
FACE_VISIBILITY_VERSION = 3


def default_data_root() -> Path:
    """``../shared/data`` beside the repository root (where the real captures live on this machine)."""
    return Path(__file__).resolve().parents[2].parent / "shared" / "data"


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
        vertex_uv: (N, T, V, 2) float16 the body mesh vertices' pixel positions, or None.
        vertex_visible: (N, T, V) bool, each vertex is the front surface (:mod:`generator.mesh_flow`), or None.
    """

    domain: str
    images: np.ndarray
    points: np.ndarray
    structure_images: np.ndarray | None
    identity: np.ndarray
    clip: np.ndarray
    start: np.ndarray
    masks: np.ndarray | None = None
    vertex_uv: np.ndarray | None = None
    vertex_visible: np.ndarray | None = None

    def __post_init__(self) -> None:
        n, t, h, w, c = self.images.shape
        if (self.vertex_uv is None) != (self.vertex_visible is None):
            raise ValueError("vertex_uv and vertex_visible come together")
        if self.vertex_uv is not None and (self.vertex_uv.shape[:2] != (n, t) or self.vertex_uv.shape[-1] != 2
                                           or self.vertex_visible.shape != self.vertex_uv.shape[:3]):
            raise ValueError(f"vertex_uv must be (N, T, V, 2) and vertex_visible (N, T, V) matching images, got "
                             f"{self.vertex_uv.shape} and {self.vertex_visible.shape}")
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
        meshed = all(p.vertex_uv is not None for p in parts)
        return FrameSequences(
            domain=parts[0].domain,
            images=np.concatenate([p.images for p in parts]),
            points=np.concatenate([p.points for p in parts]),
            structure_images=np.concatenate([p.structure_images for p in parts]) if face else None,
            identity=np.concatenate([p.identity for p in parts]),
            clip=np.concatenate([p.clip for p in parts]),
            start=np.concatenate([p.start for p in parts]),
            masks=np.concatenate([p.masks for p in parts]) if masked else None,
            vertex_uv=np.concatenate([p.vertex_uv for p in parts]) if meshed else None,
            vertex_visible=np.concatenate([p.vertex_visible for p in parts]) if meshed else None,
        )


@dataclass
class SequencesWithHeads:
    """Rendered body sequences and the visible head of every frame: ``head_masks`` (N, T, S, S) bool, the pixels
    where Anny's head vertices are the front surface (:meth:`renderers.body.BodyRenderer.render_with_masks`)."""

    sequences: FrameSequences
    head_masks: np.ndarray


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
        vertices: also keep the mesh vertices' pixels and visibility of every frame (the mesh generator's
            correspondence; body: Anny's 13,718 vertices, about 69 KB per frame; face: the drawn head sub-mesh).
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
    vertices: bool = False

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
        fields = asdict(self)
        if not self.vertices:  # the key of a split without vertices is what it was before the field existed
            del fields["vertices"]
        elif self.domain == "face":
            fields["face_visibility"] = FACE_VISIBILITY_VERSION
        blob = json.dumps({**fields, "version": DATA_VERSION}, sort_keys=True).encode()
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
