"""Bandai-Namco's clips join the corpus; licences follow the data; the subject split.

A small corpus of real files (five CMU / ACRNN clips and nine Bandai-Namco clips, each folder with the rows of
its real manifest) read as two --data folders: Bandai's actions land in the corpus's classes, its skeleton
groups are split groups, a checkpoint trained on it records CC BY-NC 4.0 and says so when loaded, and
`evaluate --split subjects` reports per action, an unseen-action row and a cross-dataset row.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.data.corpus import action_class, clip_group, source_of
from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.data.licences import (card_section, is_non_commercial, licence_record, licence_table,
                                        shipped_licences)
from motion2video.evaluation.per_action import family_key, subject_split_report
from motion2video.models import checkpoint as C
from motion2video.models.training import TrainConfig, train_model

MOCAP_CLIPS = ("cmu/02_01.bvh", "cmu/07_01.bvh", "cmu/08_01.bvh", "cmu/16_01.bvh", "acrnn/indian_04.bvh")
# Performers 2A, 2B, 2C (bandai-2) and 1A, 1B (bandai-1); 2C and 1B are the subject split's test performers.
BANDAI_CLIPS = ("dataset-2_run_exhausted_009", "dataset-2_raise-up-both-hands_elderly_020", "dataset-2_walk_normal_001",
                "dataset-2_run_feminine_001", "dataset-2_raise-up-both-hands_feminine_020",
                "dataset-1_walk_normal_001", "dataset-1_bow_angry_001", "dataset-1_walk_active_001",
                "dataset-1_bow_active_001")


def subset(source: Path, out: Path, keep) -> Path:
    """``out`` holding symbolic links to the files of ``source``'s manifest rows that ``keep(row)`` selects,
    and a manifest.csv of those rows."""
    with (source / "manifest.csv").open(newline="") as f:
        reader = csv.DictReader(f)
        fields, rows = reader.fieldnames, [r for r in reader if keep(r)]
    for row in rows:
        target = out / row["file"]
        target.parent.mkdir(parents=True, exist_ok=True)
        target.symlink_to(source / row["file"])
    with (out / "manifest.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    return out


@pytest.fixture(scope="module")
def corpus(tmp_path_factory, shared_dir) -> list[Path]:
    root = tmp_path_factory.mktemp("corpus")
    mocap = subset(shared_dir / "data" / "mocap", root / "mocap", lambda r: r["file"] in MOCAP_CLIPS)
    bandai = subset(shared_dir / "data" / "bandai", root / "bandai",
                    lambda r: Path(r["file"]).name.split(".")[0] in BANDAI_CLIPS)
    assert len(list((bandai / "bvh").iterdir())) == len(BANDAI_CLIPS)
    return [mocap, bandai]


@pytest.fixture(scope="module")
def dataset(corpus):
    return build_dataset(corpus, DatasetConfig(held_out="subjects", stride=16))


def _quick() -> TrainConfig:
    return TrainConfig(steps=2, batch_size=4, lr=1e-3, warmup_steps=0, final_lr_fraction=1.0, checkpoint_every=2,
                       val_every=2, val_windows=4, seed=0)


@pytest.fixture(scope="module")
def checkpoints(tmp_path_factory, dataset, corpus):
    """A tiny model trained on the joined corpus (subject split), one on the CMU folder alone."""
    root = tmp_path_factory.mktemp("ckpt")
    joined = train_model(model_name="pred-lstm", model_config={"hidden_dim": 8}, dataset=dataset, config=_quick(),
                         out=root / "with-bandai.safetensors", progress=False)
    alone = build_dataset(corpus[0], DatasetConfig(stride=16))
    cmu = train_model(model_name="pred-lstm", model_config={"hidden_dim": 8}, dataset=alone, config=_quick(),
                      out=root / "cmu-only.safetensors", progress=False)
    leaky = build_dataset(corpus, DatasetConfig(stride=16))  # the corpus rule trains on Bandai's 1B and 2C
    train_model(model_name="pred-lstm", model_config={"hidden_dim": 8}, dataset=leaky, config=_quick(),
                out=root / "leaky.safetensors", progress=False)
    return {"with": root / "with-bandai.safetensors", "without": root / "cmu-only.safetensors",
            "leaky": root / "leaky.safetensors", "results": (joined, cmu)}


def test_bandai_actions_land_in_the_corpus_classes():
    expected = {"walk": "walk", "walk-back": "walk", "walk-left": "walk", "walk-turn-right": "walk",
                "run": "run", "dash": "run", "wave-left-hand": "wave", "bye": "wave", "byebye": "wave",
                "raise-up-both-hands": "raise hands", "bow": "bow", "kick": "kick", "punch": "punch",
                "dance-short": "dance", "slash": "slash", "guide": "guide"}
    assert {a: action_class(a) for a in expected} == expected
    assert action_class("walk (start-walk-stop, MJ style)") == "walk"  # the corpus's own labels keep theirs
    assert source_of("bandai/bvh/dataset-2_run_active_001.bvh.xz") == "bandai-2"
    assert clip_group("bvh/dataset-1_bow_active_001.bvh.xz", "bow", "1B") == "bandai-1B"


def test_two_folders_form_one_corpus_split_by_performer(dataset):
    names = [c.name for c in dataset.clips]
    assert "cmu/02_01.bvh" in names and "bandai/bvh/dataset-2_run_feminine_001.bvh.xz" in names
    groups = {c.name: c.group for c in dataset.clips}
    assert {g for g in groups.values() if g.startswith("bandai")} == {"bandai-1A", "bandai-1B", "bandai-2A",
                                                                      "bandai-2B", "bandai-2C"}
    test_groups = {groups[n] for n in dataset.split.test}
    assert test_groups == {"cmu-02", "cmu-94", "bandai-1B", "bandai-2C"}
    train = set(dataset.split.train)
    assert not any(groups[n] in test_groups for n in train)
    labels = {c.name: c.label for c in dataset.clips}
    assert labels["bandai/bvh/dataset-2_raise-up-both-hands_elderly_020.bvh.xz"] == "raise hands"
    # every Bandai test action is performed in training; Indian dance is not
    train_actions = {labels[n] for n in train}
    assert {labels[n] for n in dataset.split.test if n.startswith("bandai/")} <= train_actions
    assert "indian dance" not in train_actions
    licences = dataset.summary["licences"]
    assert licences["non_commercial"] and licences["licences"]["CC BY-NC 4.0"] == sum(
        1 for n in train | set(dataset.split.val) if n.startswith("bandai/"))


def test_corpus_stats_shows_minutes_per_action_and_source(corpus, capsys, tmp_path):
    out = tmp_path / "stats.json"
    code = main(["corpus-stats", "--data", str(corpus[0]), "--data", str(corpus[1]), "--held-out", "subjects",
                 "--json", str(out)])
    text = capsys.readouterr().out
    assert code == 0
    stats = json.loads(out.read_text())
    frames = {"bandai-1": 0, "bandai-2": 0}
    with (corpus[1] / "manifest.csv").open() as f:
        for row in csv.DictReader(f):
            frames[row["dataset"]] += int(row["frames"])
    for source, count in frames.items():  # 30 fps files at the corpus's 25 fps: the same seconds
        assert stats["per_source"][source]["minutes"] == pytest.approx(count / 30 / 60, rel=0.02)
        assert f"| `{source}` |" in text
    assert {"walk", "run", "raise hands", "bow", "indian dance", "jump"} <= set(stats["per_action"])
    assert "| raise hands |" in text


def test_licence_words():
    assert is_non_commercial("CC BY-NC 4.0") and is_non_commercial("non-commercial research only")
    for free in ("CMU Graphics Lab mocap terms (free use; credit requested)", "MIT", "Apache-2.0 repo", "BSD-2-Clause",
                 "zlib (pybullet); DeepMimic MIT; mocap CMU/SFU per paper"):
        assert not is_non_commercial(free)
    record = licence_record(["MIT", "CC BY-NC 4.0", None, "MIT"])
    assert record["licences"] == {"CC BY-NC 4.0": 1, "MIT": 2, "unknown (no manifest licence)": 1}
    assert record["non_commercial"]
    table = licence_table({"bandai-model": record, "cmu-model": licence_record(["MIT"])})
    assert "bandai-model NON-COMMERCIAL data (CC BY-NC 4.0)" in table
    assert "cmu-model    no non-commercial licence among its 1 files" in table


@pytest.mark.slow
def test_checkpoints_record_licences_and_a_non_commercial_one_says_so_when_loaded(checkpoints, capsys):
    capsys.readouterr()
    meta = C.read_meta(checkpoints["with"])
    assert meta.data_summary["licences"]["non_commercial"]
    bundle = C.load_model(checkpoints["with"])
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "with-bandai was trained on non-commercial data (CC BY-NC 4.0)" in err[0]
    assert bundle.licences["non_commercial"]
    free = C.load_model(checkpoints["without"])
    assert capsys.readouterr().err == "" and not free.licences["non_commercial"]


def test_shipped_models_record_the_licences_of_their_training_files(shared_dir, capsys):
    from motion2video.evaluation.model_licences import shipped_licence_records

    recorded = shipped_licences()
    assert set(recorded) == set(C.shipped_names())
    assert shipped_licence_records(shared_dir / "data") == recorded
    for name, record in recorded.items():
        card = (C.WEIGHTS_DIR / f"{name}.md").read_text()
        assert card_section(record) in card, f"{name}.md: the data licence section is out of step"
    # where a user picks a model: the model list of --help
    with pytest.raises(SystemExit):
        main(["sample", "--help"])
    text = capsys.readouterr().out
    assert "data licences of the shipped models" in text
    line = next(x for x in text.splitlines() if x.split()[:1] == ["mixture-periodic"] and "licence" in x)
    assert line.split(None, 1)[1] == "no non-commercial licence among its 191 files", line


def test_subject_split_report_known_answer():
    def row(ade, n):
        return {"ade": ade, "fde": 2 * ade, "windows": n}

    per_key = {family_key("walk", "mocap"): row(1.0, 1), family_key("walk", "bandai"): row(4.0, 3),
               family_key("run", "bandai"): row(2.0, 2), family_key("indian dance", "mocap"): row(9.0, 5)}
    report = subject_split_report(per_key, {"walk", "run", "jump"})
    assert report["per_action"]["walk"] == {"ade": 3.25, "fde": 6.5, "windows": 4}
    assert report["macro"]["ade"] == pytest.approx((3.25 + 2.0) / 2)
    assert list(report["unseen"]) == ["indian dance"] and report["unseen"]["indian dance"]["ade"] == 9.0
    assert report["cross_dataset"] == {"ade": 3.0, "fde": 6.0, "windows": 5}


@pytest.mark.slow
def test_evaluate_split_subjects(checkpoints, corpus, tmp_path, capsys):
    out = tmp_path / "subjects.json"
    code = main(["evaluate", "--model", str(checkpoints["without"]), "--data", str(corpus[0]), "--data",
                 str(corpus[1]), "--split", "subjects", "--samples", "3", "--stride", "32", "--json", str(out)])
    text = capsys.readouterr().out
    assert code == 0
    report = json.loads(out.read_text())["subjects"]
    ours = report["report"]["cmu-only"]
    assert "indian dance" in ours["unseen"] and "indian dance" not in ours["per_action"]
    assert "walk" in ours["per_action"] and "run" in ours["per_action"]
    assert ours["macro"]["ade"] == pytest.approx(np.mean([r["ade"] for r in ours["per_action"].values()]))
    assert ours["cross_dataset"]["windows"] > 0 and report["trained_on_bandai"] == {"cmu-only": False}
    assert "unseen action: indian dance" in text and "(trained without Bandai)" in text
    # models trained on the subject split and on the CMU folder compare on the same windows
    code = main(["evaluate", "--model", str(checkpoints["with"]), "--model", str(checkpoints["without"]), "--data",
                 str(corpus[0]), "--data", str(corpus[1]), "--split", "subjects", "--samples", "3", "--stride", "32"])
    assert code == 0 and "with-bandai (trained with Bandai)" in capsys.readouterr().out
    # a model that trained on a held-out performer is refused with one line
    code = main(["evaluate", "--model", str(checkpoints["leaky"]), "--data", str(corpus[0]), "--data",
                 str(corpus[1]), "--split", "subjects", "--samples", "3"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err[0].startswith("motion2video: note: leaky was trained on non-commercial data")
    assert len(err) == 2 and err[1].startswith("motion2video evaluate: error: ") and "leaky.safetensors" in err[1]
    assert "holds out" in err[1]
