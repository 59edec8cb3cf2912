"""`motion2video batch`: many render / sample / synthesize jobs on a local process pool or on Ray."""

from __future__ import annotations

import argparse
from pathlib import Path

from motion2video.apps.batch import ENGINES, BatchConfig, describe, load_jobs, run_batch
from motion2video.commands.common import add_command
from motion2video.core.errors import InputError

DESCRIPTION = """\
Run independent jobs in parallel: each is one sub-command with its own arguments and output. Bad inputs fail
their own row and never stop the batch; outputs are written atomically.
"""

EXAMPLES = """\
examples:
  motion2video batch ../shared/data/mocap/cmu --template "render {input} -o {output} --style skeleton" --out out/cmu
  motion2video batch "../shared/data/mocap/**/*.bvh" --template "render {input} --palette openpose --size 256" \\
      --out out/openpose --workers 2
  motion2video batch jobs.jsonl --out out/jobs --engine ray --address auto --retries 3
  motion2video batch jobs.jsonl --out out/jobs --force            # redo every job

jobs.jsonl has one job per line (outputs relative to --out):
  {"command": "render", "args": ["clip.bvh", "--style", "mesh"], "output": "clip_mesh.mp4"}
  {"command": "sample", "args": {"input": "clip.bvh", "model": "mtvae-add", "samples": 4}, "output": "f.mp4"}

A job whose output already reads back as a video is skipped (--force redoes it). The output folder gets
results.jsonl (one row per job: status, seconds, output, frames, error) and index.html (the gallery).
Exit status: 0 when no job failed, 1 when some failed, 2 for a bad batch (no jobs, bad template).
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "batch", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("jobs", help="a .jsonl job file, or a folder of motion files / a glob pattern (with --template)")
    p.add_argument("--template", help='command for each input, e.g. "render {input} -o {output} --style skeleton" '
                   "(fields {input} {output} {stem} {name})")
    p.add_argument("--out", required=True, help="output folder (results.jsonl, index.html, relative outputs)")
    p.add_argument("--ext", choices=(".mp4", ".gif"), default=".mp4", help="output extension with --template")
    p.add_argument("--engine", choices=ENGINES, default="local", help="local process pool (default) or Ray")
    p.add_argument("--workers", type=int, default=1,
                   help="worker processes (local) or CPUs of the local Ray instance (default 1)")
    p.add_argument("--address", default=None,
                   help="Ray cluster address ('auto' for the cluster of `ray start`); default: a local instance")
    p.add_argument("--retries", type=int, default=2, help="extra attempts for a job whose worker crashed (default 2)")
    p.add_argument("--force", action="store_true", help="redo jobs whose output already exists")
    p.add_argument("--dry-run", action="store_true", help="list the jobs and exit")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def run(args: argparse.Namespace) -> int:
    if args.engine == "local" and args.address is not None:
        raise InputError("--address needs --engine ray")
    jobs = load_jobs(args.jobs, args.out, template=args.template, suffix=args.ext)
    if args.dry_run:
        print(describe(jobs))
        return 0
    config = BatchConfig(out_dir=Path(args.out), engine=args.engine, workers=args.workers, address=args.address,
                         retries=args.retries, force=args.force, progress=not args.no_progress)
    summary = run_batch(jobs, config)
    print(f"{summary.line()}; results {summary.results_path}, gallery {summary.gallery_path}")
    return 1 if summary.count("failed") else 0
