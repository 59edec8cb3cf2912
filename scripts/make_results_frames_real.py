"""The body frame generator driven by real mocap it never trained on, with the head measured.

    python scripts/make_results_frames_real.py [--model frames-body-mesh-256] [--mocap ../shared/data/mocap]

For each clip of :data:`CLIPS` (real CMU captures held out of the frame training data:
``motion2video.frames.specs.is_test_clip``), runs what ``motion2video evaluate-frames --model MODEL --poses
CLIP`` runs (the same functions, once per clip: the held-out identities posed by 4 windows of the clip, the truth
the Anny render of each pose) and writes:

- the section between ``<!-- frames-real-motion:begin -->`` and ``<!-- frames-real-motion:end -->`` of
  docs/results.md: whole-frame, person and head PSNR / SSIM and the person sharpness ratio per clip and method,
  and the targets per clip;
- docs/images/frames_real_motion.png: reference | truth | generator | (previous generator, when it loads) |
  limb-warp, two pairs per clip, each frame at twice its size with the head region enlarged beside it;
- out/results_frames_real.json: the evaluate-frames JSON of each clip.

With ``--held-out``, also runs ``motion2video evaluate-frames --model MODEL --head`` (the project's held-out pairs,
rendered again with head masks) and adds its person and head metrics to the section, for comparison.

About 2 minutes on 2 cores, plus about 3 with ``--held-out``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2video.core.atomic import write_json, write_section  # noqa: E402

BEGIN, END = "<!-- frames-real-motion:begin -->", "<!-- frames-real-motion:end -->"
# Held-out real captures (none is in the frame generator's training clips), one walk, one jump, one dance.
CLIPS = ("cmu/08_01.bvh", "cmu/13_42.bvh", "cmu/05_14.bvh")
WINDOWS = 4
BASELINES = ("copy-reference", "limb-warp")


def order(results: dict) -> list[str]:
    """The methods of a payload in table order: the generator, the previous generator(s), the baselines."""
    old = [k for k in results if k != "generator" and k not in BASELINES]
    return ["generator", *old, *BASELINES]


def method_name(key: str, model: str) -> str:
    if key == "generator":
        return f"**new** (`{model}`)"
    return key if key in BASELINES else f"old (`{key}`)"
TARGETS = {"person_psnr_vs_limb_warp_3db": "person PSNR >= limb-warp + 3 dB",
           "head_psnr_vs_limb_warp_3db": "head PSNR >= limb-warp + 3 dB",
           "person_sharpness_0.9": "person sharpness ratio >= 0.9"}
SHEET_ROWS = (7, 23)  # pairs per clip shown: the last target (1.2 s on) of the first and of the third window
SCALE = 2  # sheet cells at twice the frame size
HEAD_BOX = 24  # pixels (frame scale) of the enlarged head crop beside each cell


def evaluate_clip(model_name: str, clip: Path):
    """The evaluation of ``evaluate-frames --model model_name --poses clip --windows WINDOWS``, its JSON payload
    (the same functions the command runs) and (N, 2, H, W) bool head masks of each pair's target and reference."""
    from motion2video.frames.data import evaluation_pair_index
    from motion2video.evaluation.frame_generators import evaluate_posed, load_baselines
    from motion2video.frames.checkpoint import load_frame_model
    from motion2video.frames.evaluate import json_payload
    from motion2video.frames.poses import load_body_clips

    loaded = load_frame_model(model_name)
    baselines, left_out = load_baselines(None, loaded)
    posed = evaluate_posed(loaded.model, load_body_clips(clip), poses_path=clip, windows=WINDOWS, baselines=baselines,
                           progress=False)
    evaluation, rendered = posed.evaluation, posed.rendered
    index = evaluation_pair_index(rendered.sequences)  # (N, 3) sequence, reference, target: the evaluated pairs
    heads = np.stack([rendered.head_masks[index[:, 0], index[:, 2]], rendered.head_masks[index[:, 0], index[:, 1]]],
                     axis=1)  # (N, 2, H, W)
    extra = {"model": str(loaded.path.relative_to(ROOT)) if loaded.path.is_relative_to(ROOT) else str(loaded.path),
             "model_kind": loaded.kind, "model_step": loaded.step, "poses": posed.poses}
    if left_out:
        extra["baselines_left_out"] = left_out
    return evaluation, json_payload(evaluation, extra=extra), heads


