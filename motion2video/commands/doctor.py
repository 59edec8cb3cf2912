"""`motion2video doctor`: what this machine can do, what is missing, and the fix for each missing thing."""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict

from motion2video.apps.doctor import report, run_checks
from motion2video.commands.common import add_command
from motion2video.core.atomic import check_output_path, write_text

DESCRIPTION = """\
Print what is available and what is missing, each missing thing with its fix.
"""

EXAMPLES = """\
examples:
  motion2video doctor
  motion2video doctor --json out/doctor.json

Checks: torch (version, threads), ffmpeg, the GL backends OSMesa and EGL (each renders one triangle in a child
process), the Anny model cache (built or not, size), and that every shipped checkpoint loads. Exit status 0 when
everything essential works (GL is not essential: skeleton and heatmap styles need none), 1 otherwise.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "doctor", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--json", default=None, help="also write the checks as JSON here")


def run(args: argparse.Namespace) -> int:
    if args.json:
        check_output_path(args.json, (".json",))
    checks = run_checks()
    print(report(checks))
    if args.json:
        write_text(args.json, json.dumps([asdict(c) for c in checks], indent=2) + "\n")
    return 0 if all(c.ok for c in checks if c.essential) else 1
