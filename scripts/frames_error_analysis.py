"""Where a warp body generator's error on the person comes from, on the held-out body pairs.

    python scripts/frames_error_analysis.py --model frames-body-128 --json out/frames_error_analysis.json

Measures, on the same 256 pairs that ``motion2video evaluate-frames`` scores:

1. person PSNR (inside the target's silhouette) by the time between reference and target (frames 1..8 of
   each 1.2 s sequence), for the generator, limb-warp and copy-reference;
2. how much a sub-pixel error of the flow costs: the reference sampled by the generator's own person flow,
   and by that flow shifted by half a pixel;
3. the whole frame's squared error split into the target's silhouette, the background the reference person
   uncovered (reference silhouette minus the target's) and the rest;
4. ceilings: the generator's person flow composited with the true target silhouette over the true
   background (no mask or background error left: what the flow alone allows), and with a per-pair residual
   flow fitted to the truth (an oracle: how far the flow is from one that matches).

The generator runs on the whole 128x128 frames (``forward_parts``), which for these frames is the crop that
``evaluate-frames`` uses; the paste back differs only outside the people.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from motion2video.frames.baselines import run_baseline  # noqa: E402
from motion2video.frames.checkpoint import load_frame_model  # noqa: E402
from motion2video.frames.data import (  # noqa: E402
    default_cache_dir, evaluation_pair_index, load_or_generate, make_pairs,
)
from motion2video.frames.specs import default_spec  # noqa: E402
from motion2video.core.atomic import write_json  # noqa: E402
from motion2video.frames.evaluate import frame_metrics, region_psnr, sharpness_ratio  # noqa: E402
from motion2video.frames.model import images_to_tensor, tensor_to_images  # noqa: E402
from motion2video.frames.warp import WarpGenerator, warp_image  # noqa: E402


def mean_person_psnr(pred: np.ndarray, truth: np.ndarray, masks: np.ndarray) -> float:
    return float(np.nanmean([region_psnr(p, t, m) for p, t, m in zip(pred, truth, masks)]))


def fitted_residual_psnr(ref: torch.Tensor, truth: torch.Tensor, flow: torch.Tensor, masks: np.ndarray, *,
                         grid: int, steps: int, mode: str) -> tuple[float, float]:
    """Person PSNR of the reference sampled by ``flow`` (B, H, W, 2) plus a smooth residual (a ``grid`` x
    ``grid`` field, bilinearly upsampled) fitted by Adam to the truth inside the silhouettes; and the fitted
    residual's mean length in pixels."""
    b, _, h, w = ref.shape
    weight = torch.from_numpy(masks)[:, None].float()
    delta = torch.zeros(b, 2, grid, grid, requires_grad=True)
    opt = torch.optim.Adam([delta], lr=0.5)
    for _ in range(steps):
        d = F.interpolate(delta, size=(h, w), mode="bilinear", align_corners=False).permute(0, 2, 3, 1)
        err = ((warp_image(ref, flow + d, mode) - truth).abs() * weight).sum() / weight.sum()
        smooth = (delta[:, :, 1:] - delta[:, :, :-1]).abs().mean() + (delta[..., 1:] - delta[..., :-1]).abs().mean()
        loss = err + 0.01 * smooth
        opt.zero_grad()
        loss.backward()
        opt.step()
    with torch.no_grad():
        d = F.interpolate(delta, size=(h, w), mode="bilinear", align_corners=False).permute(0, 2, 3, 1)
        pred = tensor_to_images(warp_image(ref, flow + d, mode))
        length = float(d.norm(dim=-1)[torch.from_numpy(masks)].mean())
    truth_u8 = tensor_to_images(truth)
    return mean_person_psnr(pred, truth_u8, masks), length


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--model", default="frames-body-128", help="a warp body generator (checkpoint or shipped name)")
    p.add_argument("--json", default="out/frames_error_analysis.json")
    p.add_argument("--cache", default=None, help="frame-data cache folder (default ~/.cache/motion2video/frames)")
    p.add_argument("--oracle-every", type=int, default=8, help="fit the oracle residual on every Nth pair")
    p.add_argument("--oracle-steps", type=int, default=300)
    args = p.parse_args(argv)
    torch.manual_seed(0)
    loaded = load_frame_model(args.model)
    model = loaded.model.eval()
    if not isinstance(model, WarpGenerator):
        p.error(f"{args.model}: not a warp generator (kind {loaded.kind})")
    mode = model.config.sample_mode
    seqs = load_or_generate(default_spec("body", "test"), cache_dir=args.cache or default_cache_dir(),
                            progress=False)
    index = evaluation_pair_index(seqs)
    pairs = make_pairs(seqs, index)
    truth, ref_u8, tgt_masks, ref_masks = pairs.tgt_images, pairs.ref_images, pairs.tgt_masks, pairs.ref_masks
    ref = images_to_tensor(ref_u8)
    images, flows, person = [], [], []
    with torch.no_grad():
        for s in range(0, len(pairs), 32):
            out = model.forward_parts(ref[s:s + 32], torch.from_numpy(pairs.ref_points[s:s + 32]),
                                      torch.from_numpy(pairs.tgt_points[s:s + 32]),
                                      torch.from_numpy(pairs.tgt_structures[s:s + 32]))
            images.append(tensor_to_images(out.image))
            flows.append(out.flow)
            person.append(1.0 - out.masks[:, -1])
    gen, flow = np.concatenate(images), torch.cat(flows)
    limb = run_baseline("limb-warp", ref_u8, pairs.ref_points, pairs.tgt_points)
    rows = tgt_masks.any(axis=2)  # (N, H): image rows the target person covers
    height = float(np.mean([np.ptp(np.nonzero(r)[0]) + 1 for r in rows if r.any()]))
    report: dict = {"model": args.model, "sample_mode": mode, "num_pairs": len(pairs),
                    "person_height_px": round(height, 1), "person_pixels": round(float(tgt_masks.sum((1, 2)).mean()))}

    gaps = {}
    for gap in sorted(set(index[:, 2].tolist())):
        sel = index[:, 2] == gap
        moved = np.linalg.norm(pairs.ref_points[sel] - pairs.tgt_points[sel], axis=-1).mean()
        gaps[int(gap)] = {"pairs": int(sel.sum()), "mean_joint_motion_px": round(float(moved), 1),
                          **{name: round(mean_person_psnr(x[sel], truth[sel], tgt_masks[sel]), 2)
                             for name, x in (("generator", gen), ("limb-warp", limb), ("copy-reference", ref_u8))}}
    report["person_psnr_by_gap"] = gaps

    shifts = {}
    with torch.no_grad():
        for name, offset in (("none", (0.0, 0.0)), ("x+0.5", (0.5, 0.0)), ("x-0.5", (-0.5, 0.0)),
                             ("y+0.5", (0.0, 0.5)), ("y-0.5", (0.0, -0.5))):
            sampled = tensor_to_images(warp_image(ref, flow + torch.tensor(offset), mode))
            shifts[name] = round(mean_person_psnr(sampled, truth, tgt_masks), 2)
    report["person_psnr_of_the_flow_shifted"] = shifts

    err = ((gen.astype(np.float64) - truth.astype(np.float64)) ** 2).mean(-1)  # (N, H, W)
    uncovered = ref_masks & ~tgt_masks
    rest = ~ref_masks & ~tgt_masks
    total = err.sum()
    report["whole_frame_error_share"] = {name: round(float(err[m].sum() / total), 3) for name, m in
                                         (("target_person", tgt_masks), ("uncovered_background", uncovered),
                                          ("rest", rest))}
    with torch.no_grad():
        sampled = tensor_to_images(warp_image(ref, flow, mode))
    alpha = tgt_masks[..., None].astype(np.float64)
    ceiling = np.rint(alpha * sampled + (1 - alpha) * truth).astype(np.uint8)
    report["whole_psnr"] = {"generator": round(float(frame_metrics(gen, truth)[0].mean()), 2),
                            "its_flow_true_silhouette_true_background": round(float(frame_metrics(ceiling, truth)[0].mean()), 2)}
    report["person"] = {"generator_psnr": round(mean_person_psnr(gen, truth, tgt_masks), 2),
                        "generator_sharpness": round(float(np.nanmean([sharpness_ratio(a, b, m) for a, b, m in
                                                                       zip(gen, truth, tgt_masks)])), 3),
                        "limb_warp_psnr": round(mean_person_psnr(limb, truth, tgt_masks), 2)}

    pick = np.arange(0, len(pairs), args.oracle_every)
    tgt = images_to_tensor(truth[pick])
    with torch.no_grad():
        base = mean_person_psnr(tensor_to_images(warp_image(ref[pick], flow[pick], mode)), truth[pick], tgt_masks[pick])
    oracle = {"pairs": len(pick), "its_flow": round(base, 2)}
    for grid in (16, 32):
        value, length = fitted_residual_psnr(ref[pick], tgt, flow[pick], tgt_masks[pick], grid=grid,
                                             steps=args.oracle_steps, mode=mode)
        oracle[f"fitted_residual_{grid}x{grid}"] = {"person_psnr": round(value, 2),
                                                    "mean_residual_px": round(length, 2)}
    report["oracle_residual_flow"] = oracle

    print(write_json(args.json, report).read_text(), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
