"""Where the mesh generator's person is off on a real video, per body part.

    python scripts/measure_silhouette_parts.py [--video ../shared/data/video/dancer.avi] [--model frames-body-mesh-128]

The pairs of ``motion2video evaluate-frames --video`` (frame 0 the reference, 64 later frames the targets, the
silhouettes the mesh generator is given: the fitted mesh grown by the person's clothes margin). Per body part (each
pixel goes to the nearest bone of the target's BlazePose skeleton, named by the joint it ends at), the person's
pixels, those the given silhouette does not cover, and the silhouette's pixels that are not the person. Then the
generator's share of the squared error inside the person that the uncovered pixels carry, and of its absolute
error in pixels the silhouette covers that are neither the person nor the frame-0 person (copy-reference beside
it). About a minute with the video's pose track cached.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from motion2video.core.skeletons import H36M_17
from motion2video.evaluation.video_frames import video_frames, video_pairs, with_mesh
from motion2video.frames.checkpoint import load_frame_model
from motion2video.frames.evaluate import run_baseline, run_generator
from motion2video.pose.estimate import default_model

REPO = Path(__file__).resolve().parents[1]
BONES = [(j, p) for j, p in enumerate(H36M_17.parents) if p >= 0]


def nearest_bone(mask: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(M,) index into BONES of the nearest 2D bone of ``points`` (17, 2) for every pixel of ``mask`` (S, S)."""
    ys, xs = np.nonzero(mask)
    pix = np.stack([xs + 0.5, ys + 0.5], axis=1)
    best, label = np.full(len(pix), np.inf), np.zeros(len(pix), np.int64)
    for k, (j, p) in enumerate(BONES):
        a, ab = points[p], points[j] - points[p]
        t = np.clip(((pix - a) @ ab) / max(float(ab @ ab), 1e-6), 0.0, 1.0)
        d = np.linalg.norm(pix - (a + t[:, None] * ab), axis=1)
        closer = d < best
        best[closer], label[closer] = d[closer], k
    return label


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--video", type=Path, default=REPO.parent / "shared" / "data" / "video" / "dancer.avi")
    parser.add_argument("--model", default="frames-body-mesh-128")
    args = parser.parse_args()
    net = load_frame_model(args.model).model
    frames = video_frames(args.video, size=net.config.image_size, model=default_model())
    pairs = with_mesh(video_pairs(frames), frames)
    person, given = pairs.tgt_masks > 0.5, pairs.mesh_tgt_masks > 0.5
    counts = np.zeros((3, len(BONES)))
    for i in range(len(person)):
        for row, mask in enumerate((person[i], person[i] & ~given[i], given[i] & ~person[i])):
            counts[row] += np.bincount(nearest_bone(mask, pairs.tgt_points[i]), minlength=len(BONES))
    print("| bone ending at | person pixels | person not covered | covered, not person |")
    print("| --- | ---: | ---: | ---: |")
    for k, (j, _) in enumerate(BONES):
        total, uncovered, over = counts[:, k]
        print(f"| {H36M_17.joints[j]} | {total:.0f} | {uncovered:.0f} ({uncovered / max(total, 1):.1%}) | "
              f"{over:.0f} ({over / max(total, 1):.0%}) |")
    truth = pairs.tgt_images.astype(np.float64) / 255.0
    generated = run_generator(net, pairs).astype(np.float64) / 255.0
    squared = ((generated - truth) ** 2).mean(-1)
    uncovered = person & ~given
    print(f"person pixels not covered: {uncovered.sum() / person.sum():.1%}, carrying "
          f"{squared[uncovered].sum() / squared[person].sum():.0%} of the generator's squared error in the person")
    ref_person = np.repeat(pairs.ref_masks[:1] > 0.5, len(person), axis=0)
    stray = given & ~person & ~ref_person
    copy = run_baseline("copy-reference", pairs.ref_images, pairs.ref_points, pairs.tgt_points).astype(np.float64)
    for name, pred in (("generator", generated), ("copy-reference", copy / 255.0)):
        error = np.abs(pred - truth).mean(-1)
        print(f"{name}: {error[stray].sum() / error.sum():.0%} of its absolute error lies in pixels the silhouette "
              "covers that are neither the person nor the frame-0 person")


if __name__ == "__main__":
    main()
