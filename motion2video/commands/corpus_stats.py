"""`motion2video corpus-stats`: minutes per source, action and split of the training corpus."""

from __future__ import annotations

import argparse

from motion2video.commands.common import CHARACTER_HELP, add_command
from motion2video.data.corpus_stats import CorpusStatsSettings, corpus_report

DESCRIPTION = """\
Load every clip of a mocap folder as the dataset builder does (all formats, true frame rates, duplicate copies
of one trial dropped, the subject-disjoint split) and print Markdown tables: minutes per source, per split and
per action, and the held-out groups.
"""

EXAMPLES = """\
examples:
  motion2video corpus-stats --data ../shared/data/mocap
  motion2video corpus-stats --data ../shared/data/mocap --json out/corpus.json
  motion2video corpus-stats --data ../shared/data/mocap --keep-duplicates --held-out hash
  motion2video corpus-stats --data ../shared/data/mocap --data ../shared/data/bandai --held-out subjects

The clips, the duplicates dropped and the split are exactly what `motion2video train --data DIR` uses with
the default data config (25 fps, 16 observed + 48 future frames).
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "corpus-stats", run, description=DESCRIPTION, examples=EXAMPLES)
    p.add_argument("--data", required=True, action="append",
                   help="mocap folder (with manifest.csv); repeat to join folders into one corpus (the clips of "
                   "every folder after the first named with its folder's name in front)")
    p.add_argument("--character", metavar="FILE", default=None, help=CHARACTER_HELP)
    p.add_argument("--json", default=None, help="also write the statistics as JSON here")
    p.add_argument("--held-out", choices=("corpus", "hash", "subjects"), default="corpus",
                   help="split rule (default corpus: the pinned held-out subjects and sources; subjects: also one "
                   "Bandai-Namco performer per set)")
    p.add_argument("--keep-duplicates", action="store_true",
                   help="keep every copy of a trial found in several folders")


def run(args: argparse.Namespace) -> int:
    settings = CorpusStatsSettings(data=tuple(args.data), json=args.json, held_out=args.held_out,
                                   keep_duplicates=args.keep_duplicates, character=args.character)
    report = corpus_report(settings)
    print(report.markdown, end="")
    if report.json is not None:
        print(f"wrote {report.json}")
    return 0
