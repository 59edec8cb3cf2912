"""Golden-frame regression tests for every render style, on a real mocap clip, a real face capture and the
demo inputs, through the ``golden_frames`` fixture of the package's pytest plugin (goldens in ``tests/golden/``).
Regenerate after an intended change with ``make golden`` (``pytest --update-golden``).

Skeleton and heatmap goldens must match within 1 grey level; mesh and face goldens within a relative L1
error of 2e-2 (OSMesa's rasteriser is deterministic here, but the tolerance absorbs llvmpipe differences
between Mesa builds).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2video.formats.io import load_motion, resample_motion
from motion2video.apps.render import render_motion

REPO = Path(__file__).resolve().parents[1]
SIZE = 96
FRAMES = (0, 12, 24)  # frames kept per clip: enough to see motion, small enough to commit


def _clip(path: Path, fps: float = 25.0, frames: int = 25):
    motion = load_motion(path)
    return resample_motion(motion, fps).slice(0, frames)


def _check(golden_frames, frames: np.ndarray, name: str, *, tolerance: float, metric: str, fps: float) -> None:
    assert frames.shape[1:] == (SIZE, SIZE, 3) and frames.dtype == np.uint8
    assert frames.std() > 1.0, "a golden of a blank frame proves nothing"
    golden_frames(frames[list(FRAMES)], name=name, tolerance=tolerance, metric=metric, fps=fps)


BODY_INPUTS = {
    "cmu_08_01": lambda shared: shared / "data" / "mocap" / "cmu" / "08_01.bvh",
    "demo_walk_to_run": lambda shared: REPO / "demo_inputs" / "walk_to_run.npz",
}
FACE_INPUTS = {
    "llv_dao": lambda shared: shared / "data" / "face" / "llv" / "dao.csv",
    "demo_smile": lambda shared: REPO / "demo_inputs" / "smile.npz",
}


@pytest.mark.parametrize("clip", sorted(BODY_INPUTS))
@pytest.mark.parametrize("style,palette", [("skeleton", "leftright"), ("skeleton", "openpose"), ("heatmap", "leftright")])
def test_structure_goldens(clip, style, palette, shared_dir, golden_frames):
    motion = _clip(BODY_INPUTS[clip](shared_dir))
    frames = render_motion(motion, style=style, size=SIZE, palette=palette)
    _check(golden_frames, frames, f"{clip}_{style}_{palette}", tolerance=1, metric="max", fps=motion.fps)


@pytest.mark.slow
@pytest.mark.parametrize("clip", sorted(BODY_INPUTS))
def test_mesh_goldens(clip, shared_dir, golden_frames):
    motion = _clip(BODY_INPUTS[clip](shared_dir))
    frames = render_motion(motion, style="mesh", size=SIZE)
    _check(golden_frames, frames, f"{clip}_mesh", tolerance=2e-2, metric="rel_l1", fps=motion.fps)


@pytest.mark.slow
@pytest.mark.parametrize("clip", sorted(FACE_INPUTS))
def test_face_goldens(clip, shared_dir, golden_frames):
    motion = _clip(FACE_INPUTS[clip](shared_dir))
    frames = render_motion(motion, style="face", size=SIZE)
    _check(golden_frames, frames, f"{clip}_face", tolerance=2e-2, metric="rel_l1", fps=motion.fps)
