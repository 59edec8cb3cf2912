"""Atomic file writing: write to a temporary file beside the destination, then rename it into place.

A failure (or an interrupt) part-way never leaves a partial file under the destination's name, and an
existing file is only replaced by a complete one. Every writer in the package goes through here.
"""

from __future__ import annotations

import json
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import numpy as np


def check_output_path(path: str | Path, extensions: tuple[str, ...]) -> Path:
    """Validate an output path before any work is done: one of ``extensions`` (lower-case, with the dot), not
    itself a folder, in a folder that exists and is writable or can be created (missing folders are created
    by the writers when the output is written, so a failed command leaves none behind). Raises InputError
    naming the path."""
    from motion2video.core.errors import InputError

    out = Path(path)
    if out.suffix.lower() not in extensions:
        raise InputError(f"unsupported output extension {out.suffix or '(none)'!r}: the output must be an "
                         f"{' or '.join(extensions)} file", out)
    folder = out.parent
    while not folder.exists() and folder != folder.parent:  # the nearest existing ancestor
        folder = folder.parent
    if not folder.is_dir():
        raise InputError(f"{folder} is a file, so the output folder cannot be created", out)
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"the output folder {folder} is not writable", out)
    if out.is_dir():
        raise InputError("the output path is a directory", out)
    return out


@contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path in ``path``'s folder (same suffix, so format-sniffing writers behave); when the
    block succeeds it is renamed onto ``path``, otherwise it is removed. Creates missing parent folders."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def save_npz(path: str | Path, arrays: dict[str, np.ndarray], *, compressed: bool = False) -> Path:
    """``np.savez`` (or ``savez_compressed``) ``arrays`` to ``path`` atomically; returns ``path``."""
    path = Path(path)
    with atomic_output(path) as tmp, open(tmp, "wb") as f:
        (np.savez_compressed if compressed else np.savez)(f, **arrays)
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically; returns ``path``."""
    path = Path(path)
    with atomic_output(path) as tmp:
        tmp.write_text(text)
    return path


def write_json(path: str | Path, record: dict, *, indent: int = 2) -> Path:
    """Write ``record`` as JSON (trailing newline) to ``path`` atomically; returns ``path``."""
    return write_text(path, json.dumps(record, indent=indent) + "\n")


def check_section(path: str | Path, begin: str, end: str) -> Path:
    """Check that an existing document holds the marker lines ``begin`` and then ``end`` (a missing document is
    fine: :func:`write_section` starts it); a generator calls this before its run, so that a long run does not
    end without a place to write. Returns ``path``.

    Raises:
        InputError: naming the document and the missing marker (or the pair in the wrong order).
    """
    from motion2video.core.errors import InputError

    path = Path(path)
    if not path.is_file():
        return path
    text = path.read_text()
    for marker in (begin, end):
        if marker not in text:
            raise InputError(f"no marker line {marker}: put {begin} and {end} around the section that is "
                             "regenerated", path)
    if end not in text.split(begin, 1)[1]:
        raise InputError(f"{end} comes before {begin}", path)
    return path


def write_section(path: str | Path, begin: str, end: str, body: str) -> Path:
    """Replace the text between the marker lines ``begin`` and ``end`` of a document with ``body``, keeping
    everything else; written atomically. A missing document starts as ``# Results`` followed by the marked
    block; an existing one must hold both markers (:func:`check_section`). Used by the sub-commands of
    ``scripts/make_results.py`` and by ``scripts/shipped_licences.py``.

    Raises:
        InputError: the document exists but lacks ``begin`` or ``end``. Nothing is written.
        ValueError: the marked block holds a heading that ``body`` does not: hand-written text placed between
            the markers would be lost (move it outside them). Nothing is written.
    """
    path = Path(path)
    block = f"{begin}\n{body.strip()}\n{end}"
    if not path.is_file():
        return write_text(path, f"# Results\n\n{block}\n")
    check_section(path, begin, end)
    head, rest = path.read_text().split(begin, 1)
    old, tail = rest.split(end, 1)
    new_headings = {line.strip() for line in body.splitlines() if line.startswith("#")}
    lost = [line.strip() for line in old.splitlines() if line.startswith("#") and line.strip() not in new_headings]
    if lost:
        raise ValueError(f"{path}: the block between {begin} and {end} holds {lost[0]!r}, which the new section "
                         "does not: move hand-written text outside the markers")
    return write_text(path, head + block + tail)
