"""The first Anny construction on a machine builds its cache for a minute or more: a line on stderr says so before
it starts; a built cache says nothing."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from renderers.anny_model import build_note, cache_built, cache_folder


def test_the_note_names_the_folder_and_the_cost_until_the_cache_is_built(tmp_path):
    folder = tmp_path / "anny"
    note = build_note(folder)
    assert note is not None and str(folder) in note and "once per machine" in note and "40 s" in note
    (folder / "v14").mkdir(parents=True)
    (folder / "v14" / "data.safetensors").write_bytes(b"built")
    assert cache_built(folder) and build_note(folder) is None


@pytest.mark.slow
def test_a_fresh_cache_is_announced_on_stderr_before_the_build(tmp_path):
    """A real first construction with an empty cache folder: its first line on stderr is the note (the process is
    stopped there rather than left to build 0.8 GB)."""
    env = dict(os.environ, ANNY_CACHE_DIR=str(tmp_path / "anny"))
    proc = subprocess.Popen([sys.executable, "-c", "from renderers.anny_model import get_anny; get_anny()"],
                            stderr=subprocess.PIPE, text=True, env=env)
    try:
        first = proc.stderr.readline()
    finally:
        proc.kill()
        proc.wait()
    assert first.startswith("motion2video: building the Anny body model's cache in ") and str(tmp_path) in first


@pytest.mark.slow
def test_a_built_cache_says_nothing(capfd):
    from renderers.anny_model import get_anny

    assert cache_built(cache_folder())  # the machine's cache, built by the first mesh test or `make demo`
    get_anny()
    assert "Anny" not in capfd.readouterr().err
