"""Licences follow the data: what a model's training files allow, recorded with the model.

Every manifest row names its file's licence (``licence`` column). A model trained on a corpus records the
licences of its training clips (:func:`licence_record`, in the checkpoint's data summary); the shipped
checkpoints, trained before that record existed, have theirs in ``motion2video/weights/licences.json``
(written by ``scripts/shipped_licences.py`` from each checkpoint's recorded clips and the manifests). A model
whose files include a non-commercial licence (:func:`is_non_commercial`, e.g. Bandai-Namco's CC BY-NC 4.0)
says so where a user picks it (``--help``'s model list, its card) and when it is loaded (:func:`licence_note`).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

SHIPPED_LICENCES = Path(__file__).resolve().parents[1] / "weights" / "licences.json"
# "CC BY-NC 4.0", "CC BY-NC-SA", "non-commercial", "noncommercial", "NC"
_NON_COMMERCIAL = re.compile(r"(?:\bBY-NC\b|\bNC\b|non-?commercial)", re.IGNORECASE)
UNKNOWN = "unknown (no manifest licence)"


def is_non_commercial(licence: str | None) -> bool:
    """Whether a licence text forbids commercial use (``CC BY-NC 4.0``, "non-commercial", ...)."""
    return bool(licence) and _NON_COMMERCIAL.search(licence) is not None


def licence_record(licences: list[str | None]) -> dict:
    """The record a checkpoint keeps of its training files' licences.

    Args:
        licences: one licence text per training file (None: the file's manifest names none).
    Returns:
        ``{"licences": {licence: files}, "non_commercial": bool}``, licences sorted by name.
    """
    counts: dict[str, int] = {}
    for text in licences:
        key = text or UNKNOWN
        counts[key] = counts.get(key, 0) + 1
    return {"licences": dict(sorted(counts.items())),
            "non_commercial": any(is_non_commercial(k) for k in counts)}


def shipped_licences(path: str | Path = SHIPPED_LICENCES) -> dict[str, dict]:
    """``{shipped model name: licence record}`` of ``motion2video/weights/licences.json`` (empty when absent)."""
    path = Path(path)
    if not path.is_file():
        return {}
    return json.loads(path.read_text(encoding="utf-8"))


def model_licences(name: str, recorded: dict | None) -> dict | None:
    """A model's licence record: the one its checkpoint holds (``recorded``), else the shipped record of
    ``name``, else None."""
    if recorded:
        return recorded
    return shipped_licences().get(name)


def licence_label(record: dict | None) -> str:
    """A short label for a model list: ``"NON-COMMERCIAL data (CC BY-NC 4.0)"`` or ``"no non-commercial
    licence among its 191 files"``."""
    if not record:
        return "data licence not recorded"
    names = list(record["licences"])
    if record["non_commercial"]:
        return "NON-COMMERCIAL data (" + "; ".join(n for n in names if is_non_commercial(n)) + ")"
    return f"no non-commercial licence among its {sum(record['licences'].values())} files"


def licence_note(name: str, record: dict | None) -> str | None:
    """The one-line note printed when a model trained on non-commercial files is loaded (None otherwise)."""
    if not record or not record["non_commercial"]:
        return None
    nc = "; ".join(n for n in record["licences"] if is_non_commercial(n))
    return (f"{name} was trained on non-commercial data ({nc}): its outputs are for non-commercial use only")


def licence_table(records: dict[str, dict] | None = None) -> str:
    """The lines ``--help`` adds to its list of shipped models: each model's data licence label
    (:func:`licence_label`), from ``motion2video/weights/licences.json`` by default."""
    records = shipped_licences() if records is None else records
    if not records:
        return ""
    width = max(len(n) for n in records)
    lines = ["data licences of the shipped models (motion2video/weights/licences.json, each file's manifest licence):"]
    lines += [f"  {name:<{width}} {licence_label(record)}" for name, record in records.items()]
    return "\n".join(lines) + "\n"


CARD_BEGIN = "<!-- data licence: begin (scripts/shipped_licences.py) -->"
CARD_END = "<!-- data licence: end -->"


def card_section(record: dict) -> str:
    """A model card's "Data licence" section for its licence record."""
    lines = ["## Data licence", ""]
    if record["non_commercial"]:
        lines.append("**Non-commercial.** Trained on files under a non-commercial licence "
                     f"({'; '.join(n for n in record['licences'] if is_non_commercial(n))}): the model and what it "
                     "generates are for non-commercial use only, and loading it prints a note saying so.")
    else:
        lines.append("No file it was trained on carries a non-commercial licence.")
    lines += ["", f"Trained on {record.get('data', 'its training files')}; their manifest licences (files):", ""]
    lines += [f"- {name}: {count}" for name, count in record["licences"].items()]
    return "\n".join(lines)
