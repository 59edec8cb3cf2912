"""scripts/ holds tools: a few entry points that import the installed package, each with its parts as
sub-commands (``bench.py``, ``make_results.py``)."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def _run(*argv: str, timeout: int = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *argv], capture_output=True, text=True, timeout=timeout)


def test_scripts_are_few_and_import_the_package():
    files = sorted(p.name for p in SCRIPTS.iterdir())
    assert len(files) <= 12, files
    for path in SCRIPTS.glob("*.py"):
        assert not re.search(r"sys\.path\.(insert|append)|sys\.path\[", path.read_text()), f"{path.name} edits sys.path"


@pytest.mark.parametrize("script, subcommands", [
    ("bench", ("render", "batch", "frames", "pipeline", "pose", "sampling", "long-bvh", "mesh-video",
               "transfer-fit")),
    ("make_results", ("forecasting", "card", "corpus", "known-answer", "per-action", "five-minute-models",
                      "skeleton-figure", "frames", "frames-analysis", "frames-real", "transfer",
                      "transfer-benchmark", "transfer-unseen", "face-sheet", "bandai")),
])
def test_entry_points_list_their_subcommands_and_refuse_unknown_ones(script, subcommands, monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(SCRIPTS))  # as when the script runs: its folder first on the path
    module = importlib.import_module(script)
    assert module.main(["--help"]) == 0
    listed = capsys.readouterr().out
    for name in subcommands:
        assert f"\n  {name} " in listed
    assert module.main(["no-such-part"]) == 2 and "usage:" in capsys.readouterr().err
    # every part parses its own options
    for name in subcommands:
        with pytest.raises(SystemExit) as done:
            module.main([name, "--help"])
        assert done.value.code == 0 and "usage:" in capsys.readouterr().out, name



def test_every_results_section_has_its_markers_on_its_page(monkeypatch):
    """Each sub-command of make_results.py that writes a results page finds its marker pairs there (write_section
    refuses a page without them), each pair once, in order."""
    from motion2video.core.atomic import check_section

    monkeypatch.syspath_prepend(str(SCRIPTS))
    module = importlib.import_module("make_results")
    docs = SCRIPTS.parent / "docs"
    pages = {"results.md": ("FORECASTING", "CORPUS", "KNOWN_ANSWER", "PER_ACTION", "FRAMES", "FRAMES_REAL"),
             "results_bandai.md": ("BANDAI",),
             "results_transfer.md": ("TRANSFER_ANALOGY", "TRANSFER_CLAIMS", "TRANSFER_BENCHMARK")}
    for name, parts in pages.items():
        text = (docs / name).read_text()
        for part in parts:
            begin, end = getattr(module, f"{part}_BEGIN"), getattr(module, f"{part}_END")
            check_section(docs / name, begin, end)
            assert text.count(begin) == 1 and text.count(end) == 1, (name, part)


def test_card_keeps_the_data_licence_block_of_the_card_it_replaces(tmp_path, monkeypatch):
    """make_results.py card rewrites a model card but keeps the block scripts/shipped_licences.py writes between
    its markers (a new card gets the empty pair, which shipped_licences fills)."""
    import json

    from motion2video.core.atomic import write_section
    from motion2video.data.licences import CARD_BEGIN, CARD_END

    monkeypatch.syspath_prepend(str(SCRIPTS))
    module = importlib.import_module("make_results")
    evaluation = tmp_path / "mtvae-add.eval.json"
    row = {"ade": 0.66, "fde": 0.69, "mmade": 0.69, "mmfde": 0.69, "apd": 3.7}
    evaluation.write_text(json.dumps({"protocol": {"windows": 301, "clips": ["cmu/131_01.bvh"], "samples": 50,
                                                   "units": "metres"}, "results": {"mtvae-add": row}}))
    card = tmp_path / "mtvae-add.md"
    argv = ["card", "--checkpoint", str(SCRIPTS.parent / "motion2video" / "weights" / "mtvae-add.safetensors"),
            "--eval", str(evaluation), "--command", "motion2video train ...", "--out", str(card)]
    assert module.main(argv) == 0
    text = card.read_text()
    assert text.startswith("# mtvae-add\n") and "| mtvae-add | 0.660 | 0.690 |" in text
    assert text.rstrip().endswith(f"{CARD_BEGIN}\n{CARD_END}")
    write_section(card, CARD_BEGIN, CARD_END, "## Data licence\n\nCC0 files only.")
    assert module.main(argv) == 0
    assert card.read_text().rstrip().endswith(f"{CARD_BEGIN}\n## Data licence\n\nCC0 files only.\n{CARD_END}")

@pytest.mark.slow
def test_make_results_skeleton_figure_draws_every_source(tmp_path, mocap_dir):
    out = tmp_path / "skeletons.png"
    run = _run(str(SCRIPTS / "make_results.py"), "skeleton-figure", "--mocap", str(mocap_dir), "--out", str(out),
               timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    import cv2

    image = cv2.imread(str(out))
    assert image is not None and image.shape[0] > 100 and image.shape[1] > 100
    assert (image < 128).any()  # lines drawn on the white page
