"""Shared pytest fixtures: where the shared data lives (``../shared`` beside the repository root)."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_DIR = Path(__file__).resolve().parents[2] / "shared"


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
    """The 72 real BVH clips with their ``manifest.csv`` (``shared/data/mocap``)."""
    return _existing(shared_dir / "data" / "mocap")


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
