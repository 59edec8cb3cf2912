"""The parsed-mocap cache gives exactly what a fresh read gives, and reads a file afresh when it changed or its
entry is damaged."""

from __future__ import annotations

import os
import shutil

import numpy as np

from motion2video.data.clip_cache import cache_key, cached_canonical
from motion2video.formats.mocap import mocap_canonical


def _same(a, b) -> None:
    assert a.names == b.names and a.rig == b.rig and a.unit == b.unit and a.fps == b.fps
    for name in ("joints", "nodes"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x, y), name


def test_a_cached_read_is_the_fresh_read(tmp_path, mocap_dir):
    bvh = tmp_path / "08_01.bvh"
    shutil.copy(mocap_dir / "cmu" / "08_01.bvh", bvh)
    folder = tmp_path / "cache"
    fresh = mocap_canonical(bvh)
    first = cached_canonical(bvh, folder=folder)
    assert len(list(folder.glob("*.npz"))) == 1
    _same(first, fresh)
    _same(cached_canonical(bvh, folder=folder), fresh)


def test_a_changed_file_or_a_damaged_entry_is_read_afresh(tmp_path, mocap_dir):
    bvh = tmp_path / "walk.bvh"
    shutil.copy(mocap_dir / "cmu" / "08_01.bvh", bvh)
    folder = tmp_path / "cache"
    cached_canonical(bvh, folder=folder)
    entry = folder / f"{cache_key(bvh)}.npz"
    entry.write_bytes(b"not an npz")
    _same(cached_canonical(bvh, folder=folder), mocap_canonical(bvh))  # the damaged entry was replaced
    assert entry.read_bytes()[:2] == b"PK"

    text = bvh.read_text().splitlines()
    frames = [i for i, line in enumerate(text) if line.startswith("Frames:")][0]
    kept = text[:frames] + ["Frames: 10"] + text[frames + 1:frames + 12]  # Frame Time + the first 10 frames
    bvh.write_text("\n".join(kept) + "\n")
    os.utime(bvh, ns=(1, 1))
    shorter = cached_canonical(bvh, folder=folder)
    assert shorter.num_frames == 10
    _same(shorter, mocap_canonical(bvh))
    assert len(list(folder.glob("*.npz"))) == 2


def test_an_unwritable_cache_still_reads(tmp_path, mocap_dir):
    folder = tmp_path / "cache"
    folder.write_text("a file where the cache folder would be")
    clip = cached_canonical(mocap_dir / "cmu" / "08_01.bvh", folder=folder)
    assert clip.joints.shape[1:] == (17, 3)
