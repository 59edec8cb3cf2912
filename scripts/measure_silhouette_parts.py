"""Where the mesh generator's person is off on a real video, per body part.

    python scripts/measure_silhouette_parts.py [--video ../shared/data/video/dancer.avi] [--model frames-body-mesh-128]

The pairs of ``motion2video evaluate-frames --video`` (frame 0 the reference, 64 later frames the targets, the
silhouettes the mesh generator is given: the fitted mesh grown by the person's clothes margin). Per body part (each
pixel goes to the nearest bone of the target's BlazePose skeleton, named by the joint it ends at), the person's
pixels, those the given silhouette does not cover, and the silhouette's pixels that are not the person. Then the
generator's share of the squared error inside the person that the uncovered pixels carry, and of its absolute
error in pixels the silhouette covers that are neither the person nor the frame-0 person (copy-reference beside
it). Last, the mean person PSNR over the pairs (as ``evaluate-frames`` reports it) of the generator, of limb-warp, and
of copy-reference, and of the generator's frames mended where the silhouette misses: the uncovered person pixels
given the truth, or the generator's nearest colour inside the person (what it would paint had its silhouette covered
them), and then the pixels it covers outside the person given the truth (a silhouette exactly the person's); with
the L1 of each. About a minute with the
video's pose track cached.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from motion2video.core.skeletons import H36M_17
from motion2video.evaluation.video_frames import video_frames, video_pairs, with_mesh
from motion2video.frames.checkpoint import load_frame_model
from motion2video.frames.evaluate import region_psnr, run_baseline, run_generator
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


def extend_colours(images: np.ndarray, source: np.ndarray, fill: np.ndarray) -> np.ndarray:
    """Copies of (N, S, S, 3) ``images`` whose ``fill`` pixels take the colour of the nearest ``source`` pixel
    (both (N, S, S) bool; :func:`motion2video.frames.mesh_warp.fill_outside_person`): what a generator would paint
    there if its silhouette reached them and it extended its neighbouring colours."""
    import torch

    from motion2video.frames.mesh_warp import fill_outside_person

    nearest = fill_outside_person(torch.from_numpy(images).permute(0, 3, 1, 2),
                                  torch.from_numpy(source.astype(np.float32))).permute(0, 2, 3, 1).numpy()
    return np.where(fill[..., None], nearest, images)


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
    limb = run_baseline("limb-warp", pairs.ref_images, pairs.ref_points, pairs.tgt_points)
    ours = np.round(generated * 255.0).astype(np.uint8)
    extended = extend_colours(ours, person & given, uncovered)
    exact = np.where((given & ~person)[..., None], pairs.tgt_images, extended)
    for name, pred in (("generator", ours), ("limb-warp", limb), ("copy-reference", copy.astype(np.uint8)),
                       ("generator, uncovered person pixels given the truth", np.where(
                           uncovered[..., None], pairs.tgt_images, ours)),
                       ("generator, uncovered person pixels given its nearest colour in the person", extended),
                       ("the same, and the pixels it covers outside the person given the truth", exact)):
        psnr = [region_psnr(p, t, m) for p, t, m in zip(pred, pairs.tgt_images, person)]
        l1 = np.abs(pred.astype(np.float64) - pairs.tgt_images).mean() / 255.0
        print(f"{name}: mean person PSNR {np.nanmean(psnr):.2f} dB, L1 {l1:.4f}")


if __name__ == "__main__":
    main()
