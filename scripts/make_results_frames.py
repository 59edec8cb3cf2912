"""The body frame generator measured on the person, next to its baselines, in one run.

    python scripts/make_results_frames.py [--model frames-body-128] [--cache DIR] [--bench out/bench_pipeline.json]

Runs ``motion2video evaluate-frames --model MODEL`` once on the held-out body pairs (held-out identities and
clips; the previous generator ``frames-body-128-v1``, copy-reference and limb-warp scored on the same pairs),
and writes:

- the section between ``<!-- body-frames:begin -->`` and ``<!-- body-frames:end -->`` of
  docs/results.md: whole-frame PSNR / SSIM, person PSNR / SSIM / sharpness inside the target's silhouette,
  PSNR / sharpness where the person moved, and the targets met or missed;
- docs/images/frames_body_person_sheet.png: reference | target | new | old | copy-reference | limb-warp;
- out/results_frames.json: the evaluation as evaluate-frames writes it.

With ``--bench``, the speed of the new and the previous body generator side by side, from a JSON written by
``scripts/bench_pipeline.py`` (``generators_side_by_side``), is added to the section.

About a minute on 2 cores when the held-out shards are cached (``--cache``), plus a few minutes to render
them the first time.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2video.core.atomic import write_section  # noqa: E402

BEGIN, END = "<!-- body-frames:begin -->", "<!-- body-frames:end -->"
ORDER = ("generator", "frames-body-128-v1", "copy-reference", "limb-warp")
NAMES = {"generator": "**new** (`{model}`)", "frames-body-128-v1": "old (`frames-body-128-v1`)",
         "copy-reference": "copy-reference", "limb-warp": "limb-warp"}
TARGETS = {
    "person_psnr_vs_limb_warp_3db": "person PSNR >= limb-warp + 3 dB",
    "person_psnr_vs_copy_reference_5db": "person PSNR >= copy-reference + 5 dB",
    "person_psnr_vs_frames-body-128-v1_2db": "person PSNR >= old generator + 2 dB",
    "person_sharpness_0.9": "person sharpness ratio >= 0.9",
    "psnr_29db": "whole-frame PSNR >= 29 dB",
    "ssim_above_every_baseline": "SSIM above every baseline",
}


def table(results: dict, model: str) -> str:
    head = ("| method | whole PSNR | whole SSIM | person PSNR | person SSIM | person sharpness | moving PSNR "
            "| moving sharpness |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows = []
    for key in ORDER:
        r = results.get(key)
        if r is None:
            continue
        rows.append(f"| {NAMES[key].format(model=model)} | {r['psnr']:.2f} | {r['ssim']:.3f} | {r['person_psnr']:.2f} "
                     f"| {r['person_ssim']:.3f} | {r['person_sharpness']:.2f} | {r['moving_psnr']:.2f} "
                     f"| {r['moving_sharpness']:.2f} |")
    return head + "\n" + "\n".join(rows)


# The bench's third generator, when measured: the shipped model before its bicubic stage (--compare-frame-model FILE).
STAGE3_NOTE = (" `frames-body-128-stage3` is the third-stage (bilinear) checkpoint, measured with "
               "`--compare-frame-model` on `git show 7587fa5:motion2video/weights/frames-body-128.safetensors`.")


def stage3_note(side: dict) -> str:
    """:data:`STAGE3_NOTE` and the speed bicubic sampling costs, when the bench measured the third stage."""
    stage3 = [fps for name, fps in side.items() if name.endswith("stage3")]
    if not stage3 or "frames-body-128" not in side:
        return ""
    return f"{STAGE3_NOTE} Bicubic sampling costs {100 * (1 - side['frames-body-128'] / stage3[0]):.0f}% of the speed."


def speed_line(bench: dict | None) -> str:
    if not bench or not bench.get("generators_side_by_side"):
        return ""
    side = bench["generators_side_by_side"]
    machine = bench.get("machine", {})
    shown = ", ".join(f"`{name}` {fps:.1f}" for name, fps in side.items())
    return (f"Speed at 128x128 (`python scripts/bench_pipeline.py`, same run, load average "
            f"{machine.get('load_average_1min', float('nan')):.1f}): {shown} frames/s. The warp generator pays for "
            f"the person crop and its paste back into the full-size reference.{stage3_note(side)}\n")


def analysis_text(a: dict | None) -> str:
    """The error analysis of ``scripts/frames_error_analysis.py`` (its JSON) as a markdown subsection."""
    if not a:
        return ""
    gap_rows = "\n".join(f"| {g} ({0.15 * int(g):.2f} s) | {v['mean_joint_motion_px']:.1f} | {v['generator']:.2f} "
                         f"| {v['limb-warp']:.2f} | {v['copy-reference']:.2f} |"
                         for g, v in a["person_psnr_by_gap"].items())
    sh = a["person_psnr_of_the_flow_shifted"]
    worst = min(v for k, v in sh.items() if k != "none")
    share = a["whole_frame_error_share"]
    whole = a["whole_psnr"]
    oracle = a["oracle_residual_flow"]
    fits = "; ".join(f"a {k.split('_')[-1]} field: {v['person_psnr']:.2f} dB, mean length {v['mean_residual_px']:.2f} px"
                     for k, v in oracle.items() if k.startswith("fitted"))
    return f"""### Where the person's error is

