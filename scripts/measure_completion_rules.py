"""One-off measurement of the completion rules of docs/results.md's rules table: the other side of the body
(``mesh_flow.mirror_vertices``) and the clothes judged per limb segment (``mesh_flow.colour_groups``).

    python scripts/measure_completion_rules.py

Fits Anny to each reference as ``synthesize --frame-model frames-body-mesh-256`` does (two frames of the demo's walk
observed, two predicted; ``--crop-person`` for the photos) and prints, for the hidden vertices:
- ``fashion_man_red_jacket.png``'s shins (trousers region, lower-leg bones): the share completed from a dark pixel
  (mean RGB under 130), with the segment rule as shipped, with every segment judged alone, and with none;
- the demo reference's shirt: the share completed from a skin pixel, with no colour test, with and without the mirror.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2video.generator import mesh_flow
from motion2video.generator.checkpoint import load_frame_model
from motion2video.generator.mesh_fit import reference_crop
from motion2video.stages.generation import mesh_setup
from motion2video.stages.reference import load_reference
from motion2video.stages.sampling import Forecast
from motion2video.stages.structure import render_structures
from renderers import anny_model

ROOT = Path(__file__).resolve().parents[1]


def fitted(path: Path, **load):
    """The reference and the MeshVideo synthesize fits to it (the demo walk's frames 0-3)."""
    walk = np.load(ROOT / "demo_inputs" / "cmu_walk.npz")["joints"].astype(np.float64)
    forecast = Forecast(observed=walk[:2], futures=walk[None, 2:4], fps=25.0, layout="body3d", model="measure",
                        seed=0)
    reference = load_reference(path, size=256, domain="body", **load)
    net = load_frame_model("frames-body-mesh-256").model
    return reference, mesh_setup(net, reference, render_structures(forecast, domain="body", size=256,
                                                                   reference=reference))


def colours_at(picture: np.ndarray, uv: np.ndarray, ids: np.ndarray) -> np.ndarray:
    rows, cols = mesh_flow.pixel_indices(uv[ids], *picture.shape[:2])
    return picture[rows, cols].astype(np.float64)


def main() -> int:
    regions = anny_model.vertex_regions()
    reference, video = fitted(ROOT.parent / "shared" / "data" / "photos" / "fashion_man_red_jacket.png",
                              crop_person=True)
    picture = reference_crop(reference.image, video.crop, 256)
    uv, seen = video.reference.uv[0], video.reference.visible[0]
    shins = np.flatnonzero(~seen & (regions == anny_model.TROUSERS) & (mesh_flow.limb_segments() == 2))
    shipped = mesh_flow.colour_groups

    def dark_share(groups) -> float:
        mesh_flow.colour_groups = groups
        try:
            done = mesh_flow.complete_reference_uv(uv, seen, image=picture, person=video.person)
        finally:
            mesh_flow.colour_groups = shipped
        return float((colours_at(picture, done, shins).mean(axis=1) < 130).mean())

    def every_segment(ref_uv, sources, image):
        split = np.isin(regions, (anny_model.TOP, anny_model.TROUSERS))
        return regions * (len(mesh_flow.LIMB_SEGMENTS) + 1) + np.where(split, mesh_flow.limb_segments(), 0)

    print(f"fashion_man_red_jacket.png, {len(shins)} hidden shin vertices completed from a dark pixel: "
          f"shipped {dark_share(shipped):.2f}, every segment alone {dark_share(every_segment):.2f}, "
          f"no segment {dark_share(lambda u, s, i: regions):.2f}")

    reference, video = fitted(ROOT / "demo_inputs" / "reference_body.png")
    x0, y0, side = video.crop
    picture = reference.image[y0:y0 + side, x0:x0 + side]
    uv, seen = video.reference.uv[0], video.reference.visible[0]
    shirt = np.flatnonzero(~seen & (regions == anny_model.TOP))

    def skin_share(mirror: bool) -> float:
        c = colours_at(picture, mesh_flow.complete_reference_uv(uv, seen, mirror=mirror), shirt)
        return float(((c[:, 0] > 150) & (c[:, 0] - c[:, 2] > 40)).mean())

    print(f"demo reference, {len(shirt)} hidden shirt vertices on skin (no colour test): "
          f"without the mirror {skin_share(False):.3f}, with it {skin_share(True):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
