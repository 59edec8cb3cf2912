"""Evaluation of a frame generator against the baselines on the same held-out pairs, and contact sheets.

Metrics, computed per pair on uint8 RGB frames (data range 255) and averaged over pairs:

- whole frame: scikit-image's PSNR and SSIM;
- person (over the target person's rendered silhouette): PSNR of the silhouette's pixels, the mean of
  scikit-image's SSIM map inside it, and the *sharpness ratio*: the mean squared Sobel gradient magnitude
  of the grey image inside the silhouette, generated / truth (1.0 = as sharp as the truth; a blurry
  person scores below 1);
- moving region (pixels of either person's silhouette where reference and target differ by more than
  :data:`MOVING_THRESHOLD` in some channel): PSNR and the sharpness ratio;
- head (over the target's visible head: the pixels where the Anny head vertices are the front surface,
  :meth:`renderers.body.BodyRenderer.render_with_masks` with ``head=True``): PSNR and the mean of the SSIM map
  inside it (``head_psnr``, ``head_ssim``). Only evaluations that rendered head masks have them
  (``evaluate-frames --poses``); elsewhere they are null.

The person metrics need sequences with masks (rendered caches of data version 2); without them they are
NaN.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

from motion2video.generator.background import composite, inpaint_background, soft_matte
from motion2video.generator.image_baselines import BASELINES, run_baseline
from motion2video.generator.data import FramePairs, evaluation_pair_index, make_pairs
from motion2video.generator.head_paste import lay_moved_face
from motion2video.generator.specs import FrameSequences
from motion2video.generator.mesh_warp import MeshWarpGenerator, head_cut, mesh_inputs, mesh_source_mask
from motion2video.generator.model import FrameGenerator, generate, images_to_tensor
from motion2video.generator.warp import WarpGenerator, warp_generate

METHODS = ("generator",) + BASELINES
MOVING_THRESHOLD = 10  # uint8 levels: a pixel "moved" when reference and target differ by more


def frame_metrics(pred: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame PSNR (dB) and SSIM.

    Args:
        pred, target: (N, H, W, 3) uint8.
    Returns:
        psnr (N,) float64, ssim (N,) float64.
    """
    psnr = frame_psnr(pred, target)
    ssim = np.array([structural_similarity(t, p, channel_axis=-1, data_range=255) for p, t in zip(pred, target)],
                    np.float64)
    return psnr, ssim