`python scripts/frames_error_analysis.py --model {a['model']}` (same pairs; the generator on whole frames):

| time from the reference | mean joint motion (px) | person PSNR, generator | limb-warp | copy-reference |
| --- | ---: | ---: | ---: | ---: |
{gap_rows}

- **Sub-pixel alignment decides the person PSNR.** The reference sampled by the generator's own person flow
  scores {sh['none']:.2f} dB; the same flow shifted by half a pixel scores {worst:.2f} to
  {max(v for k, v in sh.items() if k != 'none'):.2f} dB. The people are {a['person_height_px']:.0f} pixels tall on average ({a['person_pixels']} pixels), with stripes and
  checks a few pixels wide, so where a limb twists about its bone or a garment slides (neither is in 2D keypoints)
  the texture lands out of phase. Even one frame after the reference (0.15 s, about 4 pixels of joint motion) the
  person PSNR is {a['person_psnr_by_gap']['1']['generator']:.2f} dB.
- **The flow is close, not right.** A smooth residual flow fitted to the truth on {oracle['pairs']} pairs (an
  oracle, from {oracle['its_flow']:.2f} dB): {fits}.
- **The whole frame.** Of its squared error, {100 * share['target_person']:.0f}% is on the target person,
  {100 * share['uncovered_background']:.0f}% on the background the reference person uncovered (never seen:
  filled by OpenCV's Telea inpainting) and {100 * share['rest']:.0f}% elsewhere (the soft masks and the plate's
  margin). With the true silhouette and the true background, this flow would give {whole['its_flow_true_silhouette_true_background']:.2f} dB
  ({whole['generator']:.2f} dB as generated).
"""


def section(evaluation: dict, model: str, command: str, minutes: float, bench: dict | None = None,
            analysis: dict | None = None) -> str:
    res = evaluation["results"]
    gen = res["generator"]
    margins = ", ".join(f"{gen['person_psnr'] - res[k]['person_psnr']:+.2f} dB over {k}"
                        for k in ORDER[1:] if k in res)
    met = evaluation.get("targets_met", {})
    target_rows = "\n".join(f"| {TARGETS.get(k, k)} | {'met' if v else '**missed**'} |" for k, v in met.items())
    return f"""## Body frames measured on the person

