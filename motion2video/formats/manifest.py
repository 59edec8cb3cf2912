"""The mocap ``manifest.csv``: per clip its action label, rig, true frame rate and notes.

Format (one header row)::

    file,action,rig,fps,frames,source,licence,notes
    cmu/16_01.bvh,"jump (...)",cmu-daz,120.0,322,...

``file`` is relative to the manifest's folder. An empty ``fps`` means "trust the file's header". The face
manifest (``file,fps,rows,duration_s,...,content,...``) reads with the same code; its label is ``content``.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError

REQUIRED_COLUMNS = ("file",)


@dataclass(frozen=True)
class ManifestEntry:
    """One manifest row.

    Attributes:
        file: path relative to the manifest's folder, with forward slashes.
        label: the ``action`` column (``content`` in the face manifest).
        rig: the ``rig`` column as written (loaders detect the rig from joint names themselves).
        fps: true frame rate, or None when the column is empty.
        frames: declared frame count, or None.
        notes: free text.
        licence: the ``licence`` column (None when empty).
        group: the ``skeleton_group`` column, the performer of a source that names none per clip (Bandai-Namco's
            sets), or None.
    """

    file: str
    label: str
    rig: str | None
    fps: float | None
    frames: int | None
    notes: str
    licence: str | None = None
    group: str | None = None


def read_manifest(path: str | Path) -> dict[str, ManifestEntry]:
    """Read a manifest.csv into ``{file: entry}`` in file order. Raises InputError on a malformed file."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    with path.open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        missing = [c for c in REQUIRED_COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise InputError(f"manifest lacks column(s) {', '.join(missing)}", path)
        entries: dict[str, ManifestEntry] = {}
        for row in reader:
            line = reader.line_num
            file = (row["file"] or "").strip().replace("\\", "/")
            if not file:
                raise InputError(f"line {line}: empty file column", path)
            fps = _optional_number(row.get("fps"), "fps", line, path)
            if fps is not None and fps <= 0:
                raise InputError(f"line {line}: fps must be positive, got {fps}", path)
            frames = _optional_number(row.get("frames"), "frames", line, path)
            entries[file] = ManifestEntry(
                file=file,
                label=(row.get("action") or row.get("content") or "").strip(),
                rig=(row.get("rig") or "").strip() or None,
                fps=fps,
                frames=None if frames is None else int(frames),
                notes=(row.get("notes") or "").strip(),
                licence=(row.get("licence") or "").strip() or None,
                group=(row.get("skeleton_group") or "").strip() or None,
            )
    return entries


def _optional_number(text: str | None, column: str, line: int, path: Path) -> float | None:
    text = (text or "").strip()
    if not text:
        return None
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"line {line}: {column} is not a number ({text!r})", path) from None
    if not np.isfinite(value):
        raise InputError(f"line {line}: {column} is not finite ({text!r})", path)
    return value


def find_manifest_entry(
    clip_path: str | Path, *, manifest: str | Path | None = None, levels: int = 4
) -> ManifestEntry | None:
    """The manifest row for a clip: true fps, label and rig.

    Args:
        clip_path: the clip file.
        manifest: a manifest.csv to look in; None searches ``manifest.csv`` in the clip's folder and up to
            ``levels - 1`` folders above it (cmu-bench files sit three folders below the mocap root),
            returning the first one that lists the clip.
    Returns:
        the entry, or None when no manifest lists the clip.
    """
    clip = Path(clip_path).resolve()
    if manifest is not None:
        candidates = [Path(manifest)]
    else:
        candidates = [parent / "manifest.csv" for parent in list(clip.parents)[:levels]]
    for candidate in candidates:
        if not candidate.is_file():
            continue
        root = candidate.resolve().parent
        try:
            key = clip.relative_to(root).as_posix()
        except ValueError:
            continue
        entry = read_manifest(candidate).get(key)
        if entry is not None:
            return entry
    return None


def resolve_manifest(clip_path: str | Path, manifest: str | Path | ManifestEntry | bool | None
                     ) -> ManifestEntry | None:
    """The manifest row a reader should use for ``clip_path``.

    Args:
        manifest: a :class:`ManifestEntry` (used as is), ``True`` (search with :func:`find_manifest_entry`;
            None when no manifest lists the clip), a ``manifest.csv`` path (the clip must be listed there),
            or None / False (no manifest).
    Raises:
        InputError: a manifest path that does not list the clip.
    """
    if isinstance(manifest, ManifestEntry):
        return manifest
    if manifest is True:
        return find_manifest_entry(clip_path)
    if manifest in (None, False):
        return None
    entry = find_manifest_entry(clip_path, manifest=manifest)
    if entry is None:
        raise InputError(f"not listed in {manifest}", clip_path)
    return entry


def default_trim(rig: str) -> int:
    """Frames to drop at the start of a clip of this rig (cgspeed's DAZ files, ``cmu/`` and ``acrnn/``,
    begin with an added T-pose and transition)."""
    return 5 if rig == "cmu-daz" else 0
