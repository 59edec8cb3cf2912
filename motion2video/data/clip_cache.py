"""A disk cache of parsed motion-capture files, so that a corpus is read and posed once, not by every command.

Reading the mocap corpus means parsing text and running forward kinematics on every frame of every file: about
30 s of one core for ``../shared/data/mocap`` (225 clips) and several minutes for the Bandai sets. ``train``,
``evaluate`` and ``corpus-stats`` all start that way, so the result of
:func:`motion2video.formats.mocap.mocap_canonical` (a :class:`~motion2video.formats.canonical.CanonicalClip`,
before trimming, floor and resampling) is kept per file in ``$XDG_CACHE_HOME/motion2video/mocap`` (default
``~/.cache/motion2video/mocap``), the arrays stored exactly (no re-encoding), so a cached read gives the same
numbers as a fresh one.

An entry's key is the file's absolute path, size and modification time, the DeepMimic character file (when one
is given) and a digest of the readers' own source files, so an edited file or a changed reader is read afresh.
A damaged or unreadable entry is read afresh too; an entry that cannot be written (a read-only home) is
skipped. Nothing else of the clip (trim, floor, fps, label) is cached: those come from the manifest each time.
"""

from __future__ import annotations

import functools
import hashlib
import os
import zipfile
from pathlib import Path

import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.formats.canonical import CanonicalClip
from motion2video.formats.manifest import ManifestEntry
from motion2video.formats.mocap import mocap_canonical

# the modules whose code decides what a cached clip holds
READER_MODULES = ("canonical.py", "mocap.py", "bvh.py", "deepmimic.py", "expmap.py", "numbers.py")


def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/motion2video/mocap`` (default ``~/.cache/motion2video/mocap``)."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "motion2video" / "mocap"


@functools.lru_cache(maxsize=1)
def reader_digest() -> str:
    """sha256 of the reader modules' source (:data:`READER_MODULES`), their data tables and the canonical skeleton's."""
    formats = Path(mocap_canonical.__code__.co_filename).parent
    digest = hashlib.sha256()
    tables = sorted((formats / "data").glob("*"))  # rig tables the readers load
    for path in [formats / name for name in READER_MODULES] + tables + [formats.parent / "core" / "skeletons.py"]:
        if path.is_file():
            digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()


def cache_key(path: Path, character: str | Path | None = None) -> str:
    """The entry name of ``path`` (see the module docstring)."""
    stat = path.stat()
    parts = [str(path.resolve()), str(stat.st_size), str(stat.st_mtime_ns), str(character or ""), reader_digest()]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:32]


def _read_entry(file: Path) -> CanonicalClip | None:
    try:
        with np.load(file, allow_pickle=False) as z:
            return CanonicalClip(joints=z["joints"], nodes=z["nodes"], names=tuple(str(n) for n in z["names"]),
                                 rig=str(z["rig"]), unit=float(z["unit"]), fps=float(z["fps"]))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return None


def cached_canonical(path: str | Path, *, entry: ManifestEntry | None = None,
                     character: str | Path | None = None, folder: str | Path | None = None) -> CanonicalClip:
    """:func:`~motion2video.formats.mocap.mocap_canonical` of ``path``, from the cache when it holds this file.

    Args:
        path: a mocap file the corpus lists.
        entry: its manifest row (tells the reader which kind the file is).
        character: DeepMimic files only: their character file.
        folder: the cache folder (None: :func:`cache_dir`).
    Returns:
        the clip, read from the cache or freshly (and then stored).
    """
    path = Path(path)
    file = Path(folder or cache_dir()) / f"{cache_key(path, character)}.npz"
    if file.is_file():
        clip = _read_entry(file)
        if clip is not None:
            return clip
    clip = mocap_canonical(path, entry=entry, character=character)
    try:
        save_npz(file, {"joints": clip.joints, "nodes": clip.nodes, "names": np.array(clip.names),
                        "rig": np.array(clip.rig), "unit": np.array(clip.unit), "fps": np.array(clip.fps)})
    except OSError:
        pass  # a cache that cannot be written only costs the next reader the parse
    return clip
