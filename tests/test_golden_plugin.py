"""The pytest plugin (fixture ``golden_frames``, ``--update-golden``, ``--golden-results``, the session summary),
run through pytest's own ``pytester``: the example file of docs/testing.md in a fresh project directory, and bad goldens.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from motion2video.formats.io import load_motion, resample_motion
from motion2video.apps.render import render_motion
from motion2video.testing.golden import panel_layout
from motion2video.formats.video import read_image, write_image

pytest_plugins = ["pytester"]

TESTING_DOC = Path(__file__).resolve().parents[1] / "docs" / "testing.md"


def readme_example() -> str:
    """The first python block of the docs/testing.md section "Golden-frame tests for your renders"."""
    text = TESTING_DOC.read_text()
    section = text[text.index("## Golden-frame tests for your renders"):]
    start = section.index("```python\n") + len("```python\n")
    return section[start:section.index("```", start)]


@pytest.mark.slow
def test_readme_example_through_pytester(pytester, mocap_dir):
    code = readme_example()
    assert code.count('palette="leftright"') == 1
    tests = pytester.mkdir("tests")
    (tests / "mocap").symlink_to(mocap_dir)
    (tests / "test_my_renders.py").write_text(code)
    args = ("-p", "no:cacheprovider", "tests/test_my_renders.py")
    golden = tests / "golden"

    # 1. --update-golden writes both goldens (a fresh process: the plugin comes from the installed entry point).
    first = pytester.runpytest_subprocess(*args, "--update-golden")
    first.assert_outcomes(passed=2)
    first.stdout.fnmatch_lines(["golden frames: 0 compared, 2 written, 0 failed, 0 unused"])
    assert sorted(os.listdir(golden / "test_walk_skeleton")) == [
        "frame_000.png", "frame_012.png", "frame_024.png", "golden.json"]
    assert sorted(os.listdir(golden / "test_walk_video")) == [
        "frame_000.png", "frame_006.png", "frame_012.png", "frame_018.png", "frame_024.png", "golden.json"]

    # 2. Without it the same renders pass; a golden folder no test uses is reported.
    shutil.copytree(golden / "test_walk_skeleton", golden / "test_old_walk")
    second = pytester.runpytest_subprocess(*args)
    second.assert_outcomes(passed=2)
    second.stdout.fnmatch_lines(["golden frames: 2 compared, 0 written, 0 failed, 1 unused", "*UNUSED*test_old_walk"])

    # 3. One render parameter changed: the skeleton test fails, with pictures that show the change.
    (tests / "test_my_renders.py").write_text(code.replace('palette="leftright"', 'palette="openpose"'))
    third = pytester.runpytest_subprocess(*args, "--golden-results", "results")
    third.assert_outcomes(passed=1, failed=1)
    third.stdout.fnmatch_lines(["golden frames: 2 compared, 0 written, 1 failed, 1 unused",
                                "*FAILED*test_walk_skeleton*(tests/test_my_renders.py::test_walk_skeleton)"])
    results = pytester.path / "results" / "test_walk_skeleton"
    output = third.stdout.str()
    walk = resample_motion(load_motion(mocap_dir / "cmu" / "08_01.bvh"), 25.0).slice(0, 25)
    openpose = render_motion(walk, style="skeleton", size=96, palette="openpose")
    layout = panel_layout(96, 96, 3)
    failing = sorted(p.name for p in results.iterdir())
    assert failing and failing == sorted(f"{kind}_{t:03d}.png" for t in (0, 12, 24) for kind in ("actual", "diff"))
    for t in (0, 12, 24):
        assert str(results / f"diff_{t:03d}.png") in output and f"frame {t}: max " in output
        before = read_image(golden / "test_walk_skeleton" / f"frame_{t:03d}.png")
        after = read_image(results / f"actual_{t:03d}.png")
        np.testing.assert_array_equal(after, openpose[t])
        panel = read_image(results / f"diff_{t:03d}.png")
        boxes = {name: panel[rows, cols][::layout.scale, ::layout.scale] for name, (rows, cols) in layout.boxes.items()}
        np.testing.assert_array_equal(boxes["golden"], before)
        np.testing.assert_array_equal(boxes["actual"], after)
        changed = (before != after).any(axis=-1)  # (96, 96): the recoloured limbs
        assert changed.sum() > 50
        np.testing.assert_array_equal(boxes["diff"].max(axis=-1) > 0, changed)
        assert (panel[layout.text_top:] > 200).sum() > 300  # the numbers under the images


BAD_INPUT_TESTS = """
import numpy as np

