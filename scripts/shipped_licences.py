"""Write motion2video/weights/licences.json, the licences of the files each shipped checkpoint was trained on,
and the "Data licence" section of each model card (motion2video/weights/NAME.md).

    PYTHONPATH=. python scripts/shipped_licences.py --data-root ../shared/data
"""

from __future__ import annotations

import argparse

from pathlib import Path

from motion2video.core.atomic import write_json, write_section
from motion2video.data.licences import CARD_BEGIN, CARD_END, SHIPPED_LICENCES, card_section
from motion2video.evaluation.model_licences import shipped_licence_records


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default="../shared/data", help="folder holding mocap/ and face/")
    parser.add_argument("--out", default=str(SHIPPED_LICENCES))
    args = parser.parse_args(argv)
    records = shipped_licence_records(args.data_root)
    write_json(args.out, records)
    for name, record in records.items():
        card = Path(args.out).parent / f"{name}.md"
        if card.is_file():
            write_section(card, CARD_BEGIN, CARD_END, card_section(record))
    for name, record in records.items():
        print(f"{name}: {'NON-COMMERCIAL ' if record['non_commercial'] else ''}{', '.join(record['licences'])}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
