"""Compose a mixture checkpoint from trained samplers (nothing is trained; a few seconds).

    python scripts/make_mixture.py mtvae-add-dlow mixer-cvae-dlow -o motion2video/weights/mixture-dlow.safetensors

Each MODEL is a checkpoint path or a shipped name. Future k of the mixture comes from MODEL number k mod C
(:mod:`motion2video.models.mixture`); the models must share their windows, feature layout, normalisation and split.
Bad input gives one line and exit 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from motion2video.core.errors import InputError  # noqa: E402
from motion2video.models.checkpoint import compose_mixture, load_model, save_checkpoint  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+", help="two or more checkpoint paths or shipped names, in drawing order")
    parser.add_argument("-o", "--output", required=True, help="the mixture checkpoint to write (.safetensors)")
    args = parser.parse_args(argv)
    try:
        if not args.output.endswith(".safetensors"):
            raise InputError("the output must end in .safetensors", args.output)
        mixture = compose_mixture([load_model(m) for m in args.models])
    except InputError as err:
        print(f"make_mixture: error: {err}", file=sys.stderr)
        return 2
    out = save_checkpoint(args.output, model=mixture.model, meta=mixture.meta)
    print(f"wrote {out}: futures drawn in turn from {', '.join(mixture.model.names)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