`{command}`: {evaluation['num_pairs']} held-out pairs (held-out identities and clips, data v2: 200 training
identities with patterned clothing, 26 backgrounds), every method on the same pairs in one run. Person metrics are
computed inside the target's rendered silhouette; "moving" is where the reference and the target differ (the
union of both silhouettes where the pixels changed); sharpness is the generated image's gradient energy inside the
silhouette over the truth's (1.0: as sharp as the truth).

{table(res, model)}

The new generator's person PSNR: {margins}.

| target | |
| --- | --- |
{target_rows}

What was tried, in order (each stage starts from the previous weights; the model card has the commands): the
warp design with its network at 1/4 resolution, 1800 steps: person PSNR 17.15 dB, sharpness 0.77 (the untrained
model, which warps by the part transforms alone, is at limb-warp's level); its network at 1/2 resolution
(`--net-scale 2`), 3000 more steps: 17.35 dB, sharpness 0.78; a third stage at a lower learning rate with the
edge loss doubled: 17.45 dB, sharpness 0.78 (the model shipped until 2026-11-25). Bilinear sampling at
sub-pixel offsets low-passes the texture it moves, so a fourth stage samples the reference bicubically
(`--sample-mode bicubic`, 6500 steps, 36 min): the shipped model above, at about 0.2 dB of person PSNR for the
sharpness (sharp texture a fraction of a pixel off costs more than a blur). Beside it, the same stage with a
learned dense residual of the person's flow (`--flow-correction`), scored by the same command on its
checkpoint: person PSNR 17.49 dB, sharpness 0.86, whole frame 26.80 dB (the residual learns to smear where it
is unsure); 2200 more steps of it with the edge loss at 4: 17.49 dB, sharpness 0.81. The missed targets need more than training time: see below.

{analysis_text(analysis)}
{speed_line(bench)}
Reference | target | new | old | copy-reference | limb-warp, on held-out pairs:

![body person sheet](images/frames_body_person_sheet.png)

_Generated {time.strftime('%Y-%m-%d %H:%M:%S')} in {minutes:.1f} min._
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="frames-body-128", help="the body generator (default frames-body-128)")
    parser.add_argument("--cache", default=None, help="frame-data cache folder (evaluate-frames --cache)")
    parser.add_argument("--doc", default=str(ROOT / "docs" / "results.md"))
    parser.add_argument("--json", default=str(ROOT / "out" / "results_frames.json"))
    parser.add_argument("--bench", default=None, help="a bench_pipeline.py JSON: adds the generators' speed")
    parser.add_argument("--no-analysis", action="store_true",
                        help="leave out scripts/frames_error_analysis.py (a few minutes: it fits oracle flows)")
    args = parser.parse_args(argv)

    start = time.perf_counter()
    sheet = ROOT / "docs" / "images" / "frames_body_person_sheet.png"
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    cmd = ["motion2video", "evaluate-frames", "--model", args.model, "--json", args.json,
           "--contact-sheet", str(sheet), "--no-progress"]
    if args.cache:
        cmd += ["--cache", args.cache]
    subprocess.run([sys.executable, "-m", "motion2video.cli", *cmd[1:]], check=True, cwd=ROOT)
    evaluation = json.loads(Path(args.json).read_text())
    shown = f"motion2video evaluate-frames --model {args.model} --json out/results_frames.json"
    bench = json.loads(Path(args.bench).read_text()) if args.bench else None
    analysis = None
    if not args.no_analysis:
        analysis_json = Path(args.json).with_name("frames_error_analysis.json")
        subprocess.run([sys.executable, str(ROOT / "scripts" / "frames_error_analysis.py"), "--model", args.model,
                        "--json", str(analysis_json), *(["--cache", args.cache] if args.cache else [])], check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
        analysis = json.loads(analysis_json.read_text())
    write_section(args.doc, BEGIN, END, section(evaluation, args.model, shown, (time.perf_counter() - start) / 60,
                                                bench, analysis))
    print(f"wrote {args.doc}, {sheet} and {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
