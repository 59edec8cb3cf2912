"""One reader for every motion-capture file of a mocap folder: BVH, DeepMimic motion files and exp-map
text files, each to a canonical ``h36m-17`` Motion with the manifest's true frame rate and label.

=================================  ===========================  ============================================
file                               kind                         reader
=================================  ===========================  ============================================
``*.bvh``, ``*.bvh.xz``            ``bvh``                      :func:`~motion2video.formats.bvh.load_bvh`
``*.txt`` / ``*.json`` holding a   ``deepmimic``                :func:`~motion2video.formats.deepmimic.load_deepmimic`
JSON object with ``"Frames"``      (:func:`is_deepmimic_file`)
other ``*.txt`` (comma-separated   ``expmap``                   :func:`~motion2video.formats.expmap.load_expmap`
numbers)
=================================  ===========================  ============================================

The kind comes from the manifest's ``rig`` column when it names one (``deepmimic-humanoid-txt``,
``...-expmap``), else from the file itself (:func:`mocap_kind`).
"""

from __future__ import annotations

from pathlib import Path

from motion2video.core.errors import InputError
from motion2video.core.skeletons import BODY_POINT_RIGS
from motion2video.formats.canonical import CanonicalClip, canonical_motion
from motion2video.formats.manifest import (
    ManifestEntry,
    default_trim,
    read_manifest,
    resolve_manifest,
)
from motion2video.core.motion import Motion

KINDS = ("bvh", "deepmimic", "expmap")
MOCAP_SUFFIXES = (".bvh", ".bvh.xz", ".txt", ".json")


def is_deepmimic_file(path: str | Path) -> bool:
    """Whether a file looks like a DeepMimic motion file: a JSON object naming ``"Frames"`` in its first
    4 KB (DeepMimic writes ``"Loop"`` and ``"Frames"`` first; OpenPose JSON never has that key)."""
    try:
        with Path(path).open("rb") as f:
            head = f.read(4096)
    except OSError as err:
        raise InputError(f"cannot read the file ({err.strerror})", path) from None
    return head.lstrip().startswith(b"{") and b'"Frames"' in head


