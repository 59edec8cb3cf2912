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
