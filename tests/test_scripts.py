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
    ("bench", ("render", "batch", "frames", "pipeline", "pose", "sampling", "long-bvh", "mesh-video")),
    ("make_results", ("forecasting", "card", "corpus", "known-answer", "per-action", "five-minute-models",
                      "skeleton", "skeleton-figure", "frames", "frames-analysis", "frames-real", "transfer",
                      "transfer-benchmark", "face-sheet")),
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