def head_crop(image: np.ndarray, head: np.ndarray, size: int) -> np.ndarray:
    """A ``HEAD_BOX``-pixel square of ``image`` (H, W, 3) centred on the head mask ``head`` (H, W), enlarged to
    ``size`` x ``size`` (nearest neighbour)."""
    import cv2

    h, w = head.shape
    ys, xs = np.nonzero(head)
    cy, cx = (int(round(ys.mean())), int(round(xs.mean()))) if len(ys) else (h // 4, w // 2)
    y0 = int(np.clip(cy - HEAD_BOX // 2, 0, h - HEAD_BOX))
    x0 = int(np.clip(cx - HEAD_BOX // 2, 0, w - HEAD_BOX))
    return cv2.resize(image[y0:y0 + HEAD_BOX, x0:x0 + HEAD_BOX], (size, size), interpolation=cv2.INTER_NEAREST)


def sheet_columns(evaluation, head_masks: np.ndarray, rows: list[int]) -> dict[str, np.ndarray]:
    """Columns of the sheet for pairs ``rows``: each method's frame at SCALE with its head crop beside it."""
    import cv2

    preds = evaluation.predictions
    names = [("reference", "reference"), ("target", "truth"), ("generator", "new")]
    names += [(k, "old") for k in preds if k not in ("generator", "reference", "target", *BASELINES)][:1]
    names += [("limb-warp", "limb-warp")]
    out = {}
    for key, title in names:
        cells = []
        for r in rows:
            frame = preds[key][r]
            big = cv2.resize(frame, None, fx=SCALE, fy=SCALE, interpolation=cv2.INTER_NEAREST)
            # The head crop is taken where the target's head is (the reference's own head for the reference).
            mask = head_masks[r, 1] if key == "reference" else head_masks[r, 0]
            side = np.full((big.shape[0], big.shape[1] // 2, 3), 255, np.uint8)  # the head crop, top right
            side[: big.shape[1] // 2] = head_crop(frame, mask, big.shape[1] // 2)
            cells.append(np.concatenate([big, side], axis=1))
        out[title] = np.stack(cells)
    return out


def table(payloads: dict[str, dict], model: str) -> str:
    head = ("| clip | method | person PSNR | person SSIM | person sharpness | head PSNR | head SSIM | whole PSNR |\n"
            "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows = []
    for clip, payload in payloads.items():
        for key in order(payload["results"]):
            r = payload["results"].get(key)
            if r is not None:
                rows.append(f"| `{clip}` | {method_name(key, model)} | {r['person_psnr']:.2f} "
                            f"| {r['person_ssim']:.3f} | {r['person_sharpness']:.2f} | {r['head_psnr']:.2f} "
                            f"| {r['head_ssim']:.3f} | {r['psnr']:.2f} |")
    return head + "\n" + "\n".join(rows)


def margins(payloads: dict[str, dict]) -> str:
    lines = []
    for clip, payload in payloads.items():
        res = payload["results"]
        g, w, c = res["generator"], res["limb-warp"], res["copy-reference"]
        lines.append(f"- `{clip}` ({payload['num_pairs']} pairs): person PSNR {g['person_psnr'] - w['person_psnr']:+.2f} dB "
                     f"over limb-warp, {g['person_psnr'] - c['person_psnr']:+.2f} dB over copy-reference; head PSNR "
                     f"{g['head_psnr'] - w['head_psnr']:+.2f} dB over limb-warp, "
                     f"{g['head_psnr'] - c['head_psnr']:+.2f} dB over copy-reference.")
    return "\n".join(lines)


def targets(payloads: dict[str, dict]) -> str:
    head = "| target | " + " | ".join(f"`{c}`" for c in payloads) + " |\n| --- |" + " --- |" * len(payloads)
    rows = [f"| {text} | " + " | ".join("met" if p["targets_met"].get(key) else "**missed**"
                                         for p in payloads.values()) + " |" for key, text in TARGETS.items()]
    return head + "\n" + "\n".join(rows)


def held_out_text(payload: dict | None, model: str) -> str:
    """The held-out pairs' person and head metrics (``evaluate-frames --head``), or nothing."""
    if payload is None:
        return ""
    return f"""For comparison, the project's held-out pairs (poses of held-out clips drawn like the training data's, the same
identities), `motion2video evaluate-frames --model {model} --head` ({payload['num_pairs']} pairs):

{table({'held-out pairs': payload}, model)}
"""


def section(payloads: dict[str, dict], model: str, minutes: float, note: str = "",
            held_out: dict | None = None) -> str:
    left_out = {k: v for p in payloads.values() for k, v in p.get("baselines_left_out", {}).items()}
    old = ("" if not left_out else
           f" The previous generator (`{', '.join(left_out)}`) is left out: it was trained on the previous canonical "
           "skeleton (version 1), and the loader refuses it on the new joints until it is fine-tuned on them.")
    clips = "\n".join(f"motion2video evaluate-frames --model {model} --poses ../shared/data/mocap/{c}" for c in payloads)
    return f"""### Body frames driven by real motion

One run per clip (`python scripts/make_results_frames_real.py` runs the same functions and writes this section):

```
{clips}
```

The frame test split's 8 held-out identities, posed by {WINDOWS} windows spread evenly
over each real CMU capture (9 frames over 1.2 s each; frame 0 of a window is the reference, the 8 later frames
the targets), rendered by the Anny body renderer exactly as the training data is (background, camera yaw and
elevation, light); the truth is the render of each pose. None of these clips is in the frame training data
(`motion2video.frames.specs.is_test_clip`; `cmu/02_01.bvh` is a training clip, so a held-out
walk is used instead). The head is the target's visible head: the pixels where Anny's head vertices (dominant
bone `head` or below it) are the front surface, by a depth test, so a hand in front of the face is not head.{old}

{note}

{table(payloads, model)}

{margins(payloads)}

{held_out_text(held_out, model)}
The targets driven by real motion:

{targets(payloads)}

Reference | truth | new | old | limb-warp (old: the previous generator, when it loads), two pairs per clip ({', '.join(f'`{c}`' for c in payloads)}, top to
bottom), at twice the frame size, each with the head region enlarged beside it (top right):

![real motion sheet](images/frames_real_motion.png)

_Generated {time.strftime('%Y-%m-%d %H:%M:%S')} in {minutes:.1f} min by `python scripts/make_results_frames_real.py`._
"""


def main(argv: list[str] | None = None) -> int:
    import imageio.v3 as iio

    from motion2video.frames.evaluate import contact_sheet

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="frames-body-mesh-256",
                        help="the body generator (default frames-body-mesh-256, make demo's)")
    parser.add_argument("--mocap", default=str(ROOT.parent / "shared" / "data" / "mocap"),
                        help="the mocap folder holding cmu/ (default ../shared/data/mocap)")
    parser.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    parser.add_argument("--sheet", default=str(ROOT / "docs" / "images" / "frames_real_motion.png"))
    parser.add_argument("--json", default=str(ROOT / "out" / "results_frames_real.json"))
    parser.add_argument("--held-out", action="store_true",
                        help="also run evaluate-frames --head on the held-out pairs and add it to the section")
    parser.add_argument("--note", default="", help="a paragraph added to the section (e.g. which checkpoint --model is)")
    args = parser.parse_args(argv)

    from motion2video.frames.specs import is_test_clip

    start = time.perf_counter()
    payloads, columns = {}, []
    for clip in CLIPS:
        assert is_test_clip(clip), f"{clip} is a frame training clip"
        evaluation, payload, heads = evaluate_clip(args.model, Path(args.mocap) / clip)
        payloads[clip] = payload
        columns.append(sheet_columns(evaluation, heads, list(SHEET_ROWS)))
        print(f"{clip}: {json.dumps({k: v['person_psnr'] for k, v in payload['results'].items()})}", flush=True)
    held_out = None
    if args.held_out:
        held_json = Path(args.json).with_name("results_frames_head.json")
        subprocess.run([sys.executable, "-m", "motion2video.cli", "evaluate-frames", "--model", args.model, "--head",
                        "--json", str(held_json), "--no-progress"], check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
        held_out = json.loads(held_json.read_text())
    merged = {k: np.concatenate([c[k] for c in columns]) for k in columns[0]}
    sheet = Path(args.sheet)
    sheet.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(sheet, contact_sheet(merged, label_height=22))
    write_json(args.json, payloads)
    write_section(args.doc, BEGIN, END, section(payloads, args.model, (time.perf_counter() - start) / 60,
                                                args.note, held_out))
    print(f"wrote {args.doc}, {sheet} and {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
