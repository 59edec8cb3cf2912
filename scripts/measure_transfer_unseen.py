"""Behaviour transfer on clips the shipped ``behavior`` model never saw: CMU jumps and leg lifts of the corpus's
test subjects and Bandai-Namco waves, a bow and a punch (a source no shipped model trained on), each re-enacted
from walking postures of OTHER test subjects, scored by the root-relative signatures
(``motion2video.evaluation.signatures``) as ratios of the source's.

Two ways, the same source window, target posture, z and step count (300, ``--adapt-steps``' default):

- ``before``: the decoder fitted to the source from the source's OWN start posture, then run from the target's
  (what ``transfer`` did before), the root path shifted by the difference of the start heights;
- ``after``: ``motion2video transfer`` now (``stages.latents.reenact_source``): the decoder fitted to the source
  retargeted onto the target's posture and bones, run from the target's posture along the goal's root path.

Writes a markdown table (per clip: the median over its targets), the macro over clips, the raw numbers as JSON,
and a contact sheet PNG (source | before | after, every 8th frame) of chosen pairs drawn with the project's mesh
renderer.

    python scripts/measure_transfer_unseen.py --json out/transfer_unseen.json --sheet out/transfer_unseen.png

About 25 minutes on a loaded 2-core machine (two fits per pair). ``--held-out-benchmark`` prints the known-answer
transfer benchmark's held-out rows instead (``evaluation.transfer_benchmark``, one fit per case and target).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from motion2video.apps.transfer import TransferResult, render_transfer
from motion2video.evaluation import signatures as S
from motion2video.evaluation.transfer_benchmark import MIN_RELATIVE_AMPLITUDE
from motion2video.formats.video import write_image
from motion2video.models.checkpoint import load_model
from motion2video.stages.clips import load_clip
from motion2video.stages.latents import (ADAPT_STEPS, adapt_to_source, behavior_latents, behavior_model,
                                         behavior_root, decode_sequences, encode_sequences, reenact, reenact_source,
                                         rigid_bones)

ROOT = Path(__file__).resolve().parents[1]
MOCAP = ROOT / ".." / "shared" / "data" / "mocap"
BANDAI = ROOT / ".." / "shared" / "data" / "bandai" / "bvh"
HORIZON = 48
FPS = 25.0
RELATIVE = ("leg_extension", "arm_swing", "knee_bend", "ankle_lift")

# (label, file, subject, start at 25 fps or None: the window with the largest summed root-relative signatures of
# the SOURCE, stride 4). CMU: the corpus's test subjects (docs/data.md); Bandai: no shipped model trained on it.
SOURCES = (
    ("jump", MOCAP / "cmu/02_04.bvh", "cmu-02", 0),
    ("hop", MOCAP / "cmu/131_03.bvh", "cmu-131", 124),
    ("leg lift (dance)", MOCAP / "cmu/05_14.bvh", "cmu-05", 64),
    ("leg lift (dance)", MOCAP / "cmu/05_15.bvh", "cmu-05", None),
    ("wave (Bandai 2C)", BANDAI / "dataset-2_wave-both-hands_feminine_001.bvh.xz", "bandai-2C", None),
    ("bow (Bandai 1B)", BANDAI / "dataset-1_bow_active_001.bvh.xz", "bandai-1B", None),
    ("punch (Bandai 1A)", BANDAI / "dataset-1_punch_normal_001.bvh.xz", "bandai-1A", None),
)
# Walking postures (file, frame at 25 fps, subject); every source uses the first two of other subjects.
TARGETS = (
    (MOCAP / "cmu/07_03.bvh", 30, "cmu-07"),
    (MOCAP / "cmu/05_01.bvh", 42, "cmu-05"),
    (MOCAP / "cmu/02_02.bvh", 42, "cmu-02"),
)
SHEET = (("jump", "cmu/07_03.bvh"), ("wave (Bandai 2C)", "cmu/07_03.bvh"), ("punch (Bandai 1A)", "cmu/05_01.bvh"))


def best_window(clip: np.ndarray) -> int:
    """Start (25 fps) of the 1 + HORIZON window with the largest summed root-relative signatures."""
    starts = range(0, clip.shape[0] - HORIZON - 1, 4)
    return max(starts, key=lambda s: sum(S.signature(n, clip[s:s + 1 + HORIZON], FPS) for n in RELATIVE))


def fitted_to_own_start(bundle, source: np.ndarray, start: np.ndarray) -> np.ndarray:
    """The previous re-enactment: the decoder fitted to the source from its own start, run from ``start``."""
    model = behavior_model(bundle)
    src, _ = encode_sequences(bundle, source[None])
    tgt, frame = encode_sequences(bundle, start[None, None])
    z = behavior_latents(model, src)
    fitted = adapt_to_source(model, src, z, steps=ADAPT_STEPS)
    gen = reenact(fitted, z, tgt[:, 0], horizon=HORIZON, root=behavior_root(fitted, src, tgt[:, 0]))
    seq = np.concatenate([tgt, gen], axis=1)
    return rigid_bones("body3d", decode_sequences(bundle, seq[:, None], frame)[0])[0]


def ratios(source: np.ndarray, made: np.ndarray) -> dict[str, float]:
    out = {}
    for name in RELATIVE:
        src = S.signature(name, source, FPS)
        out[name] = S.signature(name, made, FPS) / src if src >= MIN_RELATIVE_AMPLITUDE else float("nan")
    return out


def fmt(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{x:.2f}"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--json", type=Path, default=None)
    p.add_argument("--sheet", type=Path, default=None, help="contact sheet PNG of the pairs in SHEET")
    p.add_argument("--held-out-benchmark", action="store_true",
                   help="instead: the known-answer transfer benchmark's held-out cases (transfer rows, medians)")
    args = p.parse_args()
    torch.set_num_threads(1)
    bundle = load_model("behavior")
    if args.held_out_benchmark:
        held_out_benchmark(bundle)
        return
    rows, pairs, sheet = [], [], []
    for label, path, subject, start in SOURCES:
        clip = load_clip(bundle, path).data
        start = best_window(clip) if start is None else start
        source = clip[start:start + 1 + HORIZON]
        targets = [t for t in TARGETS if t[2] != subject][:2]
        per = {"before": [], "after": []}
        for tpath, tframe, _ in targets:
            posture = load_clip(bundle, tpath).data[tframe]
            t0 = time.time()
            before = fitted_to_own_start(bundle, source, posture)
            _, after, shown = reenact_source(bundle, source, posture, adapt_steps=ADAPT_STEPS)
            after = after[0]
            r = {"before": ratios(shown, before), "after": ratios(shown, after)}
            for k in per:
                per[k].append(r[k])
            pair = {"clip": path.name, "label": label, "start_25fps": int(start), "target": tpath.name,
                    "target_frame_25fps": int(tframe), **r,
                    "source_amplitude_m": {n: S.signature(n, shown, FPS) for n in RELATIVE},
                    "start_error_m": S.posture_error(after[1:2], posture),
                    "bone_spread": S.bone_length_spread(after[1:]), "seconds": time.time() - t0}
            pairs.append(pair)
            print(json.dumps(pair), flush=True)
            if (label, f"cmu/{tpath.name}") in SHEET:
                sheet.append((label, path, tpath, shown, before, after))
        row = {"clip": path.name, "label": label, "start_25fps": int(start),
               "targets": [t[0].name for t in targets]}
        for k in per:
            row[k] = {n: float(np.nanmedian([d[n] for d in per[k]])) if any(np.isfinite(d[n]) for d in per[k])
                      else float("nan") for n in RELATIVE}
        rows.append(row)
    macro = {k: {n: float(np.nanmean([r[k][n] for r in rows])) for n in RELATIVE} for k in ("before", "after")}
    head = "| clip | " + " | ".join(f"{n.replace('_', ' ')} before / after" for n in RELATIVE) + " |"
    lines = [head, "| --- |" + " ---: |" * len(RELATIVE)]
    for r in rows:
        lines.append(f"| {r['label']}: `{r['clip']}` from {r['start_25fps']} | "
                     + " | ".join(f"{fmt(r['before'][n])} / **{fmt(r['after'][n])}**" for n in RELATIVE) + " |")
    lines.append("| macro (mean over clips) | " + " | ".join(f"{fmt(macro['before'][n])} / **{fmt(macro['after'][n])}**"
                                                      for n in RELATIVE) + " |")
    print("\n".join(lines))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"rows": rows, "macro": macro, "pairs": pairs}, indent=1, default=float))
    if args.sheet and sheet:
        write_image(args.sheet, contact_sheet(sheet))
        print(f"wrote {args.sheet}")


def held_out_benchmark(bundle) -> None:
    """Print the held-out rows of :mod:`motion2video.evaluation.transfer_benchmark` for ``transfer`` as it is."""
    from motion2video.evaluation import transfer_benchmark as B

    cases = tuple(c for c in B.CASES if c.split == "held-out")
    for row in B.summarise(B.run_benchmark(str(MOCAP), transfer=bundle, cases=cases)):
        if row["method"] == "transfer":
            print(f"| {row['behaviour']} | {row['median_ratio']:.2f} | "
                  + " | ".join(fmt(row["relative"][n]) for n in RELATIVE)
                  + f" | {row['start_error']:.3f} | {fmt(row['posture_kept'])} |", flush=True)


def contact_sheet(items) -> np.ndarray:
    """One row per pair: the source, then the re-enactment before and after, every 8th frame (mesh style)."""
    from motion2video.formats.video import label as put_label

    picks = np.arange(0, HORIZON + 1, 8)
    rows = []
    for label, path, tpath, shown, before, after in items:
        cells = []
        for name, made in (("before", before), ("after", after)):
            result = TransferResult(source=shown[picks].astype(np.float32),
                                    reenacted=made[None, picks].astype(np.float32), z=np.zeros((1, 1)), fps=FPS / 8, layout="body3d", source_name=str(path),
                                    target_name=str(tpath), target_frame=0)
            frames = render_transfer(result, style="mesh", size=160)  # (7, 160, 322, 3): source | re-enactment
            if not cells:
                cells.append(np.concatenate(list(frames[:, :, :160]), axis=1))
            right = np.concatenate(list(frames[:, :, 162:]), axis=1)
            cells.append(put_label(right[None], f"{name}: {label} from {tpath.stem}")[0])
        cells[0] = put_label(cells[0][None], f"source: {path.name.split('.')[0]}")[0]
        rows.append(np.concatenate(cells, axis=0))
    gap = np.full((6, rows[0].shape[1], 3), 255, np.uint8)
    return np.concatenate([x for r in rows for x in (r, gap)][:-1], axis=0)


if __name__ == "__main__":
    main()
