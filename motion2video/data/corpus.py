"""The motion corpus: which split group (performer) and which recorded trial each clip of the mocap folder
is, which copies of one trial to drop, and the held-out groups of the subject-disjoint split.

Everything here is a pure function of a clip's name (its path relative to the mocap folder) and its
manifest label, so it works on the shared folder, on a copy, and on small test folders alike.

Groups (the unit a split never cuts), per folder of ``../shared/data/mocap``:

- ``cmu/NN_MM.bvh``, ``deepmimic-cmu/NN_MM.txt``: CMU subject NN -> ``cmu-NN``.
- ``cmu-bench/...``: the subject of the CMU trial the manifest's label names (``"...; CMU 13_11)"`` ->
  ``cmu-13``); a file whose trial is not identified -> ``cmu-bench:<benchmark action>`` (its subject is
  unknown, so all unidentified files of one benchmark action stay together).
- ``acrnn/``: by the label (the source does not name trials): salsa = CMU subjects 60 and 61, the two
  dancers of every take, one group ``cmu-60-61``; indian dance = subject 94 (``cmu-94``); martial arts =
  subject 135 (``cmu-135``).
- ``deepmimic/`` (BVH twins and ``txt/`` originals): one source, ``deepmimic`` (its capture subjects are
  not stated).
- ``mass/``: one source, ``mass``.
- Bandai-Namco's sets (files named ``dataset-1_*`` / ``dataset-2_*``, sources ``bandai-1`` / ``bandai-2``): the
  manifest's ``skeleton_group`` (one set of bone offsets, most likely one actor): ``bandai-2C``.
- any other name: the CMU rule when the file stem is ``NN_MM``, else the clip itself.

Several folders form one corpus (:func:`corpus_rows`, ``--data A --data B``): the clips of every folder after
the first are named with that folder's name in front (``bandai/bvh/dataset-2_walk_normal_001.bvh.xz``), so the
first folder's names, and the splits checkpoints recorded with them, stay as they are.

Trials (what a duplicate is): ``cmu NN_MM`` for the CMU files named or labelled with a trial, ``deepmimic
<motion>`` for a DeepMimic BVH and its ``.txt`` original; other clips are their own trial. When one trial
sits in several folders (02_01 is in ``cmu/``, ``deepmimic-cmu/`` and ``cmu-bench/``), the corpus keeps
one copy (:func:`drop_duplicates`), preferring ``cmu/`` (120 fps BVH) over ``cmu-bench/`` over
``deepmimic-cmu/``, and a DeepMimic BVH over its ``.txt`` twin. Copies share their group anyway, so the
split stays subject-disjoint either way.

Held-out groups (:data:`TEST_GROUPS`, :data:`VAL_GROUPS`) are fixed, chosen so that no subject the
shipped 5-minute checkpoints trained on is held out (their test subjects were 16 and 131, validation 2, 3
and 8), and so that test holds whole subjects of several actions plus one whole new source (indian dance,
subject 94) the old models never saw. Linking (:func:`link_groups`) merges cmu-02 with CMU 5, 6 and 7 through
the unidentified ``cmu-bench`` walking files, and the 72-clip split trained on clips of 5, 6 and 7: comparisons
with the 5-minute checkpoints leave those clips out (``scripts/make_results.py per-action`` does).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from motion2video.formats.manifest import ManifestEntry

# Groups pinned to test and validation (see the module docstring). Other groups go to training, unless the
# folder lacks these groups altogether (then make_split's hash rule fills the fractions).
TEST_GROUPS = ("cmu-02", "cmu-131", "cmu-94", "cmu-140")
VAL_GROUPS = ("cmu-03", "cmu-85", "cmu-bench:basketball", "mass")
# The split that tests what training covers (``held_out="subjects"``, ``evaluate --split subjects``): the
# corpus's test subjects plus one whole Bandai-Namco performer per set (skeleton groups 1B and 2C: every action
# of each set is performed by its other large group too, so every held-out Bandai action is in training).
SUBJECT_TEST_GROUPS = TEST_GROUPS + ("bandai-1B", "bandai-2C")
BANDAI_SOURCES = ("bandai-1", "bandai-2")
_BANDAI_FILE = re.compile(r"^dataset-([12])_")

_STEM = re.compile(r"^(\d+)_(\d+)$")
_LABEL_TRIAL = re.compile(r"\bCMU (\d+)_(\d+)\b")
_BENCH = re.compile(r"^cmu-bench/(?:train|test)/([^/]+)/")
ACRNN_SUBJECTS = {"salsa": "cmu-60-61", "indian": "cmu-94", "martial": "cmu-135"}
# Which copy of a trial the corpus keeps: lower is preferred.
SOURCE_PREFERENCE = ("cmu", "deepmimic", "cmu-bench", "deepmimic-cmu")


def source_of(name: str) -> str:
    """The folder a clip comes from: ``cmu``, ``acrnn``, ``cmu-bench``, ``deepmimic-cmu``, ``deepmimic``,
    ``deepmimic/txt``, ``mass`` (the first path part; ``deepmimic/txt`` kept apart), ``bandai-1`` / ``bandai-2``
    (Bandai-Namco's files ``dataset-1_*`` / ``dataset-2_*``, in any folder), or ``other``."""
    bandai = _BANDAI_FILE.match(Path(name).name)
    if bandai:
        return f"bandai-{bandai.group(1)}"
    parts = Path(name).parts
    if len(parts) < 2:
        return "other"
    if parts[0] == "deepmimic" and parts[1] == "txt":
        return "deepmimic/txt"
    return parts[0]


def cmu_trial(name: str, label: str | None = None) -> tuple[int, int] | None:
    """The CMU (subject, take) of a clip: from a ``NN_MM`` file stem in ``cmu/`` or ``deepmimic-cmu/`` (or
    a folder of unknown origin), or from ``CMU NN_MM`` in a ``cmu-bench`` label; None when unknown."""
    source = source_of(name)
    if source == "cmu-bench":
        match = _LABEL_TRIAL.search(label or "")
        return (int(match.group(1)), int(match.group(2))) if match else None
    if source in ("acrnn", "deepmimic", "deepmimic/txt", "mass") + BANDAI_SOURCES:
        return None
    match = _STEM.match(Path(name).stem)
    return (int(match.group(1)), int(match.group(2))) if match else None


def clip_group(name: str, label: str | None = None, manifest_group: str | None = None) -> str:
    """The split group of a clip (module docstring): ``cmu-08``, ``cmu-60-61``, ``cmu-bench:soccer``,
    ``deepmimic``, ``mass``, ``bandai-2C``, or the name itself. ``manifest_group``: the manifest's
    ``skeleton_group`` column (the performer of a source that names none per clip)."""
    source = source_of(name)
    if manifest_group:
        return f"bandai-{manifest_group}" if source in BANDAI_SOURCES else f"{source}:{manifest_group}"
    trial = cmu_trial(name, label)
    if trial is not None:
        return f"cmu-{trial[0]:02d}"
    if source == "cmu-bench":
        match = _BENCH.match(Path(name).as_posix())
        return f"cmu-bench:{match.group(1) if match else Path(name).stem}"
    if source == "acrnn":
        kind = Path(name).stem.split("_")[0]
        return ACRNN_SUBJECTS.get(kind, f"acrnn:{kind}")
    if source in ("deepmimic", "deepmimic/txt"):
        return "deepmimic"
    if source == "mass":
        return "mass"
    return name


def trial_key(name: str, label: str | None = None) -> str:
    """What recording a clip is: ``cmu 02_01``, ``deepmimic humanoid3d_walk``, or the name itself."""
    trial = cmu_trial(name, label)
    if trial is not None:
        return f"cmu {trial[0]:02d}_{trial[1]:02d}"
    if source_of(name) in ("deepmimic", "deepmimic/txt"):
        return f"deepmimic {Path(name).stem}"
    return name


def _preference(name: str) -> tuple[int, str]:
    source = source_of(name)
    rank = SOURCE_PREFERENCE.index(source) if source in SOURCE_PREFERENCE else len(SOURCE_PREFERENCE)
    return rank, name


def duplicates(names_labels: list[tuple[str, str | None]]) -> dict[str, str]:
    """The copies a corpus drops: ``{dropped name: kept name}``, one kept copy per trial (module docstring).

    Args:
        names_labels: (name, manifest label) per clip.
    """
    by_trial: dict[str, list[str]] = {}
    for name, label in names_labels:
        by_trial.setdefault(trial_key(name, label), []).append(name)
    dropped = {}
    for copies in by_trial.values():
        if len(copies) > 1:
            keep = min(copies, key=_preference)
            dropped.update({c: keep for c in copies if c != keep})
    return dropped


def link_groups(names_groups: list[tuple[str, str]]) -> dict[str, str]:
    """Merge groups that may share a performer: ``{group: merged group}``.

    A ``cmu-bench`` file whose trial is not identified has an unknown subject; it may be any subject whose
    trials the same benchmark action contains (the identified ``walking_extra`` files are subjects 8 and
    16, the identified ``running`` file subject 16, ...). So ``cmu-bench:<action>`` is merged with the
    group of every identified ``cmu-bench`` clip of that action, transitively. A merged group is named by
    its members joined with ``+`` in sorted order (``cmu-08+cmu-16+cmu-bench:walking_extra``).

    Args:
        names_groups: (clip name, :func:`clip_group`) per clip.
    """
    parent: dict[str, str] = {g: g for _, g in names_groups}

    def find(g: str) -> str:
        while parent[g] != g:
            parent[g] = parent[parent[g]]
            g = parent[g]
        return g

    for name, group in names_groups:
        match = _BENCH.match(Path(name).as_posix())
        unknown = f"cmu-bench:{match.group(1)}" if match else None
        if unknown is not None and unknown in parent and group != unknown:
            parent[find(group)] = find(unknown)
    members: dict[str, list[str]] = {}
    for g in parent:
        members.setdefault(find(g), []).append(g)
    return {g: "+".join(sorted(members[find(g)])) for g in parent}


def pinned_split(group: str, *, test_groups: tuple[str, ...] = TEST_GROUPS,
                 val_groups: tuple[str, ...] = VAL_GROUPS) -> str | None:
    """``"test"`` / ``"val"`` when a member of ``group`` (a merged group, :func:`link_groups`) is pinned
    there, else None. Test wins when a merged group holds both."""
    members = set(group.split("+"))
    if members & set(test_groups):
        return "test"
    if members & set(val_groups):
        return "val"
    return None


# Coarse action classes of the manifest's free-text labels: the first keyword found wins (order matters:
# "jump and spin kick" is a jump, "stretch and cartwheel" a cartwheel).
ACTION_KEYWORDS = (
    ("salsa", "salsa"), ("indian", "indian dance"), ("martial", "martial arts"),
    ("basketball_signal", "basketball signal"), ("directing_traffic", "directing traffic"),
    ("wash", "wash window"), ("cartwheel", "cartwheel"), ("getup", "get up"), ("get up", "get up"),
    ("backflip", "flip"), ("flip", "flip"), ("handstand", "handstand"), ("basketball", "basketball"),
    ("soccer", "soccer"), ("jump", "jump"), ("hop", "jump"), ("leap", "jump"), ("run", "run"),
    ("walk", "walk"), ("dance", "dance"), ("pirouette", "dance"), ("kick", "kick"), ("punch", "punch"),
    ("fall", "fall"), ("slip", "fall"), ("crawl", "crawl"), ("roll", "roll"), ("spin", "spin"),
    # Bandai-Namco's actions: walks of every direction and turn are walks, a dash is a run; waves ("bye",
    # "byebye", "wave-left-hand") are one class, raised hands another; bow, guide, call, respond, slash keep
    # their names.
    ("dash", "run"), ("wave", "wave"), ("bye", "wave"), ("raise-up", "raise hands"),
)


def action_class(label: str | None) -> str | None:
    """A coarse action class of a manifest label (:data:`ACTION_KEYWORDS`), else its first word:
    ``"walk (start-walk-stop, MJ style)"`` -> ``"walk"``, ``"salsa dance (partner a of take 01)"`` ->
    ``"salsa"``, ``"HandStandKicks"`` -> ``"handstand"``, ``"dance_a"`` -> ``"dance"``."""
    if not label:
        return None
    head = re.split(r"[(,]", label)[0].strip().lower()
    if not head:
        return None
    for key, action in ACTION_KEYWORDS:
        if key in head:
            return action
    return head.split()[0].split("_")[0]


def corpus_rows(folders: list[str | Path], *, drop_duplicates: bool = True) -> list[tuple[Path, "CorpusRow"]]:
    """The clips of one or more mocap folders as one corpus: (file path, row) per clip, the row's name with
    the folder's name in front for every folder after the first (module docstring)."""
    out = []
    for i, folder in enumerate(folders):
        folder = Path(folder)
        prefix = "" if i == 0 else f"{folder.name}/"
        for row in corpus_index(folder, drop_duplicates=drop_duplicates).rows:
            out.append((folder / row.name, CorpusRow(prefix + row.name, row.entry, row.group)))
    return out


@dataclass(frozen=True)
class CorpusRow:
    """One clip the corpus uses.

    Attributes:
        name: path relative to the mocap folder.
        entry: its manifest row (None in a folder without a manifest).
        group: its split group after :func:`link_groups`.
    """

    name: str
    entry: ManifestEntry | None
    group: str


@dataclass(frozen=True)
class CorpusIndex:
    """The clips of a mocap folder as the corpus sees them (nothing loaded yet).

    Attributes:
        rows: the clips used, in manifest order.
        dropped: ``{dropped copy: kept copy}`` (:func:`duplicates`), empty with ``drop_duplicates=False``.
        entries: every manifest row (also the dropped ones), ``{name: entry or None}``.
    """

    rows: tuple[CorpusRow, ...]
    dropped: dict
    entries: dict


def corpus_index(folder: str | Path, *, drop_duplicates: bool = True) -> CorpusIndex:
    """Groups (linked over every file, dropped copies included) and duplicates of a mocap folder."""
    from motion2video.formats.mocap import mocap_files

    entries = mocap_files(folder)
    labelled = [(name, entry.label if entry is not None else None) for name, entry in entries.items()]
    groups = {name: clip_group(name, label, entries[name].group if entries[name] is not None else None)
              for name, label in labelled}
    linked = link_groups(list(groups.items()))
    dropped = duplicates(labelled) if drop_duplicates else {}
    rows = tuple(CorpusRow(name, entry, linked[groups[name]]) for name, entry in entries.items()
                 if name not in dropped)
    return CorpusIndex(rows=rows, dropped=dropped, entries=entries)
