"""The licence records of the shipped checkpoints (``motion2video/weights/licences.json``), derived from the
clips each checkpoint records (a motion model's train and validation split, a frame generator's posing or
expression clips) and the licence column of the manifests those clips are listed in
(:mod:`motion2video.data.licences`). ``scripts/shipped_licences.py`` writes the file; a test checks it
against the data."""

from __future__ import annotations

import json
from pathlib import Path

from safetensors import safe_open

from motion2video.data.licences import licence_record
from motion2video.formats.manifest import read_manifest
from motion2video.models.checkpoint import FORMAT, WEIGHTS_DIR, read_meta, shipped_names


def checkpoint_clips(path: str | Path) -> tuple[str, list[str]]:
    """(``"body"`` or ``"face"``, the clip names a checkpoint records as its training data): a motion
    model's train + validation split, a frame generator's ``train.data.clips``."""
    with safe_open(str(path), framework="pt") as f:
        metadata = f.metadata() or {}
    if metadata.get("format") == FORMAT:
        meta = read_meta(path)
        domain = "face" if meta.data_config.layout == "face" else "body"
        return domain, [] if meta.split is None else list(meta.split.train) + list(meta.split.val)
    train = json.loads(metadata.get("train") or "{}")
    data = train.get("data", {})
    return data.get("domain", "body"), list(data.get("clips", []))


def shipped_licence_records(data_root: str | Path, *, weights_dir: Path = WEIGHTS_DIR) -> dict[str, dict]:
    """``{shipped name: licence record}`` (:func:`~motion2video.data.licences.licence_record`) with the
    record's ``"data"``: the folder the clips come from and how many there are.

    Args:
        data_root: the folder holding ``mocap/`` and ``face/`` with their ``manifest.csv`` (``../shared/data``).
    """
    root = Path(data_root)
    folders = {"body": "mocap", "face": "face"}
    manifests = {d: read_manifest(root / f / "manifest.csv") for d, f in folders.items()}
    out = {}
    for name in shipped_names():
        domain, clips = checkpoint_clips(weights_dir / f"{name}.safetensors")
        entries = manifests[domain]
        record = licence_record([entries[c].licence if c in entries else None for c in clips])
        record["data"] = f"{len(clips)} clips of ../shared/data/{folders[domain]}"
        out[name] = record
    return out
