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
    record's ``"data"``: the folders the clips come from and how many there are.

    A clip of a corpus joined from several folders is named with its folder in front (``bandai/bvh/...``,
    :func:`motion2video.data.dataset.load_clips`); its licence is looked up in that folder's manifest.

    Args:
        data_root: the folder holding ``mocap/`` and ``face/`` (and any folder joined to ``mocap/``, such as
            ``bandai/``) with their ``manifest.csv`` (``../shared/data``).
    """
    root = Path(data_root)
    folders = {"body": "mocap", "face": "face"}
    manifests: dict[str, dict] = {}

    def manifest(folder: str) -> dict:
        if folder not in manifests:
            path = root / folder / "manifest.csv"
            manifests[folder] = read_manifest(path) if path.is_file() else {}
        return manifests[folder]

    out = {}
    for name in shipped_names():
        domain, clips = checkpoint_clips(weights_dir / f"{name}.safetensors")
        used = [folders[domain]]
        licences = []
        for clip in clips:
            folder, rest = folders[domain], clip
            head, _, tail = clip.partition("/")
            if clip not in manifest(folder) and tail and head != folder and manifest(head):
                folder, rest = head, tail
                used += [] if folder in used else [folder]
            entry = manifest(folder).get(rest)
            licences.append(entry.licence if entry is not None else None)
        record = licence_record(licences)
        record["data"] = f"{len(clips)} clips of " + " + ".join(f"../shared/data/{f}" for f in used)
        out[name] = record
    return out
