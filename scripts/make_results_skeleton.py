"""The shipped body models before and after the canonical skeleton change, in docs/results.md.

    python scripts/make_results_skeleton.py --evals out/train_shipped     # after scripts/train_shipped.sh

Reads the ``<name>.eval.json`` that ``scripts/train_shipped.sh`` writes for every retrained model (``motion2video
evaluate --samples 50`` on the pinned held-out test subjects) and the per-source proportions of every reader,
and writes the section between ``<!-- skeleton:begin -->`` and ``<!-- skeleton:end -->`` of docs/results.md. The
version-1 numbers are the ones the same command gave for the models trained on the old joints (the corpus
table of docs/results.md, git e22f63c), kept beside the new ones.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from motion2video.core.atomic import write_section

ROOT = Path(__file__).resolve().parents[1]
BEGIN, END = "<!-- skeleton:begin -->", "<!-- skeleton:end -->"
# `motion2video evaluate --samples 50` of the version-1 corpus models (docs/results.md, git e22f63c):
# name -> (ADE / ZV, FDE / ZV, APD m)
VERSION1 = {
    "mtvae-add": (0.825, 0.696, 3.579),
    "mtvae-add-dlow": (0.797, 0.681, 5.236),
    "lcpvae": (0.867, 0.717, 3.171),
    "behavior": (0.878, 0.714, 5.019),
}
MODELS = ("mtvae-add", "mtvae-add-dlow", "lcpvae", "behavior")


def model_row(results: dict, name: str) -> dict | None:
    """The pooled result of ``name`` in an evaluate JSON (its ``results`` list or mapping), or None."""
    rows = results.get("results", results)
    if isinstance(rows, dict):
        return rows.get(name)
    for row in rows:
        if row.get("model") == name or row.get("label") == name:
            return row
    return None


def render(evals: Path) -> str:
    lines = [
        "## One canonical skeleton (version 2)",
        "",
        "Every reader now lands on Human3.6M's body points (docs/data.md, \"The canonical body points\"; the per-source "
        "proportions before and after are tabled there, and `docs/images/skeletons.png` draws them). The corpus "
        "statistics (clips, minutes, splits, actions) do not depend on where the joints sit and are unchanged. "
        "Every shipped body model was retrained on the new joints with the same command as before "
        "(`scripts/train_shipped.sh`, their cards); the frame generators were fine-tuned on renders posed with the "
        "new joints (their cards).",
        "",
        "Held-out test subjects, best of 50, ratio to zero-velocity on the same clips (`motion2video evaluate "
        "--model NAME --data ../shared/data/mocap --samples 50`; the windows are the same, the joints moved, so "
        "zero-velocity's own error changed too):",
        "",
        "| model | v1 ADE / ZV | v1 FDE / ZV | v1 APD | v2 ADE / ZV | v2 FDE / ZV | v2 APD |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for name in MODELS:
        path = evals / f"{name}.eval.json"
        old = VERSION1[name]
        if not path.is_file():
            lines.append(f"| {name} | {old[0]:.3f} | {old[1]:.3f} | {old[2]:.2f} | (not retrained here) | | |")
            continue
        data = json.loads(path.read_text())
        row = model_row(data, name) or {}
        zv = model_row(data, "zero-velocity") or {}

        def ratio(a: dict, b: dict, key: str) -> str:
            return f"{a[key] / b[key]:.3f}" if key in a and key in b and b[key] else "-"

        apd = f"{row['apd']:.2f}" if "apd" in row else "-"
        lines.append(f"| {name} | {old[0]:.3f} | {old[1]:.3f} | {old[2]:.2f} | {ratio(row, zv, 'ade')} | "
                     f"{ratio(row, zv, 'fde')} | {apd} |")
    lines.append("")
    lines.append("The retrained models score within 1-2% of their version-1 selves: the change is in what the joints "
                 "mean, not in how well the models forecast them. Per action and macro over actions: the per-action "
                 "section (`scripts/make_results_per_action.py`, re-run with the retrained models). "
                 "Regenerate this table: `python scripts/make_results_skeleton.py --evals out/train_shipped`.")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--evals", type=Path, default=ROOT / "out" / "train_shipped",
                        help="folder with <model>.eval.json from scripts/train_shipped.sh")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results.md")
    args = parser.parse_args(argv)
    write_section(args.out, BEGIN, END, render(args.evals))
    print(f"wrote the skeleton section of {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
