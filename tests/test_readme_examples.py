"""Every ``motion2video`` example of the README and of docs/cli.md runs as written.

The examples are read out of the code blocks of README.md, then docs/cli.md, at test time (a continued line
with its ``\\`` joined), and run in that order (an example both give runs once), from a working folder laid out
like a fresh clone beside ``../shared``: ``demo_inputs/`` and ``scripts/`` of this checkout are linked in, ``out/``
and ``runs/`` start empty, so the examples write their own outputs and never over anything of the checkout.

Each example runs through :func:`motion2video.cli.main`, the function the installed ``motion2video`` command
calls, in the test's own process (its working folder, output, torch threads, signal handlers and unraisable hook
set for the example and restored after it), so torch, Anny, MediaPipe and the renderers load once per part
rather than once per example. ``batch``, which starts worker processes of its own, runs as a process of its own;
so do the tests of tests/test_interrupts.py and tests/test_determinism.py, which check the command as a process
(signals, exit codes, results across processes), and :func:`test_the_installed_command_runs_the_cli_main`.

Training examples run with tiny step counts (``--steps 2``; ``train-frames`` also renders only 8 training
sequences, unless it fine-tunes on a ``--video``): that is the only change made to any command. The cluster
example is left out because it needs a running multi-node Ray cluster (``--address auto``); it is listed in
:data:`NEEDS_A_CLUSTER`, so any other example that is added to these documents runs here.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import signal
import subprocess
import sys
import traceback
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
NEEDS_A_CLUSTER = ("--address auto",)
DOCUMENTS = ("README.md", "docs/cli.md")
TINY = {"--steps": "2"}


def readme_examples(text: str) -> list[str]:
    """The ``motion2video ...`` command lines of the README's fenced code blocks, continuations joined."""
    commands: list[str] = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S):
        joined = re.sub(r"\\\n\s*", " ", block)
        for line in joined.splitlines():
            line = line.split("  #")[0].strip()
            if line.startswith("motion2video "):
                commands.append(line)
    return commands


def documented_examples() -> list[str]:
    """The examples of every document in :data:`DOCUMENTS`, in order, each command once."""
    commands: list[str] = []
    for name in DOCUMENTS:
        commands += [c for c in readme_examples((ROOT / name).read_text()) if c not in commands]
    return commands


def tiny(argv: list[str]) -> list[str]:
    """Training examples with tiny step counts (and few training renders for train-frames)."""
    out = list(argv)
    if argv[1] in ("train", "train-frames"):
        for i, arg in enumerate(out[:-1]):
            if arg in TINY:
                out[i + 1] = TINY[arg]
    if argv[1] == "train-frames" and "--train-sequences" not in out and "--video" not in out:
        out += ["--train-sequences", "8"]  # a fine-tune on a --video renders nothing
    return out


def test_readme_examples_are_found():
    commands = documented_examples()
    names = {shlex.split(c)[1] for c in commands}
    assert {"render", "sample", "synthesize", "transfer", "analogy", "train", "evaluate", "pose"} <= names, names
    assert tiny(["motion2video", "train", "--steps", "2000"]) == ["motion2video", "train", "--steps", "2"]
    fine_tune = ["motion2video", "train-frames", "--video", "v.avi", "--steps", "600"]
    assert tiny(fine_tune) == fine_tune[:-1] + ["2"]


# docs/cli.md's sections in parts that share no output and take a few minutes each, so that test workers can
# run them side by side (each part runs in order in its own working folder, one test file per part)
CLI_PARTS = {
    "cli-show": ("render", "pose", "sample"),
    "cli-make": ("synthesize", "transfer", "analogy"),
    "cli-score": ("evaluate", "train", "corpus-stats", "batch", "doctor", "app"),
    "cli-frames": ("evaluate-frames", "train-frames"),
}


def cli_sections(text: str) -> dict[str, str]:
    """docs/cli.md's ``## name`` sections by name (the text before the first one under "")."""
    sections: dict[str, str] = {}
    name, lines = "", []
    for line in text.splitlines(keepends=True):
        if line.startswith("## "):
            sections[name] = "".join(lines)
            name, lines = line[3:].strip(), []
        lines.append(line)
    sections[name] = "".join(lines)
    return sections


def example_parts() -> dict[str, list[str]]:
    """:func:`documented_examples` in parts that share no output: the README's, then docs/cli.md's by
    :data:`CLI_PARTS` (an example the README gives runs with the README's)."""
    readme = readme_examples((ROOT / "README.md").read_text())
    sections = cli_sections((ROOT / "docs/cli.md").read_text())
    parts, taken = {"readme": readme}, list(readme)
    for part, names in CLI_PARTS.items():
        parts[part] = [c for name in names for c in readme_examples(sections.get(name, "")) if c not in taken]
        taken += parts[part]
    return parts


OWN_PROCESS = ("batch",)  # commands that start worker processes of their own: run as the installed command