FRAMES = np.random.default_rng(0).integers(0, 255, (2, 16, 16, 3), dtype=np.uint8)


def test_dir_is_file(golden_frames):
    golden_frames(FRAMES, tolerance=0)


def test_corrupt(golden_frames):
    golden_frames(FRAMES, tolerance=0)


def test_other_size(golden_frames):
    golden_frames(FRAMES, tolerance=0)


def test_fine(golden_frames):
    golden_frames(FRAMES, tolerance=0)
"""


def test_bad_goldens_fail_the_test_not_the_plugin(pytester):
    pytester.makepyfile(test_bad=BAD_INPUT_TESTS)
    pytester.runpytest("-p", "no:cacheprovider", "--update-golden").assert_outcomes(passed=4)
    golden = pytester.path / "golden"
    shutil.rmtree(golden / "test_dir_is_file")
    (golden / "test_dir_is_file").write_text("a file where a golden folder belongs")
    (golden / "test_corrupt" / "frame_001.png").write_bytes(b"\x89PNG\r\n\x1a\n cut short")
    write_image(golden / "test_other_size" / "frame_000.png", np.zeros((8, 8, 3), np.uint8))

    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1, failed=3)
    output = result.stdout.str()
    assert "INTERNALERROR" not in output and "Traceback" not in output
    result.stdout.fnmatch_lines([
        "*test_dir_is_file: golden path *test_dir_is_file is a file, not a directory of frame_[*].png*",
        "*test_corrupt: bad golden files in *test_corrupt: cannot decode frame_001.png (corrupt PNG)*",
        "*test_other_size: bad golden files in *test_other_size: size: frame_000.png is 8x8, not 16x16*",
    ], consecutive=False)
    result.stdout.fnmatch_lines(["golden frames: 4 compared, 0 written, 3 failed, 0 unused"])

    # Update mode over a file fails the same way, and leaves the file alone.
    again = pytester.runpytest("-p", "no:cacheprovider", "--update-golden", "-k", "dir_is_file")
    again.assert_outcomes(failed=1, deselected=3)
    again.stdout.fnmatch_lines(["*is a file, not a directory; remove it or choose another name*",
                                "golden frames: 0 compared, 0 written, 1 failed, 3 unused",
                                "*3 tests were deselected*"])
    assert (golden / "test_dir_is_file").read_text() == "a file where a golden folder belongs"

    # The golden root itself a file: a clear failure, and the summary still prints.
    (pytester.path / "other").mkdir()
    (pytester.path / "other" / "golden").write_text("not a folder")
    shutil.copy(pytester.path / "test_bad.py", pytester.path / "other" / "test_other.py")
    rooted = pytester.runpytest("-p", "no:cacheprovider", "other/test_other.py", "-k", "fine")
    rooted.assert_outcomes(failed=1, deselected=3)
    rooted.stdout.fnmatch_lines(["*test_fine: golden directory *other/golden/test_fine does not exist*",
                                 "golden frames: 1 compared, 0 written, 1 failed, 0 unused"])
    updated = pytester.runpytest("-p", "no:cacheprovider", "other/test_other.py", "-k", "fine", "--update-golden")
    updated.assert_outcomes(failed=1, deselected=3)
    updated.stdout.fnmatch_lines(["*test_fine: cannot write goldens to *other/golden/test_fine*"])
    assert "INTERNALERROR" not in rooted.stdout.str() + updated.stdout.str()


NAMING_TESTS = """
import numpy as np
import pytest

