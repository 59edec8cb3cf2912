"""Draw docs/images/skeletons.png: every source's canonical H36M-17 skeleton beside Human3.6M's.

Each source gives one frame of a walk (mid-stance: the frame whose ankles are closest together), moved so
its pelvis is at the origin, turned to face -y and scaled so its leg (thigh + shin) is Human3.6M's 897 mm.
Front (x-z) and side (y-z) views; Human3.6M's own skeleton (subject S1 bone lengths) is drawn grey behind
every source, and the four proportions the skeleton is checked on are printed under each (1.00 = as in Human3.6M).

    python scripts/make_skeleton_figure.py [--mocap ../shared/data/mocap] [--out docs/images/skeletons.png]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from motion2video.core.skeletons import (H36M_17, H36M_BONES_MM, H36M_LEG_MM, L_ANKLE, L_HIP, PELVIS, R_ANKLE, R_HIP,
                                         leg_length, proportion_ratios)
from motion2video.formats.io import load_motion

ROOT = Path(__file__).resolve().parents[1]
# source label -> file under the mocap folder (or demo_inputs/ for the procedural generator)
SOURCES = {
    "CMU Daz BVH": "cmu/08_01.bvh",
    "acrnn (Daz)": "acrnn/salsa_01a.bvh",
    "CMU 3dsMax": "cmu/131_01.bvh",
    "CMU MotionBuilder": "cmu/01_01.bvh",
    "CMU amc2bvh": "cmu/16_01.bvh",
    "DeepMimic BVH": "deepmimic/humanoid3d_walk.bvh",
    "DeepMimic .txt": "deepmimic/txt/humanoid3d_walk.txt",
    "MASS": "mass/mass_walk.bvh",
    "exp-map benchmark": "cmu-bench/test/walking/walking_1.txt",
    "procedural demo": "demo:walk_to_run.npz",
}


def human36m_pose() -> np.ndarray:
    """(17, 3) Human3.6M's skeleton standing straight, arms hanging, mm."""
    b = H36M_BONES_MM
    j = np.zeros((17, 3))
    for side, (hip, knee, ankle, shoulder, elbow, wrist) in ((-1, (1, 2, 3, 14, 15, 16)), (1, (4, 5, 6, 11, 12, 13))):
        j[hip] = (side * b["hip"], 0, 0)
        j[knee] = j[hip] - (0, 0, b["thigh"])
        j[ankle] = j[knee] - (0, 0, b["shin"])
    j[7] = (0, 0, b["pelvis_spine"])
    j[8] = j[7] + (0, 0, b["spine_thorax"])
    j[9] = j[8] + (0, 0, b["thorax_nose"])
    j[10] = j[9] + (0, 0, b["nose_head"])
    for side, (shoulder, elbow, wrist) in ((1, (11, 12, 13)), (-1, (14, 15, 16))):
        j[shoulder] = j[8] + (side * b["thorax_shoulder"], 0, 0)
        j[elbow] = j[shoulder] - (0, 0, b["upper_arm"])
        j[wrist] = j[elbow] - (0, 0, b["forearm"])
    return j


def normalised_frame(joints: np.ndarray) -> np.ndarray:
    """(17, 3) mid-stance frame of (T, 17, 3) joints: pelvis at 0, facing -y, leg = 897 mm."""
    t = int(np.argmin(np.linalg.norm(joints[:, L_ANKLE, :2] - joints[:, R_ANKLE, :2], axis=-1)))
    j = joints[t] - joints[t, PELVIS]
    across = j[L_HIP] - j[R_HIP]
    yaw = np.arctan2(across[1], across[0])  # turn the hip axis onto +x (so the body faces -y)
    c, s = np.cos(-yaw), np.sin(-yaw)
    j = j @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    return j * (H36M_LEG_MM / leg_length(joints))


def draw(out: Path, mocap: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref = human36m_pose()
    panels = [("Human3.6M (S1)", ref[None], ref)]
    for label, name in SOURCES.items():
        path = ROOT / "demo_inputs" / name[5:] if name.startswith("demo:") else mocap / name
        joints = np.asarray(load_motion(path).joints, np.float64)
        panels.append((label, joints, normalised_frame(joints)))
    fig, axes = plt.subplots(2, len(panels), figsize=(1.6 * len(panels), 6.4))
    colour = {"left": "tab:green", "right": "tab:red", "centre": "tab:blue"}
    for col, (label, joints, frame) in enumerate(panels):
        ratios = proportion_ratios(joints)
        for row, (a, b, view) in enumerate(((0, 2, "front"), (1, 2, "side"))):
            ax = axes[row, col]
            for i, p in enumerate(H36M_17.parents):
                if p < 0:
                    continue
                ax.plot(ref[[p, i], a], ref[[p, i], b], color="0.8", lw=3, zorder=1)
                name = H36M_17.joints[i]
                side = "left" if name.startswith("left") else "right" if name.startswith("right") else "centre"
                ax.plot(frame[[p, i], a], frame[[p, i], b], color=colour[side], lw=1.6, zorder=2)
            ax.scatter(frame[[8, 9, 10], a], frame[[8, 9, 10], b], s=8, color="k", zorder=3)
            ax.set_xlim(-650, 650)
            ax.set_ylim(-1000, 800)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            if row == 0:
                ax.set_title(label, fontsize=8)
            else:
                ax.set_xlabel("\n".join(f"{k.replace('_', '-')} {v:.2f}" for k, v in ratios.items()), fontsize=6.5)
            if col == 0:
                ax.set_ylabel(view, fontsize=9)
    fig.suptitle("Canonical H36M-17 of every source (skeleton version 2), leg scaled to 897 mm, grey: Human3.6M;"
                 " numbers: ratio to Human3.6M's proportions", fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mocap", type=Path, default=ROOT.parent / "shared" / "data" / "mocap")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / "skeletons.png")
    args = parser.parse_args(argv)
    print(f"wrote {draw(args.out, args.mocap)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
