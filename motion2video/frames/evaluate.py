"""Evaluation of a frame generator against the baselines on the same held-out pairs, and contact sheets.

Metrics are scikit-image's PSNR and SSIM on uint8 RGB frames (data range 255), computed per pair and
averaged over pairs.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

from motion2video.frames.baselines import BASELINES, run_baseline
from motion2video.frames.data import FramePairs, FrameSequences, evaluation_pair_index, make_pairs
from motion2video.frames.model import FrameGenerator, generate

METHODS = ("generator",) + BASELINES


def frame_metrics(pred: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame PSNR (dB) and SSIM.

    Args:
        pred, target: (N, H, W, 3) uint8.
    Returns:
        psnr (N,) float64, ssim (N,) float64.
    """
    if pred.shape != target.shape or pred.dtype != np.uint8 or target.dtype != np.uint8:
        raise ValueError(f"pred and target must be uint8 of one shape, got {pred.shape} {pred.dtype} and "
                         f"{target.shape} {target.dtype}")
    psnr = np.array([peak_signal_noise_ratio(t, p, data_range=255) for p, t in zip(pred, target)], np.float64)
    ssim = np.array([structural_similarity(t, p, channel_axis=-1, data_range=255) for p, t in zip(pred, target)],
                    np.float64)
    return psnr, ssim


@dataclass
class MethodScores:
    """Mean PSNR / SSIM of one method over the pairs, with the per-pair values."""

    psnr: float
    ssim: float
    psnr_per_pair: np.ndarray = field(repr=False)
    ssim_per_pair: np.ndarray = field(repr=False)

    @staticmethod
    def from_frames(pred: np.ndarray, target: np.ndarray) -> "MethodScores":
        psnr, ssim = frame_metrics(pred, target)
        return MethodScores(float(psnr.mean()), float(ssim.mean()), psnr, ssim)


@dataclass
class FrameEvaluation:
    """Scores of the generator and the baselines on one set of pairs.

    Attributes:
        results: method name -> scores (``generator``, ``copy-reference``, ``limb-warp``).
        num_pairs: number of evaluated pairs.
        domain, image_size: what was evaluated.
        predictions: method name -> (N, H, W, 3) uint8 frames (for contact sheets), plus ``reference`` and
            ``target``.
    """

    results: dict[str, MethodScores]
    num_pairs: int
    domain: str
    image_size: int
    predictions: dict[str, np.ndarray] = field(repr=False, default_factory=dict)

    def to_dict(self) -> dict:
        """The JSON shape: ``{"results": {method: {"psnr", "ssim"}}, "num_pairs", "domain", "image_size"}``."""
        return {
            "results": {k: {"psnr": round(v.psnr, 4), "ssim": round(v.ssim, 5)} for k, v in self.results.items()},
            "num_pairs": self.num_pairs,
            "domain": self.domain,
            "image_size": self.image_size,
        }

    def targets_met(self) -> dict[str, bool]:
        """The issue's targets: PSNR >= copy-reference + 3 dB and >= limb-warp + 1 dB; SSIM above both."""
        g, c, w = (self.results[k] for k in METHODS)
        return {
            "psnr_vs_copy_reference_3db": g.psnr >= c.psnr + 3.0,
            "psnr_vs_limb_warp_1db": g.psnr >= w.psnr + 1.0,
            "ssim_above_both": g.ssim > c.ssim and g.ssim > w.ssim,
        }


def evaluate_pairs(model: FrameGenerator | None, pairs: FramePairs, *, domain: str,
                   batch_size: int = 16) -> FrameEvaluation:
    """Score the generator (when given) and every baseline on ``pairs``."""
    preds: dict[str, np.ndarray] = {}
    if model is not None:
        preds["generator"] = generate(model, pairs.ref_images, pairs.ref_structures, pairs.tgt_structures,
                                      batch_size=batch_size)
    for name in BASELINES:
        preds[name] = run_baseline(name, pairs.ref_images, pairs.ref_points, pairs.tgt_points)
    results = {name: MethodScores.from_frames(p, pairs.tgt_images) for name, p in preds.items()}
    preds["reference"] = pairs.ref_images
    preds["target"] = pairs.tgt_images
    return FrameEvaluation(results=results, num_pairs=len(pairs), domain=domain,
                           image_size=int(pairs.ref_images.shape[1]), predictions=preds)


def evaluate_sequences(model: FrameGenerator | None, seqs: FrameSequences, *, max_pairs: int | None = None,
                       chunk: int = 64) -> FrameEvaluation:
    """Score on the fixed evaluation pairs of ``seqs`` (:func:`evaluation_pair_index`), in chunks so the
    structure maps of every pair are never all in memory at once."""
    index = evaluation_pair_index(seqs)
    if max_pairs is not None:
        index = index[:max_pairs]
    if len(index) == 0:
        raise ValueError("no evaluation pairs")
    parts = [evaluate_pairs(model, make_pairs(seqs, index[i:i + chunk]), domain=seqs.domain)
             for i in range(0, len(index), chunk)]
    preds = {k: np.concatenate([p.predictions[k] for p in parts]) for k in parts[0].predictions}
    results = {}
    for name in parts[0].results:
        psnr = np.concatenate([p.results[name].psnr_per_pair for p in parts])
        ssim = np.concatenate([p.results[name].ssim_per_pair for p in parts])
        results[name] = MethodScores(float(psnr.mean()), float(ssim.mean()), psnr, ssim)
    return FrameEvaluation(results=results, num_pairs=len(index), domain=seqs.domain,
                           image_size=seqs.image_size, predictions=preds)


def write_json(evaluation: FrameEvaluation, path: str | Path, *, extra: dict | None = None) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = evaluation.to_dict()
    payload["targets_met"] = evaluation.targets_met() if "generator" in evaluation.results else {}
    payload.update(extra or {})
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(payload, indent=2, sort_keys=True) + "\n")
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
    """reference | target | generated | copy-reference | limb-warp for ``rows`` pairs spread over the set."""
    preds = evaluation.predictions
    n = preds["reference"].shape[0]
    stride = max(1, n // rows) if stride is None else stride
    pick = np.arange(0, n, stride)[:rows]
    order = ["reference", "target", "generator", "copy-reference", "limb-warp"]
    titles = {"generator": "generated"}
    return contact_sheet({titles.get(k, k): preds[k][pick] for k in order if k in preds})