def frame_psnr(pred: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Per-frame PSNR (dB) of (N, H, W, 3) uint8 frames: (N,) float64."""
    if pred.shape != target.shape or pred.dtype != np.uint8 or target.dtype != np.uint8:
        raise ValueError(f"pred and target must be uint8 of one shape, got {pred.shape} {pred.dtype} and "
                         f"{target.shape} {target.dtype}")
    return np.array([peak_signal_noise_ratio(t, p, data_range=255) for p, t in zip(pred, target)], np.float64)


def gradient_energy(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 -> (H, W) squared Sobel gradient magnitude of the grey image (levels 0..255)."""
    import cv2

    grey = image.astype(np.float32).mean(axis=-1)
    gx = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    return gx * gx + gy * gy


def region_psnr(pred: np.ndarray, target: np.ndarray, mask: np.ndarray) -> float:
    """PSNR (dB) over the pixels of ``mask`` (H, W) bool of (H, W, 3) uint8 frames; NaN for an empty mask."""
    if not mask.any():
        return float("nan")
    mse = float(((pred.astype(np.float64) - target.astype(np.float64)) ** 2)[mask].mean())
    return float(10.0 * np.log10(255.0**2 / max(mse, 1e-10)))


def sharpness_ratio(pred: np.ndarray, target: np.ndarray, mask: np.ndarray) -> float:
    """Mean gradient energy of ``pred`` inside ``mask`` / that of ``target`` (NaN for an empty mask or a
    flat truth)."""
    if not mask.any():
        return float("nan")
    truth = float(gradient_energy(target)[mask].mean())
    return float(gradient_energy(pred)[mask].mean() / truth) if truth > 0 else float("nan")


def moving_region(ref: np.ndarray, target: np.ndarray, ref_mask: np.ndarray, tgt_mask: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels of either silhouette where the reference and the target frame differ."""
    diff = np.abs(ref.astype(np.int16) - target.astype(np.int16)).max(axis=-1) > MOVING_THRESHOLD
    return diff & (ref_mask | tgt_mask)


PERSON_METRICS = ("person_psnr", "person_ssim", "person_sharpness", "moving_psnr", "moving_sharpness")
HEAD_METRICS = ("head_psnr", "head_ssim")
COLOUR_REGIONS = ("hair", "skin")  # faces: "<region>_colour_de", the colour difference of the region's mean colour
MIN_REGION_PIXELS = 16  # a region smaller than this in a target frame is not scored (NaN)


def mean_colour_difference(pred: np.ndarray, target: np.ndarray, mask: np.ndarray) -> float:
    """CIE76 colour difference (Delta E*ab, CIELAB units; about 2.3 is just noticeable) between the mean colours of
    two (H, W, 3) uint8 frames over the pixels of ``mask`` (H, W) bool: whether a region keeps its colour (brown
    hair that turns olive), whatever its texture. NaN when the mask has fewer than :data:`MIN_REGION_PIXELS`."""
    from skimage.color import rgb2lab

    if int(mask.sum()) < MIN_REGION_PIXELS:
        return float("nan")
    a = rgb2lab(pred[mask][None].astype(np.float64) / 255.0)[0].mean(axis=0)
    b = rgb2lab(target[mask][None].astype(np.float64) / 255.0)[0].mean(axis=0)
    return float(np.linalg.norm(a - b))


def vertex_region_masks(uv: np.ndarray, visible: np.ndarray, masks: np.ndarray, labels: np.ndarray,
                        regions: dict[str, int]) -> dict[str, np.ndarray]:
    """Pixels of each region in rendered frames: every silhouette pixel takes the label of its nearest visible
    vertex.

    Args:
        uv: (N, V, 2) vertex pixels; visible: (N, V) bool; masks: (N, H, W) bool silhouettes.
        labels: (V,) int region code per vertex; regions: name -> code.
    Returns:
        name -> (N, H, W) bool.
    """
    from scipy.spatial import cKDTree

    from motion2video.generator.mesh_flow import pixel_centres

    out = {name: np.zeros(masks.shape, bool) for name in regions}
    for i in range(len(masks)):
        seen = np.flatnonzero(visible[i])
        if len(seen) == 0 or not masks[i].any():
            continue
        _, idx = cKDTree(np.asarray(uv[i], np.float64)[seen]).query(pixel_centres(masks[i]))
        code = labels[seen[idx]]
        ys, xs = np.nonzero(masks[i])
        for name, value in regions.items():
            keep = code == value
            out[name][i, ys[keep], xs[keep]] = True
    return out


def face_region_masks(seqs: FrameSequences) -> dict[str, np.ndarray]:
    """:data:`COLOUR_REGIONS` pixels of every frame of face sequences that keep their vertices: name ->
    (N, T, H, W) bool (the region of each vertex from Anny's colour regions on the default body)."""
    from renderers import anny_model

    labels = anny_model.region_weights().argmax(axis=1)
    codes = {name: anny_model.REGION_NAMES.index(name) for name in COLOUR_REGIONS}
    n, t = seqs.images.shape[:2]
    flat = vertex_region_masks(seqs.vertex_uv.reshape(n * t, -1, 2).astype(np.float32),
                               seqs.vertex_visible.reshape(n * t, -1), seqs.masks.reshape(n * t, *seqs.masks.shape[2:]),
                               labels, codes)
    return {name: m.reshape(n, t, *m.shape[1:]) for name, m in flat.items()}


def region_ssim(ssim_map: np.ndarray, mask: np.ndarray) -> float:
    """Mean of an (H, W, 3) SSIM map over the pixels of ``mask`` (H, W) bool; NaN for an empty mask."""
    return float(ssim_map.mean(axis=-1)[mask].mean()) if mask.any() else float("nan")


def person_metrics(pred: np.ndarray, target: np.ndarray, ref: np.ndarray, ref_masks: np.ndarray,
                   tgt_masks: np.ndarray, tgt_head_masks: np.ndarray | None = None,
                   tgt_regions: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
    """Per-pair person metrics (:data:`PERSON_METRICS`, :data:`HEAD_METRICS` with head masks, and
    ``<region>_colour_de`` for every region given).

    Args:
        pred, target, ref: (N, H, W, 3) uint8 frames; ref_masks, tgt_masks: (N, H, W) bool silhouettes;
        tgt_head_masks: (N, H, W) bool visible head of the target, or None;
        tgt_regions: region name -> (N, H, W) bool its pixels in the target (:func:`face_region_masks`), or None.
    Returns:
        metric name -> (N,) float64 (NaN where a region is empty).
    """
    return _person_metrics_and_ssim(pred, target, ref, ref_masks, tgt_masks, tgt_head_masks, tgt_regions)[0]


def _person_metrics_and_ssim(pred: np.ndarray, target: np.ndarray, ref: np.ndarray, ref_masks: np.ndarray,
                             tgt_masks: np.ndarray, tgt_head_masks: np.ndarray | None,
                             tgt_regions: dict[str, np.ndarray] | None) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """:func:`person_metrics` and the whole-frame SSIM of every pair (N,), from the one SSIM map each pair needs
    (scikit-image's whole-frame SSIM is the mean of that map inside its border)."""
    regions = tgt_regions or {}
    keys = PERSON_METRICS + (HEAD_METRICS if tgt_head_masks is not None else ()) + \
        tuple(f"{name}_colour_de" for name in regions)
    out = {k: np.empty(len(pred)) for k in keys}
    whole = np.empty(len(pred))
    for i, (p, t, r, mr, mt) in enumerate(zip(pred, target, ref, ref_masks, tgt_masks)):
        whole[i], smap = structural_similarity(t, p, channel_axis=-1, data_range=255, full=True)
        moving = moving_region(r, t, mr, mt)
        out["person_psnr"][i] = region_psnr(p, t, mt)
        out["person_ssim"][i] = region_ssim(smap, mt)
        out["person_sharpness"][i] = sharpness_ratio(p, t, mt)
        out["moving_psnr"][i] = region_psnr(p, t, moving)
        out["moving_sharpness"][i] = sharpness_ratio(p, t, moving)
        if tgt_head_masks is not None:
            out["head_psnr"][i] = region_psnr(p, t, tgt_head_masks[i])
            out["head_ssim"][i] = region_ssim(smap, tgt_head_masks[i])
        for name, region in regions.items():
            out[f"{name}_colour_de"][i] = mean_colour_difference(p, t, region[i])
    return out, whole


@dataclass
class MethodScores:
    """Mean scores of one method over the pairs, with the per-pair values.

    ``person`` maps each of :data:`PERSON_METRICS` to its mean over the pairs (NaN pairs left out);
    ``person_per_pair`` holds the (N,) values.
    """

    psnr: float
    ssim: float
    psnr_per_pair: np.ndarray = field(repr=False)
    ssim_per_pair: np.ndarray = field(repr=False)
    person: dict[str, float] = field(default_factory=dict)
    person_per_pair: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @staticmethod
    def from_frames(pred: np.ndarray, target: np.ndarray, *, ref: np.ndarray | None = None,
                    ref_masks: np.ndarray | None = None, tgt_masks: np.ndarray | None = None,
                    tgt_head_masks: np.ndarray | None = None,
                    tgt_regions: dict[str, np.ndarray] | None = None) -> "MethodScores":
        if ref is None or ref_masks is None or tgt_masks is None:
            psnr, ssim = frame_metrics(pred, target)
            return MethodScores.from_per_pair(psnr, ssim, {})
        psnr = frame_psnr(pred, target)
        per, ssim = _person_metrics_and_ssim(pred, target, ref, ref_masks, tgt_masks, tgt_head_masks, tgt_regions)
        return MethodScores.from_per_pair(psnr, ssim, per)

    @staticmethod
    def from_per_pair(psnr: np.ndarray, ssim: np.ndarray, per: dict[str, np.ndarray]) -> "MethodScores":
        means = {k: float(np.nanmean(v)) if np.any(np.isfinite(v)) else float("nan") for k, v in per.items()}
        return MethodScores(float(psnr.mean()), float(ssim.mean()), psnr, ssim, means, per)

    def to_dict(self) -> dict:
        """``psnr``, ``ssim`` and every person and head metric (null when not measured or not finite)."""
        out = {"psnr": round(self.psnr, 4), "ssim": round(self.ssim, 5)}
        out.update({k: None for k in PERSON_METRICS + HEAD_METRICS})
        out.update({k: (round(v, 4) if np.isfinite(v) else None) for k, v in self.person.items()})
        return out


@dataclass
class FrameEvaluation:
    """Scores of the generator and the baselines on one set of pairs.

    Attributes:
        results: method name -> scores (``generator``, ``copy-reference``, ``limb-warp``).
        num_pairs: number of evaluated pairs.
        domain, image_size: what was evaluated.
        predictions: method name -> (N, H, W, 3) uint8 frames (for contact sheets), plus ``reference`` and
            ``target``.
        pairs: ``"held-out"`` (the frame test split) or ``"poses"`` (posed by real motion, with head metrics:
            :mod:`motion2video.generator.poses`); it picks the targets.
    """

    results: dict[str, MethodScores]
    num_pairs: int
    domain: str
    image_size: int
    predictions: dict[str, np.ndarray] = field(repr=False, default_factory=dict)
    pairs: str = "held-out"

    def to_dict(self) -> dict:
        """The JSON shape: ``{"results": {method: {"psnr", "ssim", "person_psnr", ...}}, "num_pairs",
        "domain", "image_size"}`` (person metrics are null without masks)."""
        return {
            "results": {k: v.to_dict() for k, v in self.results.items()},
            "num_pairs": self.num_pairs,
            "domain": self.domain,
            "image_size": self.image_size,
            "pairs": self.pairs,
        }

    def targets_met(self) -> dict[str, bool]:
        """The targets (person targets for bodies with person metrics, whole-frame targets otherwise):

        - person PSNR >= limb-warp + 3 dB, >= copy-reference + 5 dB, >= every baseline generator + 2 dB;
        - person sharpness ratio >= 0.9; whole-frame PSNR >= 29 dB; SSIM above every baseline.
        Without person metrics: PSNR >= copy-reference + 3 dB and >= limb-warp + 1 dB; SSIM above both.
        Posed by real motion (``pairs == "poses"``): person and head PSNR >= limb-warp + 3 dB, person
        sharpness ratio >= 0.9.
        """
        g, c, w = (self.results[k] for k in METHODS)
        if self.pairs == "poses":
            def at_least(a: float, b: float) -> bool:
                return bool(np.isfinite(a) and np.isfinite(b) and a >= b)

            gp, wp = g.person, w.person
            return {
                "person_psnr_vs_limb_warp_3db": at_least(gp["person_psnr"], wp["person_psnr"] + 3.0),
                "head_psnr_vs_limb_warp_3db": at_least(gp["head_psnr"], wp["head_psnr"] + 3.0),
                "person_sharpness_0.9": at_least(gp["person_sharpness"], 0.9),
            }
        others = [v for k, v in self.results.items() if k != "generator"]
        if not g.person or not np.isfinite(g.person.get("person_psnr", np.nan)):
            return {
                "psnr_vs_copy_reference_3db": g.psnr >= c.psnr + 3.0,
                "psnr_vs_limb_warp_1db": g.psnr >= w.psnr + 1.0,
                "ssim_above_both": g.ssim > c.ssim and g.ssim > w.ssim,
            }
        pp = g.person["person_psnr"]
        out = {
            "person_psnr_vs_limb_warp_3db": pp >= w.person["person_psnr"] + 3.0,
            "person_psnr_vs_copy_reference_5db": pp >= c.person["person_psnr"] + 5.0,
        }
        for name, v in self.results.items():
            if name not in METHODS:
                out[f"person_psnr_vs_{name}_2db"] = pp >= v.person["person_psnr"] + 2.0
        out["person_sharpness_0.9"] = g.person["person_sharpness"] >= 0.9
        out["psnr_29db"] = g.psnr >= 29.0
        out["ssim_above_every_baseline"] = all(g.ssim > v.ssim for v in others)
        return out


def run_generator(model: FrameGenerator | WarpGenerator | MeshWarpGenerator, pairs: FramePairs, *,
                  batch_size: int = 16) -> np.ndarray:
    """(N, H, W, 3) uint8 frames of a generator of any kind on ``pairs`` (the warp generator through its
    inference path: person crop, generation, soft paste; the mesh generator on the whole frames, with the
    pairs' mesh correspondence)."""
    if isinstance(model, MeshWarpGenerator):
        return mesh_generate(model, pairs, batch_size=batch_size)
    if isinstance(model, WarpGenerator):
        return warp_generate(model, pairs.ref_images, pairs.ref_points, pairs.tgt_points)
    return generate(model, pairs.ref_images, pairs.ref_structures, pairs.tgt_structures, batch_size=batch_size)


@torch.inference_mode()
def mesh_generate(model: MeshWarpGenerator, pairs: FramePairs, *, batch_size: int = 16) -> np.ndarray:
    """(N, H, W, 3) uint8 frames of the mesh generator on pairs that carry their mesh correspondence.

    Pairs of real frames with a fitted body (``mesh_ref_masks`` given) are drawn as ``synthesize`` draws them: the
    reference's person (its segmentation joined with the fitted silhouette) inpainted
    (:func:`motion2video.generator.background.inpaint_background`) is the plate, and the generated person is laid
    over it through its soft matte (:func:`~motion2video.generator.background.soft_matte`), and the reference's face
    over the generated head where the pairs carry it (:func:`~motion2video.generator.head_paste.lay_moved_face`).
    Rendered pairs keep the generator's own composite over its plate
    (:func:`~motion2video.generator.mesh_warp.mesh_plate`), as in training.
    """
    if pairs.mesh_flow is None:
        raise ValueError("the mesh generator needs pairs with their mesh correspondence (sequences that keep "
                         "their mesh vertices)")
    model.eval()
    out = []
    backgrounds: dict[bytes, np.ndarray] = {}  # one inpainting per distinct reference (and its masks)
    for i in range(0, len(pairs), batch_size):
        part = pairs.subset(slice(i, i + batch_size))
        inputs = mesh_inputs(part)
        if part.mesh_ref_masks is None:
            x = model(images_to_tensor(part.ref_images), *inputs, torch.from_numpy(part.tgt_structures),
                      source_mask=mesh_source_mask(part))
            out.append((x.clamp(0, 1) * 255).round().to(torch.uint8).permute(0, 2, 3, 1).numpy())
            continue
        behind = []
        for image, person, fitted in zip(part.ref_images, part.ref_masks, part.mesh_ref_masks):
            key = hashlib.sha1(image.tobytes() + np.packbits(person | fitted).tobytes()).digest()
            if key not in backgrounds:
                backgrounds[key] = inpaint_background(image, person | fitted)
            behind.append(backgrounds[key])
        behind = np.stack(behind)
        segmented = mesh_source_mask(part)
        cut = torch.from_numpy(np.stack([head_cut(m, p) for m, p in zip(part.ref_masks.astype(np.float32),
                                                                         part.ref_points)]))[:, None]
        parts = model.forward_parts(images_to_tensor(part.ref_images), *inputs, torch.from_numpy(part.tgt_structures),
                                    plate=images_to_tensor(behind), source_mask=segmented, person_cut=cut)
        person = parts.person.clamp(0, 1).permute(0, 2, 3, 1).numpy()
        matte = soft_matte(parts.alpha[:, 0].numpy())
        frames = np.concatenate([composite(b, p[None], m[None]) for b, p, m in zip(behind, person, matte)])
        if part.head_mattes is not None:  # the reference's own face over the generated heads, as synthesize does
            frames = np.stack([
                lay_moved_face(f, r, m, a, xy @ a[:, :2].T + a[:, 2], o, t, shown, w, within=p)
                for f, r, m, xy, a, o, t, shown, w, p in
                zip(frames, part.ref_images, part.head_mattes, part.head_landmarks, part.head_affines,
                    part.head_offsets, part.head_triangles, part.head_shown, part.head_weights, matte)])
        out.append(frames)
    return np.concatenate(out)


def evaluate_pairs(model: FrameGenerator | WarpGenerator | None, pairs: FramePairs, *, domain: str,
                   batch_size: int = 16, baseline_models: dict | None = None,
                   tgt_head_masks: np.ndarray | None = None,
                   tgt_regions: dict[str, np.ndarray] | None = None) -> FrameEvaluation:
    """Score the generator (when given), every baseline and every named baseline generator
    (``baseline_models``: name -> model) on ``pairs``; ``tgt_head_masks`` (N, H, W) bool adds the head
    metrics, ``tgt_regions`` (name -> (N, H, W) bool) the colour differences of those regions."""
    preds: dict[str, np.ndarray] = {}
    if model is not None:
        preds["generator"] = run_generator(model, pairs, batch_size=batch_size)
    for name in BASELINES:
        preds[name] = run_baseline(name, pairs.ref_images, pairs.ref_points, pairs.tgt_points)
    for name, other in (baseline_models or {}).items():
        preds[name] = run_generator(other, pairs, batch_size=batch_size)
    results = {name: MethodScores.from_frames(p, pairs.tgt_images, ref=pairs.ref_images, ref_masks=pairs.ref_masks,
                                              tgt_masks=pairs.tgt_masks, tgt_head_masks=tgt_head_masks,
                                              tgt_regions=tgt_regions)
               for name, p in preds.items()}
    preds["reference"] = pairs.ref_images
    preds["target"] = pairs.tgt_images
    return FrameEvaluation(results=results, num_pairs=len(pairs), domain=domain,
                           image_size=int(pairs.ref_images.shape[1]), predictions=preds)


def evaluate_sequences(model: FrameGenerator | WarpGenerator | None, seqs: FrameSequences, *,
                       max_pairs: int | None = None, chunk: int = 64,
                       baseline_models: dict | None = None, head_masks: np.ndarray | None = None,
                       region_masks: dict[str, np.ndarray] | None = None,
                       pairs: str = "held-out") -> FrameEvaluation:
    """Score on the fixed evaluation pairs of ``seqs`` (:func:`evaluation_pair_index`), in chunks so the
    structure maps of every pair are never all in memory at once. ``head_masks`` (N, T, H, W) bool, the
    visible head of every frame, adds the head metrics; ``region_masks`` (name -> (N, T, H, W) bool,
    :func:`face_region_masks`) the colour difference of each region."""
    index = evaluation_pair_index(seqs)
    if max_pairs is not None:
        index = index[:max_pairs]
    if len(index) == 0:
        raise ValueError("no evaluation pairs")
    def heads(rows: np.ndarray) -> np.ndarray | None:
        return None if head_masks is None else head_masks[rows[:, 0], rows[:, 2]]

    def regions(rows: np.ndarray) -> dict[str, np.ndarray] | None:
        return None if region_masks is None else {k: m[rows[:, 0], rows[:, 2]] for k, m in region_masks.items()}

    parts = [evaluate_pairs(model, make_pairs(seqs, index[i:i + chunk]), domain=seqs.domain,
                            baseline_models=baseline_models, tgt_head_masks=heads(index[i:i + chunk]),
                            tgt_regions=regions(index[i:i + chunk]))
             for i in range(0, len(index), chunk)]
    preds = {k: np.concatenate([p.predictions[k] for p in parts]) for k in parts[0].predictions}
    results = {}
    for name in parts[0].results:
        psnr = np.concatenate([p.results[name].psnr_per_pair for p in parts])
        ssim = np.concatenate([p.results[name].ssim_per_pair for p in parts])
        per = {k: np.concatenate([p.results[name].person_per_pair[k] for p in parts])
               for k in parts[0].results[name].person_per_pair}
        results[name] = MethodScores.from_per_pair(psnr, ssim, per)
    return FrameEvaluation(results=results, num_pairs=len(index), domain=seqs.domain,
                           image_size=seqs.image_size, predictions=preds, pairs=pairs)


def json_payload(evaluation: FrameEvaluation, *, extra: dict | None = None) -> dict:
    """The JSON report: :meth:`FrameEvaluation.to_dict`, ``targets_met`` (empty without a generator) and
    ``extra``."""
    payload = evaluation.to_dict()
    payload["targets_met"] = evaluation.targets_met() if "generator" in evaluation.results else {}
    payload.update(extra or {})
    return payload


def write_json(evaluation: FrameEvaluation, path: str | Path, *, extra: dict | None = None) -> Path:
    """Write :func:`json_payload` to ``path`` atomically (tmp file + rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(json_payload(evaluation, extra=extra), indent=2, sort_keys=True) + "\n")
    tmp.replace(path)
    return path


def contact_sheet(columns: dict[str, np.ndarray], *, rows: int | None = None, label_height: int = 18,
                  gap: int = 2) -> np.ndarray:
    """A grid with one column per method and one row per pair, labelled at the top.

    Args:
        columns: title -> (N, H, W, 3) uint8 frames, in display order (e.g. reference | target | generated |
            copy-reference | limb-warp); every entry has the same shape.
        rows: show the first ``rows`` pairs (default all).
        label_height: pixels for the title band.
        gap: white pixels between cells.
    Returns:
        (label_height + rows * (H + gap), C * (W + gap), 3) uint8 image.
    """
    import cv2

    names = list(columns)
    if not names:
        raise ValueError("no columns")
    shape = columns[names[0]].shape
    for name in names:
        if columns[name].shape != shape or columns[name].dtype != np.uint8:
            raise ValueError(f"column {name!r} must be uint8 {shape}, got {columns[name].shape}")
    n, h, w = shape[0], shape[1], shape[2]
    rows = n if rows is None else min(rows, n)
    sheet = np.full((label_height + rows * (h + gap), len(names) * (w + gap), 3), 255, np.uint8)
    scale = 0.4 if w >= 100 else 0.3
    for c, name in enumerate(names):
        x0 = c * (w + gap)
        cv2.putText(sheet, name[: max(4, w // 7)], (x0 + 2, label_height - 5), cv2.FONT_HERSHEY_SIMPLEX, scale,
                    (0, 0, 0), 1, cv2.LINE_AA)
        for r in range(rows):
            y0 = label_height + r * (h + gap)
            sheet[y0:y0 + h, x0:x0 + w] = columns[name][r]
    return sheet


def evaluation_contact_sheet(evaluation: FrameEvaluation, *, rows: int = 6, stride: int | None = None) -> np.ndarray:
    """reference | target | generated (new) | baseline generators (old) | copy-reference | limb-warp for
    ``rows`` pairs spread over the set."""
    preds = evaluation.predictions
    n = preds["reference"].shape[0]
    stride = max(1, n // rows) if stride is None else stride
    pick = np.arange(0, n, stride)[:rows]
    extra = [k for k in preds if k not in ("reference", "target", "generator") + BASELINES]
    order = ["reference", "target", "generator", *extra, "copy-reference", "limb-warp"]
    titles = {"generator": "new", **{k: "old" if k.endswith("-v1") else k for k in extra}}
    return contact_sheet({titles.get(k, k): preds[k][pick] for k in order if k in preds})
