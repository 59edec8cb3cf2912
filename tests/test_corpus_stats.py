"""`motion2video corpus-stats` on a small mocap folder of every format (a manifest subset of the shared
data, files linked): duplicates dropped, groups kept whole, minutes that add up, one-line errors."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from motion2video.cli import main
from motion2video.data.corpus_stats import CorpusStatsSettings, corpus_report, corpus_stats
from motion2video.data.dataset import DatasetConfig

CLIPS = ("cmu/02_01.bvh", "deepmimic-cmu/02_01.txt", "cmu-bench/train/walking/walking_1.txt",
         "cmu-bench/test/walking/walking_1.txt", "acrnn/salsa_01a.bvh", "acrnn/salsa_01b.bvh",
         "cmu/131_01.bvh", "mass/mass_walk.bvh", "deepmimic-cmu/85_01.txt", "cmu/13_11.bvh")
SUPPORT = ("cmu-bench/skeleton.json", "deepmimic/humanoid3d_character.txt")


@pytest.fixture(scope="module")
def small_corpus(tmp_path_factory, mocap_dir) -> Path:
    root = tmp_path_factory.mktemp("corpus")
    for rel in CLIPS + SUPPORT:
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).symlink_to(mocap_dir / rel)
    with (mocap_dir / "manifest.csv").open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        rows = [r for r in reader if r["file"] in CLIPS]
        fields = reader.fieldnames
    with (root / "manifest.csv").open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    return root


def test_corpus_stats_command(small_corpus, tmp_path, capsys):
    out = tmp_path / "stats.json"
    assert main(["corpus-stats", "--data", str(small_corpus), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    stats = json.loads(out.read_text())
    assert "| source | files |" in printed and "| split |" in printed and "| action |" in printed
    # 02_01 is in three folders: the cmu/ BVH is kept.
    assert stats["dropped"] == {"deepmimic-cmu/02_01.txt": "cmu/02_01.bvh",
                                "cmu-bench/train/walking/walking_1.txt": "cmu/02_01.bvh"}
    assert stats["total"]["files"] == 10 and stats["total"]["clips"] == 8
    assert stats["per_source"]["cmu-bench"]["dropped_copies"] == 1
    # Pinned groups: cmu-02 (linked with the unidentified benchmark walk) and 131 test, mass and 85 val.
    assert stats["groups"]["test"] == ["cmu-02+cmu-bench:walking", "cmu-131"]
    assert stats["groups"]["val"] == ["cmu-85", "mass"]
    assert stats["groups"]["train"] == ["cmu-13", "cmu-60-61"]
    # Minutes add up across sources, splits and actions; salsa is at its true 60 fps (2238 frames: 37.3 s).
    total = stats["total"]["minutes"]
    assert sum(v["minutes"] for v in stats["per_source"].values()) == pytest.approx(total)
    assert sum(v["minutes"] for v in stats["per_split"].values()) == pytest.approx(total)
    assert sum(v["total"] for v in stats["per_action"].values()) == pytest.approx(total)
    assert stats["per_action"]["salsa"]["train"] == pytest.approx(2 * 2238 / 60 / 60, rel=0.01)
    assert f"{total:.1f} minutes" in printed
    # The command prints what its function returns: the same tables from Python, without the CLI.
    report = corpus_report(CorpusStatsSettings(data=small_corpus))
    assert report.json is None and json.loads(json.dumps(report.stats)) == stats and report.markdown in printed


def test_corpus_stats_options_and_bad_input(small_corpus, tmp_path, capsys):
    keep = corpus_stats(small_corpus, DatasetConfig(drop_duplicates=False))
    assert keep["total"]["clips"] == 10 and keep["dropped"] == {}
    assert keep["per_split"]["test"]["clips"] == 5  # the three copies of 02_01, the linked walk, 131_01
    assert main(["corpus-stats", "--data", str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "missing" in err[0]
    assert main(["corpus-stats", "--data", str(small_corpus), "--json", str(tmp_path / "no" / "x.json")]) == 2
    assert "does not exist" in capsys.readouterr().err