def mocap_kind(path: str | Path, entry: ManifestEntry | None = None) -> str:
    """The reader for a mocap file: ``"bvh"``, ``"deepmimic"`` or ``"expmap"`` (see the module table).

    Raises:
        InputError: a missing file or an extension no reader takes.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    suffix = path.suffix.lower()
    if path.name.lower().endswith((".bvh", ".bvh.xz")):
        return "bvh"
    rig = (entry.rig or "") if entry is not None else ""
    if rig.startswith("deepmimic") and rig.endswith("-txt"):
        return "deepmimic"
    if rig.endswith("-expmap"):
        return "expmap"
    if suffix in (".txt", ".json") and is_deepmimic_file(path):
        return "deepmimic"
    if suffix == ".txt":
        return "expmap"
    raise InputError(f"not a motion-capture file (expected one of {', '.join(MOCAP_SUFFIXES)})", path)


def mocap_canonical(path: str | Path, *, entry: ManifestEntry | None = None,
                    character: str | Path | None = None, rig_map: dict[str, str] | None = None) -> CanonicalClip:
    """A whole mocap file in the project frame (metres, z up, every node), before trimming and floor
    placement; ``fps`` is the rate the file states (BVH header, DeepMimic frame duration, exp-map layout).

    Args:
        path: the file.
        entry: its manifest row (used only to tell the kind, :func:`mocap_kind`).
        character: DeepMimic files only: the character file (None: found beside the motion, else the
            standard humanoid3d; :func:`~motion2video.formats.deepmimic.resolve_character`).
        rig_map: BVH files only: body point -> joint name where the joint names do not tell
            (:func:`~motion2video.formats.bvh.read_rig_map`).
    """
    kind = mocap_kind(path, entry)
    if kind == "bvh":
        from motion2video.formats.bvh import canonical_positions, read_bvh

        return canonical_positions(read_bvh(path), rig_map=rig_map)
    if kind == "deepmimic":
        from motion2video.formats.deepmimic import deepmimic_canonical, read_deepmimic, resolve_character

        rig = resolve_character(path, character)
        return deepmimic_canonical(read_deepmimic(path, rig), rig)
    from motion2video.formats.expmap import expmap_canonical, find_layout, read_expmap_layout, read_expmap_values

    layout = read_expmap_layout(find_layout(path))
    return expmap_canonical(read_expmap_values(path, layout), layout)


def load_mocap(
    path: str | Path,
    *,
    fps: float | None = None,
    target_fps: float | None = None,
    manifest: str | Path | ManifestEntry | bool | None = True,
    label: str | None = None,
    canonical: CanonicalClip | None = None,
    character: str | Path | None = None,
    rig_map: dict[str, str] | None = None,
) -> Motion:
    """Load any mocap file as a canonical ``h36m-17`` Motion (metres, z up, floor at z = 0).

    Args:
        path: a ``.bvh``, DeepMimic or exp-map file.
        fps: the true frame rate (wins over the manifest and the file).
        target_fps: resample to this rate (linear interpolation of positions).
        manifest: where the true fps, the label and the rig's default trim (:func:`default_trim`, only
            with a manifest row) come from: ``True`` (default) looks for a ``manifest.csv`` listing the file
            in its folder or up to three folders above
            (:func:`~motion2video.formats.manifest.find_manifest_entry`); a path or a
            :class:`ManifestEntry`; None / False for none.
        label: action label (wins over the manifest's).
        canonical: :func:`mocap_canonical` of this file when the caller has it already.
        character: DeepMimic files only: their character file (see :func:`mocap_canonical`).
        rig_map: BVH files only: body point -> joint name (see :func:`mocap_canonical`).
    """
    path = Path(path)
    entry = resolve_manifest(path, manifest)
    canon = (mocap_canonical(path, entry=entry, character=character, rig_map=rig_map) if canonical is None
             else canonical)
    if entry is not None:
        fps = entry.fps if fps is None else fps
        label = entry.label if label is None else label
    return canonical_motion(canon.joints, fps=canon.fps if fps is None else float(fps), source=str(path),
                            start=default_trim(canon.rig) if entry is not None else 0,
                            target_fps=target_fps, label=label, place_floor=canon.rig not in BODY_POINT_RIGS)


def mocap_files(folder: str | Path) -> dict[str, ManifestEntry | None]:
    """The clips of a mocap folder, ``{path relative to folder: manifest row}``.

    With a ``manifest.csv`` in ``folder``: its rows in its order. Without one: every ``*.bvh`` below
    ``folder`` (``*.bvh`` and ``*.bvh.xz``, sorted by path, no manifest rows).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError("no such directory", folder)
    manifest_path = folder / "manifest.csv"
    if manifest_path.is_file():
        return dict(read_manifest(manifest_path))
    paths = sorted(p.relative_to(folder).as_posix() for pattern in ("*.bvh", "*.bvh.xz") for p in folder.rglob(pattern))
    if not paths:
        raise InputError("no .bvh / .bvh.xz files and no manifest.csv in the directory", folder)
    return {p: None for p in paths}


def load_mocap_folder(folder: str | Path, *, target_fps: float | None = 25) -> list[Motion]:
    """Load every clip of a mocap folder (:func:`mocap_files`), resampled to ``target_fps`` (None: native
    rates). Manifest rows bring their true fps, labels and the BVH rigs' default trims; without a manifest
    the BVH headers' rates apply and nothing is trimmed."""
    folder = Path(folder)
    return [load_mocap(folder / name, target_fps=target_fps, manifest=entry if entry is not None else None)
            for name, entry in mocap_files(folder).items()]
