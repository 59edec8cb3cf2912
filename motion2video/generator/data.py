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
``CACHE/<domain>-<size>-<split>-<hash>/shard-00000.npz`` + ``spec.json`` (body test splits: + ``heads-00000.npz``,
the visible head of every frame); an interrupted generation resumes at the first missing shard.
"""

from __future__ import annotations

import json
import os
import zlib
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from motion2video.core.atomic import save_npz, write_text
from motion2video.core.errors import InputError
from motion2video.core.skeletons import H36M_17
from motion2video.generator.specs import (
    DATA_VERSION,
    DatasetSpec,
    FrameSequences,
    SequencesWithHeads,
    background_crop,
    background_images,
    sample_identity,
)

BODY_STRUCTURE_CHANNELS = H36M_17.num_joints + len(H36M_17.bones)  # 17 heatmaps + 16 limbs = 33
FACE_STRUCTURE_CHANNELS = 1


def structure_channels(domain: str) -> int:
    """Number of structure channels the generator takes for ``domain``."""
    if domain == "body":
        return BODY_STRUCTURE_CHANNELS
    if domain == "face":
        return FACE_STRUCTURE_CHANNELS
    raise ValueError(f"unknown domain {domain!r}")


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


def pooled_body_structures(points: np.ndarray, size: int, factor: int) -> np.ndarray:
    """:func:`body_structures` at ``size`` averaged over ``factor`` x ``factor`` pixel blocks (what a network working
    at 1 / ``factor`` of the image size reads of them), built without the full-size maps.

    The heatmaps are separable, so their block averages are the outer product of the 1-D Gaussians' block averages;
    the limb maps are drawn at ``size`` (the line's anti-aliasing is the full-size one) and their uint8 blocks summed.
    Equal to ``F.avg_pool2d(body_structures(points, size), factor)`` up to float32 rounding (1e-6), and a sixteenth
    of the memory at ``factor`` 4: building, joining and pooling 33 full-size maps was a quarter of the mesh
    generator's time per frame at 256 px (``scripts/bench.py mesh-video``).

    Args:
        points: (B, 17, 2) canonical h36m-17 joints in pixels of the ``size`` image.
        size: the image's width = height, a multiple of ``factor``.
        factor: the block side (1 gives :func:`body_structures`).
    Returns:
        (B, 33, size // factor, size // factor) float32 in [0, 1].
    """
    from renderers.skeleton import gaussian_profiles, render_limb_maps

    if factor == 1:
        return body_structures(points, size)
    points = np.asarray(points, np.float64)
    if points.ndim != 3 or points.shape[1:] != (H36M_17.num_joints, 2):
        raise ValueError(f"points must be (B, 17, 2), got {points.shape}")
    if size % factor:
        raise ValueError(f"size {size} is not a multiple of the block side {factor}")
    small = size // factor
    gx, gy = gaussian_profiles(points, (size, size), heatmap_sigma(size))  # (B, 17, size) each
    gx = gx.reshape(*gx.shape[:2], small, factor).mean(axis=-1).astype(np.float32)  # (B, 17, small)
    gy = gy.reshape(*gy.shape[:2], small, factor).mean(axis=-1).astype(np.float32)
    heat = gy[..., :, None] * gx[..., None, :]  # (B, 17, small, small)
    limbs = render_limb_maps(points, H36M_17, (size, size), thickness=limb_thickness(size), as_uint8=True)
    b, n = limbs.shape[:2]
    sums = limbs.reshape(b, n, small, factor, small, factor).sum(axis=(3, 5), dtype=np.uint32)
    return np.concatenate([heat, sums.astype(np.float32) / np.float32(255 * factor * factor)], axis=1)


def face_structures(images: np.ndarray) -> np.ndarray:
    """Face structure maps from rendered shaded face meshes: (B, H, W) uint8 -> (B, 1, H, W) float32."""
    images = np.asarray(images)
    if images.ndim != 3:
        raise ValueError(f"face structure images must be (B, H, W), got {images.shape}")
    return images[:, None].astype(np.float32) / 255.0


# --- sequences and pairs --------------------------------------------------------------------------------

@dataclass
class FramePairs:
    """A batch of (reference, target) pairs with everything the generator and the baselines need.

    Attributes:
        ref_images, tgt_images: (B, H, W, 3) uint8.
        ref_points, tgt_points: (B, K, 2) float32 control points, pixels.
        ref_structures, tgt_structures: (B, S, H, W) float32 structure maps.
        ref_masks, tgt_masks: (B, H, W) bool person silhouettes, or None when the sequences have none.
        mesh_flow: (B, H, W, 2) float32 the mesh correspondence target -> reference (reference pixels), or
            None when the sequences keep no mesh vertices (:func:`generator.mesh_flow.dense_flow`).
        mesh_visibility: (B, H, W) float32 how much of each target pixel's surface the reference shows, or None.
        mesh_ref_masks, mesh_tgt_masks: (B, H, W) bool silhouettes of the fitted mesh when they differ from the
            person masks (a body fitted to real frames), or None (rendered data: the masks are the mesh's).
        head_mattes: (B, H, W) float32 the face the reference shows (its matte in the reference's pixels,
            :func:`generator.head_paste.face_matte`), laid over the mesh generator's heads; None: no face.
        head_affines: (B, 2, 3) reference pixels -> target pixels of that face; head_weights: (B,) how much of it
            each target takes; head_shown: (B, L) bool the target shows each of its landmarks
            (:class:`generator.head_paste.HeadMoves`).
        head_landmarks: (B, L, 2) the face's landmarks in the reference's pixels; head_triangles: (B, T, 3) int their
            triangles (:func:`generator.head_paste.shown_face`); head_offsets: (B, L, 2) each landmark's offset in
            the target from where the affine map puts it (:class:`generator.head_paste.FaceBend`).
    """

    ref_images: np.ndarray
    tgt_images: np.ndarray
    ref_points: np.ndarray
    tgt_points: np.ndarray
    ref_structures: np.ndarray
    tgt_structures: np.ndarray
    ref_masks: np.ndarray | None = None
    tgt_masks: np.ndarray | None = None
    mesh_flow: np.ndarray | None = None
    mesh_visibility: np.ndarray | None = None
    mesh_ref_masks: np.ndarray | None = None
    mesh_tgt_masks: np.ndarray | None = None
    head_mattes: np.ndarray | None = None
    head_affines: np.ndarray | None = None
    head_weights: np.ndarray | None = None
    head_shown: np.ndarray | None = None
    head_landmarks: np.ndarray | None = None
    head_triangles: np.ndarray | None = None
    head_offsets: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.ref_images.shape[0])

    def subset(self, rows) -> "FramePairs":
        """The pairs at ``rows`` (a slice or an index array)."""
        return FramePairs(**{f.name: None if getattr(self, f.name) is None else getattr(self, f.name)[rows]
                             for f in fields(self)})


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
        The pairs, structures computed for the (possibly flipped, cropped) frames; with the mesh
        correspondence when the sequences keep mesh vertices.
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
    mesh_flow = mesh_vis = None
    if seqs.vertex_uv is not None and tgt_mask is not None:
        mesh_flow, mesh_vis = pair_mesh_flows(seqs, index, flip, origins if crop else None, tgt_mask,
                                              ref_images=ref_img)
    if seqs.domain == "body":
        ref_st, tgt_st = body_structures(ref_pts, size), body_structures(tgt_pts, size)
    else:
        ref_st, tgt_st = face_structures(ref_face), face_structures(tgt_face)
    masks = (None, None) if ref_mask is None else (np.ascontiguousarray(ref_mask), np.ascontiguousarray(tgt_mask))
    return FramePairs(np.ascontiguousarray(ref_img), np.ascontiguousarray(tgt_img), ref_pts, tgt_pts,
                      ref_st, tgt_st, *masks, mesh_flow=mesh_flow, mesh_visibility=mesh_vis)


def pair_mesh_flows(seqs: FrameSequences, index: np.ndarray, flip: np.ndarray | None, origins: np.ndarray | None,
                    tgt_masks: np.ndarray, *, ref_images: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The mesh correspondence of every pair of ``index`` (B, 3) after its flip and crop (``origins`` (B, 2)
    or None), filling the (already flipped and cropped) target silhouettes ``tgt_masks`` (B, h, w) and a band
    around them (:func:`generator.mesh_flow.extend_flow`). ``ref_images`` (B, h, w, 3), the flipped and cropped
    reference images, let the completion of hidden surface test its sources' colours
    (:func:`generator.mesh_flow.complete_reference_uv`).

    Returns:
        flow (B, h, w, 2) float32 reference pixels, visibility (B, h, w) float32.
    """
    from motion2video.generator.mesh_flow import band_width, dense_flow, extend_flow, mesh_triangles, transform_uv

    triangles = mesh_triangles()  # the flow is read from the target's triangles where they show whole
    flows, vis = [], []
    for k, (s, r, t) in enumerate(np.asarray(index, np.int64)):
        f = bool(flip[k]) if flip is not None else False
        origin = tuple(float(v) for v in origins[k]) if origins is not None else (0.0, 0.0)
        ref_uv = transform_uv(seqs.vertex_uv[s, r], size=seqs.image_size, flip=f, origin=origin)
        tgt_uv = transform_uv(seqs.vertex_uv[s, t], size=seqs.image_size, flip=f, origin=origin)
        mf = dense_flow(ref_uv, seqs.vertex_visible[s, r], tgt_uv, seqs.vertex_visible[s, t], tgt_masks[k],
                        image=None if ref_images is None else ref_images[k], triangles=triangles)
        mf = extend_flow(mf, band_width(seqs.image_size))
        flows.append(mf.flow)
        vis.append(mf.visibility)
    return np.stack(flows), np.stack(vis)


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


# --- dataset specification and the cache ----------------------------------------------------------------

def save_shard(path: Path, seqs: FrameSequences) -> None:
    """Write sequences to an npz shard atomically (tmp file + rename)."""
    arrays = dict(images=seqs.images, points=seqs.points.astype(np.float32), identity=seqs.identity,
                  clip=np.asarray(seqs.clip, dtype=str), start=seqs.start, domain=np.asarray(seqs.domain))
    if seqs.structure_images is not None:
        arrays["structure_images"] = seqs.structure_images
    if seqs.masks is not None:
        arrays["masks"] = seqs.masks
    if seqs.vertex_uv is not None:
        arrays["vertex_uv"] = seqs.vertex_uv.astype(np.float16)
        arrays["vertex_visible"] = seqs.vertex_visible
    save_npz(path, arrays, compressed=True)


def load_shard(path: Path) -> FrameSequences:
    try:
        with np.load(path, allow_pickle=False) as z:
            return FrameSequences(
                domain=str(z["domain"]), images=z["images"], points=z["points"],
                structure_images=z["structure_images"] if "structure_images" in z.files else None,
                identity=z["identity"], clip=z["clip"], start=z["start"],
                masks=z["masks"] if "masks" in z.files else None,
                vertex_uv=z["vertex_uv"] if "vertex_uv" in z.files else None,
                vertex_visible=z["vertex_visible"] if "vertex_visible" in z.files else None,
            )
    except (OSError, KeyError, ValueError, zlib.error) as err:
        raise InputError(f"unreadable cache shard ({type(err).__name__}: {err}); delete it to regenerate",
                         path) from None


def cache_folder(cache_dir: str | Path, spec: DatasetSpec) -> Path:
    return Path(cache_dir) / spec.key()


def heads_file(shard: Path) -> Path:
    """The head masks cached beside a body shard: ``shard-00000.npz`` -> ``heads-00000.npz``."""
    return shard.with_name("heads-" + shard.name.removeprefix("shard-"))


def load_heads(path: Path) -> np.ndarray:
    """(N, T, S, S) bool head masks of one shard (:func:`heads_file`)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            return z["head_masks"]
    except (OSError, KeyError, ValueError, zlib.error) as err:
        raise InputError(f"unreadable cache file ({type(err).__name__}: {err}); delete it to regenerate",
                         path) from err


def _ready_shards(spec: DatasetSpec, cache_dir: str | Path, data_root: str | Path | None, progress: bool, *,
                  heads: bool) -> list[Path]:
    """The shard files of ``spec`` in the cache, rendering the missing ones first. Body splits of the test
    split keep the visible head of every frame beside each shard (:func:`heads_file`), as ``heads`` asks of any
    body split; a shard without them (a cache written before they were kept) is rendered again with them."""
    folder = cache_folder(cache_dir, spec)
    folder.mkdir(parents=True, exist_ok=True)
    spec_file = folder / "spec.json"
    if not spec_file.exists():
        # atomically: test workers and training runs may fill one cache side by side
        write_text(spec_file, json.dumps({**asdict(spec), "version": DATA_VERSION}, indent=1, sort_keys=True))
    shards = [folder / f"shard-{k:05d}.npz" for k in range(spec.num_shards)]
    with_heads = spec.domain == "body" and (heads or spec.split == "test")
    missing = [k for k, p in enumerate(shards) if not p.is_file() or (with_heads and not heads_file(p).is_file())]
    if not missing:
        return shards
    from motion2video.generator.render_data import render_shard, SequenceSource

    source = SequenceSource.create(spec, data_root=data_root)
    bar = None
    try:
        if progress:
            from tqdm import tqdm

            todo = sum(min(spec.sequences_per_shard, spec.num_sequences - k * spec.sequences_per_shard)
                       for k in missing)
            bar = tqdm(total=todo, desc=f"rendering {spec.domain} {spec.split} sequences", unit="seq")
        for k in missing:
            seqs, head_masks = render_shard(source, k, heads=with_heads, on_sequence=bar.update if bar else None)
            if head_masks is not None:  # before the shard: a shard on disk without its heads is rendered again
                save_npz(heads_file(shards[k]), {"head_masks": head_masks}, compressed=True)
            save_shard(shards[k], seqs)
    finally:
        if bar is not None:
            bar.close()
        source.close()
    return shards


def load_or_generate(spec: DatasetSpec, *, cache_dir: str | Path, data_root: str | Path | None = None,
                     progress: bool = True) -> FrameSequences:
    """The split described by ``spec``, from the cache, rendering the missing shards first.

    Args:
        spec: what to load.
        cache_dir: the cache directory (created if needed).
        data_root: folder holding ``mocap/`` and ``face/`` (default :func:`default_data_root`).
        progress: show a progress bar while rendering.
    """
    shards = _ready_shards(spec, cache_dir, data_root, progress, heads=False)
    return FrameSequences.concatenate([load_shard(p) for p in shards])


def load_or_generate_with_heads(spec: DatasetSpec, *, cache_dir: str | Path, data_root: str | Path | None = None,
                                progress: bool = True) -> SequencesWithHeads:
    """A body split (:func:`load_or_generate`) and the visible head of every frame, (N, T, S, S) bool: the
    pixels where Anny's head vertices are the front surface. Both come from the cache; shards without head
    masks are rendered again with them, once."""
    if spec.domain != "body":
        raise ValueError("head masks are rendered for body splits only")
    shards = _ready_shards(spec, cache_dir, data_root, progress, heads=True)
    return SequencesWithHeads(FrameSequences.concatenate([load_shard(p) for p in shards]),
                              np.concatenate([load_heads(heads_file(p)) for p in shards]))


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