FRAMES = np.random.default_rng(1).integers(0, 255, (3, 12, 12, 3), dtype=np.uint8)


@pytest.mark.parametrize("k", [1, 2])
def test_param(golden_frames, k):
    golden_frames(FRAMES // k, tolerance=0, fps=10)


def test_named(golden_frames):
    golden_frames(FRAMES, name="shared", tolerance=0)


def test_same_name_again(golden_frames):
    golden_frames(FRAMES, name="shared", tolerance=0)
"""

CONFTEST = """
import pytest


@pytest.fixture
def golden_root(request):
    return request.config.rootpath / "snapshots"
"""


def test_names_alias_root_and_counts(pytester, monkeypatch):
    pytester.makepyfile(test_names=NAMING_TESTS)
    pytester.makeconftest(CONFTEST)
    monkeypatch.setenv("UPDATE_GOLDEN", "1")  # the old switch still writes goldens
    written = pytester.runpytest("-p", "no:cacheprovider")
    written.assert_outcomes(passed=3, failed=1)
    written.stdout.fnmatch_lines(["*shared: the golden *snapshots/shared is already used by "
                                  "test_names.py::test_named; give this comparison its own name=*",
                                  "golden frames: 0 compared, 3 written, 1 failed, 0 unused"])
    assert sorted(os.listdir(pytester.path / "snapshots")) == ["shared", "test_param_1", "test_param_2"]
    monkeypatch.delenv("UPDATE_GOLDEN")

    compared = pytester.runpytest("-p", "no:cacheprovider")
    compared.assert_outcomes(passed=3, failed=1)
    compared.stdout.fnmatch_lines(["golden frames: 3 compared, 0 written, 1 failed, 0 unused"])
    subset = pytester.runpytest("-p", "no:cacheprovider", "-k", "param")
    subset.assert_outcomes(passed=2, deselected=2)
    subset.stdout.fnmatch_lines(["golden frames: 2 compared, 0 written, 0 failed, 1 unused", "*UNUSED*snapshots/shared",
                                 "*2 tests were deselected*"])
    nothing = pytester.runpytest("-p", "no:cacheprovider", "-k", "no_such_test")
    assert "golden frames" not in nothing.stdout.str()  # no golden used: no summary


@pytest.mark.slow
def test_parallel_workers_report_one_golden_summary(pytester):
    """Under pytest-xdist (``make test`` runs two workers) the controller prints the summary of every worker's
    goldens: written, compared, failed and unused, as one process would."""
    pytester.makepyfile(test_a=BAD_INPUT_TESTS.replace("test_dir_is_file", "test_one").replace(
        "test_corrupt", "test_two").replace("test_other_size", "test_three"))
    pytester.makepyfile(test_b=BAD_INPUT_TESTS.replace("test_dir_is_file", "test_four").replace(
        "test_corrupt", "test_five").replace("test_other_size", "test_six").replace("test_fine", "test_seven"))
    args = ("-p", "no:cacheprovider", "-n", "2", "--dist", "loadfile")
    written = pytester.runpytest_subprocess(*args, "--update-golden")
    written.assert_outcomes(passed=8)
    written.stdout.fnmatch_lines(["golden frames: 0 compared, 8 written, 0 failed, 0 unused"])
    (pytester.path / "golden" / "test_old").mkdir()
    (pytester.path / "golden" / "test_old" / "golden.json").write_text("{}")
    (pytester.path / "golden" / "test_seven" / "frame_000.png").write_bytes(b"not a png")
    compared = pytester.runpytest_subprocess(*args)
    compared.assert_outcomes(passed=7, failed=1)
    compared.stdout.fnmatch_lines(["golden frames: 8 compared, 0 written, 1 failed, 1 unused",
                                   "*FAILED*golden/test_seven*", "*UNUSED*golden/test_old"])
