"""Compose a mixture checkpoint from trained samplers (nothing is trained; a few seconds).

    python scripts/make_mixture.py mtvae-add-dlow mixer-cvae-dlow mirror-periodic settle --shares 17,17,12,4 \
        -o motion2video/weights/mixture-periodic.safetensors

Each MODEL is a checkpoint path, a shipped name, or the name of a multi-future rule (``mirror-periodic``,
``settle``, which take the first model's windows and normalisation). With equal shares (no ``--shares``) future k of
the mixture comes from MODEL number k mod C; otherwise from the model furthest behind its share
(:mod:`motion2video.models.mixture`). The trained models must share their windows, feature layout, normalisation and
split. Bad input gives one line and exit 2.
"""

from __future__ import annotations

import argparse
import sys

from motion2video.core.errors import InputError
from motion2video.models.base import MODEL_REGISTRY
from motion2video.models.checkpoint import baseline_bundle, compose_mixture, load_model, save_checkpoint


def parse_shares(text: str | None, count: int) -> list[float] | None:
    """``"19,19,12"`` -> [19.0, 19.0, 12.0] (one positive number per model), None -> None."""
    if text is None:
        return None
    try:
        shares = [float(x) for x in text.split(",")]
    except ValueError:
        raise InputError(f"--shares must be numbers separated by commas, got {text!r}") from None
    if len(shares) != count or min(shares) <= 0:
        raise InputError(f"--shares needs one positive number per model ({count}), got {text!r}")
    return shares


def is_rule(name: str) -> bool:
    """Whether ``name`` is a registered model without weights (a baseline or a multi-future rule)."""
    entry = MODEL_REGISTRY.get(name)
    return entry is not None and entry.kind == "baseline"


def load_component(name: str, first):
    """A shipped name or checkpoint path; a rule's name in ``first``'s windows and normalisation statistics."""
    if is_rule(name):
        return baseline_bundle(name, first.data_config, stats=first.stats)
    return load_model(name)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+", help="two or more checkpoint paths or shipped names, in drawing order")
    parser.add_argument("-o", "--output", required=True, help="the mixture checkpoint to write (.safetensors)")
    parser.add_argument("--shares", default=None, help="one weight per model, comma-separated (default: equal)")
    args = parser.parse_args(argv)
    try:
        if not args.output.endswith(".safetensors"):
            raise InputError("the output must end in .safetensors", args.output)
        shares = parse_shares(args.shares, len(args.models))
        if is_rule(args.models[0]):
            raise InputError("the first model must be a trained sampler: a rule takes its windows and statistics",
                             args.models[0])
        bundles = [load_model(args.models[0])]
        bundles += [load_component(m, bundles[0]) for m in args.models[1:]]
        mixture = compose_mixture(bundles, shares)
    except InputError as err:
        print(f"make_mixture: error: {err}", file=sys.stderr)
        return 2
    out = save_checkpoint(args.output, model=mixture.model, meta=mixture.meta)
    parts = ", ".join(f"{n} ({w:.0%})" for n, w in zip(mixture.model.names, mixture.model.shares))
    print(f"wrote {out}: futures drawn in turn from {parts}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
