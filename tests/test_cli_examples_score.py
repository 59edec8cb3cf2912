"""The examples of docs/cli.md's evaluate, train, corpus-stats, batch, doctor and app sections run as written, in order, in a working folder laid out
like a fresh clone (:func:`tests.test_readme_examples.part_test`)."""

from tests.test_readme_examples import part_test

test_examples_run_as_written = part_test("cli-score")
