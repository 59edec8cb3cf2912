"""The examples of docs/cli.md's synthesize, transfer and analogy sections run as written, in order, in a working folder laid out
like a fresh clone (:func:`tests.test_readme_examples.part_test`)."""

from tests.test_readme_examples import part_test

test_examples_run_as_written = part_test("cli-make")
