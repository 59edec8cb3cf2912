"""Shared pytest fixtures: where the shared data lives (``../shared`` beside the repository root)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

# Property-based tests (tests/test_fuzz_readers.py): "ci" is the default profile (200 derandomised examples per
# reader, the same cases on every run); `make fuzz` runs "fuzz" (10,000 per reader, still repeatable) and `make check`
# runs "check" (25 per reader: the edit loop).
settings.register_profile("ci", max_examples=200, derandomize=True, print_blob=True)
settings.register_profile("check", max_examples=25, derandomize=True, print_blob=True)
settings.register_profile("fuzz", max_examples=10_000, derandomize=True, print_blob=True)
settings.load_profile("ci")

from motion2video.formats.canonical import CanonicalClip, floor_height
from motion2video.formats.manifest import ManifestEntry, read_manifest
from motion2video.formats.manifest import default_trim
from motion2video.formats.mocap import load_mocap, mocap_canonical
from motion2video.core.motion import Motion

SHARED_DIR = Path(__file__).resolve().parents[2] / "shared"

# The files that keep a test worker longest (minutes each in a full run on 2 cores), started first so that the
# workers finish together: xdist hands out whole files (--dist loadfile) in collection order when told not to
# start the files with the most tests first (--no-loadscope-reorder, as make test runs it), which would leave
# these single long tests for the end.
LONGEST_FIRST = ("test_cli_examples_show.py", "test_cli_examples_make.py", "test_cli_examples_score.py",
                 "test_cli_examples_frames.py", "test_transfer.py", "test_readme_examples.py", "test_exact_resume.py",
                 "test_interrupts.py", "test_determinism.py", "test_pipeline.py", "test_batch.py", "test_analogy.py")


def pytest_collection_modifyitems(config, items):
    """The files of :data:`LONGEST_FIRST` first, in that order; every other test after them in its own order."""
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))



def _existing(path: Path) -> Path:
    if not path.is_dir():
        pytest.fail(f"shared data directory not found: {path} (the tests read real data from ../shared)")
    return path


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """``../shared`` beside the repository root."""
    return _existing(SHARED_DIR)


@pytest.fixture(scope="session")
def mocap_dir(shared_dir: Path) -> Path:
    """The real mocap clips (275 files: BVH, DeepMimic, exp-map) with their ``manifest.csv``
    (``shared/data/mocap``)."""
    return _existing(shared_dir / "data" / "mocap")


@dataclass
class LoadedClip:
    """One manifest row, loaded as the corpus loads it.

    Attributes:
        entry: the manifest row.
        canonical: the whole file in the project frame (every node, no trim, no floor).
        motion: the canonical Motion (true fps, default trim, floor at 0), as ``load_mocap`` gives it.
        nodes: (T, N, 3) every node over the motion's frames, with the same floor.
    """

    entry: ManifestEntry
    canonical: CanonicalClip
    motion: Motion
    nodes: np.ndarray


@pytest.fixture(scope="session")
def mocap_manifest(mocap_dir: Path) -> dict[str, ManifestEntry]:
    return read_manifest(mocap_dir / "manifest.csv")


@pytest.fixture(scope="session")
def mocap_clips(mocap_dir: Path, mocap_manifest) -> dict[str, LoadedClip]:
    """Every row of the mocap manifest, loaded once per test session (about 15 s on a free core)."""
    out = {}
    for name, entry in mocap_manifest.items():
        canon = mocap_canonical(mocap_dir / name, entry=entry)
        motion = load_mocap(mocap_dir / name, manifest=entry, canonical=canon)
        trim = default_trim(canon.rig)
        nodes = canon.nodes[trim:].copy()
        nodes[..., 2] -= floor_height(canon.joints[trim:])
        out[name] = LoadedClip(entry, canon, motion, nodes)
    return out


@pytest.fixture(scope="session")
def face_dir(shared_dir: Path) -> Path:
    """The 6 real ARKit face captures with their ``manifest.csv`` (``shared/data/face``)."""
    return _existing(shared_dir / "data" / "face")


@pytest.fixture(scope="session", autouse=True)
def one_torch_thread():
    """Every test runs torch on one thread: the tiny models here ran 10-40x faster that way on 2 shared cores,
    and results are bit-reproducible."""
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


def link_clips(root: Path, mocap_dir: Path, clips: tuple[str, ...]) -> Path:
    """A small mocap folder for fast tests: ``clips`` (paths relative to ``mocap_dir``) symlinked under ``root``
    (no manifest, so header frame rates apply)."""
    for rel in clips:
        target = root / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        target.symlink_to(mocap_dir / rel)
    return root


@pytest.fixture(scope="session")
def photos_dir(shared_dir: Path) -> Path:
    """Three real photos of people (``shared/data/photos``: skier, man_by_truck, three_walking)."""
    return _existing(shared_dir / "data" / "photos")


@pytest.fixture(scope="session")
def dancer_video(shared_dir: Path) -> Path:
    """A real 63 s, 25 fps video of one dancer (``shared/data/video/dancer.avi``)."""
    path = shared_dir / "data" / "video" / "dancer.avi"
    if not path.is_file():
        pytest.fail(f"shared video not found: {path}")
    return path
