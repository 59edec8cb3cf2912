"""The examples of docs/cli.md's evaluate-frames and train-frames sections run as written, in order, in a working folder laid out
like a fresh clone (:func:`tests.test_readme_examples.run_examples`). A file of its own so that a test worker can
run it beside the other parts (:data:`tests.test_readme_examples.CLI_PARTS`)."""

from __future__ import annotations

import pytest

from tests.test_readme_examples import example_parts, run_examples


@pytest.mark.slow
def test_examples_run_as_written(tmp_path):
    commands = example_parts()["cli-frames"]
    assert commands
    run_examples(commands, tmp_path)