def run_in_this_process(argv: list[str], work: Path) -> tuple[int, str]:
    """``motion2video`` ``argv[1:]`` through :func:`motion2video.cli.main` in this process, from ``work``, on one
    torch thread: (exit code, its output). What the command changes of the process (working folder, torch
    threads, signal handlers, unraisable hook) is put back after it."""
    import torch

    from motion2video.cli import main

    before = (os.getcwd(), torch.get_num_threads(), signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM),
              sys.unraisablehook)
    output = io.StringIO()
    os.chdir(work)
    torch.set_num_threads(1)
    try:
        with contextlib.redirect_stdout(output), contextlib.redirect_stderr(output):
            code = main(argv[1:])
    except SystemExit as err:  # argparse's usage errors
        code = err.code if isinstance(err.code, int) else 2
    except Exception:  # a traceback is a failure of the example, reported with it
        code = 1
        output.write(traceback.format_exc())
    finally:
        os.chdir(before[0])
        torch.set_num_threads(before[1])
        signal.signal(signal.SIGINT, before[2])
        signal.signal(signal.SIGTERM, before[3])
        sys.unraisablehook = before[4]
    return code, output.getvalue()


def run_in_own_process(argv: list[str], work: Path) -> tuple[int, str]:
    """``motion2video`` ``argv[1:]`` as the installed command, from ``work``: (exit code, its output)."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYOPENGL_PLATFORM": os.environ.get("PYOPENGL_PLATFORM", "osmesa")}
    run = subprocess.run([sys.executable, "-m", "motion2video.cli", *argv[1:]], cwd=work, env=env,
                         capture_output=True, text=True, timeout=900)
    return run.returncode, run.stderr or run.stdout


def run_examples(commands: list[str], tmp_path: Path) -> None:
    """Run ``commands`` in order in a working folder laid out like a fresh clone beside ``../shared``; fails with
    every command that exited non-zero."""
    if not SHARED.is_dir():
        pytest.fail(f"the shared data folder {SHARED} is not beside the checkout")
    work = tmp_path / "clone"
    work.mkdir()
    os.symlink(SHARED, tmp_path / "shared")
    for name in ("demo_inputs", "scripts"):
        os.symlink(ROOT / name, work / name)
    failures = []
    for command in commands:
        if any(flag in command for flag in NEEDS_A_CLUSTER):
            continue
        argv = tiny(shlex.split(command))
        run = run_in_own_process if argv[1] in OWN_PROCESS else run_in_this_process
        code, output = run(argv, work)
        if code != 0:
            failures.append(f"{command}\n  exit {code}: {output.strip()[-400:]}")
    assert not failures, "documented examples that fail:\n" + "\n".join(failures)


def test_the_installed_command_runs_the_cli_main(tmp_path):
    """The ``motion2video`` command pip installed beside this interpreter is :func:`motion2video.cli.main`: its
    version, and a missing input as one line naming the file with exit 2."""
    from motion2video import __version__

    command = Path(sys.executable).parent / "motion2video"
    version = subprocess.run([command, "--version"], capture_output=True, text=True, timeout=120)
    assert version.returncode == 0 and version.stdout.strip() == f"motion2video {__version__}"
    missing = subprocess.run([command, "render", "missing.bvh", "-o", "walk.mp4"], cwd=tmp_path,
                             capture_output=True, text=True, timeout=300)
    lines = missing.stderr.strip().splitlines()
    assert missing.returncode == 2 and len(lines) == 1 and "missing.bvh" in lines[0], missing.stderr
    assert list(tmp_path.iterdir()) == []


def part_test(part: str):
    """The test that runs :func:`example_parts`'s ``part`` as written, for a test file of its own (xdist hands
    out whole files, so each part can go to its own worker)."""

    @pytest.mark.slow
    def test_examples_run_as_written(tmp_path):
        commands = example_parts()[part]
        assert commands
        run_examples(commands, tmp_path)

    return test_examples_run_as_written


def test_example_parts_hold_every_example_once():
    parts = example_parts()
    joined = [c for part in parts.values() for c in part]
    assert sorted(joined) == sorted(documented_examples()) and len(joined) == len(set(joined))
    assert len(parts["readme"]) >= 8 and all(len(parts[name]) >= 4 for name in CLI_PARTS)
    named = {name for names in CLI_PARTS.values() for name in names}
    assert set(cli_sections((ROOT / "docs/cli.md").read_text())) - named <= {"", "At a glance"}  # every section


@pytest.mark.slow
def test_every_readme_example_runs_as_written(tmp_path):
    run_examples(example_parts()["readme"], tmp_path)


def python_examples(text: str) -> list[str]:
    """The README's fenced ``python`` blocks, in order."""
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


@pytest.mark.slow
def test_readme_python_examples_run_as_written(tmp_path):
    blocks = python_examples((ROOT / "README.md").read_text())
    assert len(blocks) >= 2
    work = tmp_path / "clone"
    work.mkdir()
    os.symlink(ROOT / "demo_inputs", work / "demo_inputs")
    (work / "out").mkdir()
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYOPENGL_PLATFORM": os.environ.get("PYOPENGL_PLATFORM", "osmesa")}
    for block in blocks:
        run = subprocess.run([sys.executable, "-c", block], cwd=work, env=env, capture_output=True, text=True,
                             timeout=900)
        assert run.returncode == 0, f"{block}\n  exit {run.returncode}: {run.stderr.strip()[-600:]}"
    assert (work / "out" / "walk.mp4").is_file() and (work / "out" / "walk_mesh.mp4").is_file()
