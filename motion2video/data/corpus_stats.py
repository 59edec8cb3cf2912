"""Statistics of the motion corpus: minutes per source, per action and per split, as the dataset builder
uses it (every clip at the dataset rate, duplicates dropped, the subject-disjoint split).

:func:`corpus_stats` returns a JSON-able dict; :func:`stats_markdown` renders it as the Markdown tables
``motion2video corpus-stats`` prints (and docs/results.md shows); :func:`corpus_report` is that command's work.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from motion2video.core.atomic import write_json
from motion2video.core.errors import InputError
from motion2video.data.corpus import corpus_index, source_of
from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.data.windows import sliding_starts

SPLITS = ("train", "val", "test")


def _minutes(frames: float, fps: float) -> float:
    return frames / fps / 60.0


def corpus_stats(folder: str | Path | list, config: DatasetConfig = DatasetConfig(), *,
                 character: str | Path | None = None) -> dict:
    """Minutes per source, action and split of the corpus ``build_dataset(folder, config)`` trains on
    (``folder``: one mocap folder or a list of them, :func:`motion2video.data.corpus.corpus_rows`).

    Returns:
        ``{"config": {...}, "total": {...}, "per_split": {split: {...}}, "per_source": {source: {...}},
        "per_action": {action: {split: minutes, "total": minutes}}, "groups": {split: [group, ...]},
        "dropped": {copy: kept}}``. Minutes are clip frames at ``config.fps`` / fps / 60; windows count
        every ``config.length``-frame window ``config.stride`` frames apart.
    """
    folders = list(folder) if isinstance(folder, (list, tuple)) else [folder]
    entries, dropped = {}, {}
    for i, one in enumerate(folders):
        prefix = "" if i == 0 else f"{Path(one).name}/"
        index = corpus_index(one, drop_duplicates=config.drop_duplicates)
        entries.update({prefix + k: v for k, v in index.entries.items()})
        dropped.update({prefix + k: prefix + v for k, v in index.dropped.items()})
    dataset = build_dataset(folders[0] if len(folders) == 1 else folders, config, character=character)
    fps = config.fps
    split_of = {name: s for s in SPLITS for name in dataset.split.names(s)}
    per_split = {s: {"clips": 0, "minutes": 0.0, "windows": 0, "groups": 0} for s in SPLITS}
    per_source: dict[str, dict] = {}
    per_action: dict[str, dict] = {}
    groups: dict[str, set] = {s: set() for s in SPLITS}
    for clip in dataset.clips:
        s = split_of.get(clip.name)
        minutes = _minutes(clip.num_frames, fps)
        source = per_source.setdefault(source_of(clip.name), {"files": 0, "clips": 0, "minutes": 0.0,
                                                               "dropped_copies": 0, "dropped_minutes": 0.0})
        source["clips"] += 1
        source["minutes"] += minutes
        action = per_action.setdefault(clip.label or "unlabelled", {**{k: 0.0 for k in SPLITS}, "total": 0.0})
        action["total"] += minutes
        if s is None:
            continue
        action[s] += minutes
        per_split[s]["clips"] += 1
        per_split[s]["minutes"] += minutes
        per_split[s]["windows"] += len(sliding_starts(clip.num_frames, length=config.length, stride=config.stride))
        groups[s].add(clip.group)
    for name, entry in entries.items():
        source = per_source.setdefault(source_of(name), {"files": 0, "clips": 0, "minutes": 0.0,
                                                          "dropped_copies": 0, "dropped_minutes": 0.0})
        source["files"] += 1
        if name in dropped:
            source["dropped_copies"] += 1
            if entry is not None and entry.frames and entry.fps:
                source["dropped_minutes"] += _minutes(entry.frames, entry.fps)
    for s in SPLITS:
        per_split[s]["groups"] = len(groups[s])
    total_minutes = sum(v["minutes"] for v in per_split.values())
    return {
        "data": " + ".join(str(f) for f in folders),
        "config": {"fps": fps, "observed": config.observed, "future": config.future, "stride": config.stride,
                   "held_out": config.held_out, "drop_duplicates": config.drop_duplicates},
        "total": {"files": len(entries), "clips": len(dataset.clips), "minutes": total_minutes,
                  "dropped_copies": len(dropped)},
        "per_split": per_split,
        "per_source": dict(sorted(per_source.items(), key=lambda kv: -kv[1]["minutes"])),
        "per_action": dict(sorted(per_action.items(), key=lambda kv: -kv[1]["total"])),
        "groups": {s: sorted(groups[s]) for s in SPLITS},
        "dropped": dropped,
    }


def stats_markdown(stats: dict) -> str:
    """The statistics as three Markdown tables (sources, splits, actions) and the held-out groups."""
    total = stats["total"]["minutes"]
    lines = [f"Corpus `{stats['data']}`: {stats['total']['files']} files, {stats['total']['clips']} clips used "
             f"({stats['total']['dropped_copies']} duplicate copies dropped), {total:.1f} minutes at "
             f"{stats['config']['fps']:g} fps; windows of {stats['config']['observed']} observed + "
             f"{stats['config']['future']} future frames, stride {stats['config']['stride']}.", "",
             "| source | files | clips used | minutes used | duplicate copies dropped | their minutes |",
             "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for name, v in stats["per_source"].items():
        lines.append(f"| `{name}` | {v['files']} | {v['clips']} | {v['minutes']:.1f} | {v['dropped_copies']} | "
                     f"{v['dropped_minutes']:.1f} |")
    lines += ["", "| split | clips | groups | minutes | share | windows |", "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for s in SPLITS:
        v = stats["per_split"][s]
        share = v["minutes"] / total if total else 0.0
        lines.append(f"| {s} | {v['clips']} | {v['groups']} | {v['minutes']:.1f} | {share:.0%} | {v['windows']} |")
    lines += ["", "| action | train | val | test | total minutes |", "| --- | ---: | ---: | ---: | ---: |"]
    for name, v in stats["per_action"].items():
        lines.append(f"| {name} | {v['train']:.2f} | {v['val']:.2f} | {v['test']:.2f} | {v['total']:.2f} |")
    lines += ["", "Held-out groups:"]
    for s in ("test", "val"):
        lines.append(f"- {s}: " + ", ".join(f"`{g}`" for g in stats["groups"][s]))
    return "\n".join(lines) + "\n"



@dataclass(frozen=True)
class CorpusStatsSettings:
    """What ``motion2video corpus-stats`` reports on.

    Attributes:
        data: the mocap folder (with manifest.csv), or several joined into one corpus (every folder's clips after
            the first named with its folder's name in front).
        json: also write the statistics as JSON here (None: no file).
        held_out: the split rule, ``corpus`` (the pinned held-out subjects and sources), ``hash``, or ``subjects``
            (also one Bandai-Namco performer per set).
        keep_duplicates: keep every copy of a trial found in several folders.
        character: DeepMimic motion files' character file.
    """

    data: str | Path | tuple[str | Path, ...]
    json: str | Path | None = None
    held_out: str = "corpus"
    keep_duplicates: bool = False
    character: str | Path | None = None


@dataclass(frozen=True)
class CorpusReport:
    """The statistics (:func:`corpus_stats`), their Markdown tables and the JSON file written (or None)."""

    stats: dict
    markdown: str
    json: Path | None


def corpus_report(settings: CorpusStatsSettings) -> CorpusReport:
    """The statistics of ``settings.data`` under the default data config with the settings' split rule and
    duplicate handling; written as JSON when ``settings.json`` is given. InputError for a missing folder or a
    JSON path whose folder does not exist, before any clip is read."""
    folders = [settings.data] if isinstance(settings.data, (str, Path)) else list(settings.data)
    for folder in folders:
        if not Path(folder).is_dir():
            raise InputError("not a folder (corpus-stats takes mocap folders)", folder)
    data = Path(folders[0]) if len(folders) == 1 else folders
    if settings.json is not None and not Path(settings.json).parent.exists():
        raise InputError("the folder for --json does not exist", settings.json)
    config = DatasetConfig(held_out=settings.held_out, drop_duplicates=not settings.keep_duplicates)
    stats = corpus_stats(data, config, character=settings.character)
    out = write_json(settings.json, stats) if settings.json is not None else None
    return CorpusReport(stats=stats, markdown=stats_markdown(stats), json=out)
