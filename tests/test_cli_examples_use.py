"""Every one of the examples of docs/cli.md up to its ``## evaluate`` section (the commands that use the shipped models) runs as written, in order, in a working folder laid out like a fresh clone
(:func:`tests.test_readme_examples.run_examples`). A file of its own so that a test worker can run it beside the
README's examples."""

from __future__ import annotations

import pytest

from tests.test_readme_examples import example_parts, run_examples


@pytest.mark.slow
def test_examples_run_as_written(tmp_path):
    commands = example_parts()["cli-use"]
    assert commands
    run_examples(commands, tmp_path)
