"""Change the inference settings of a mesh frame generator checkpoint, keeping its weights.

The mesh generator's configuration (:class:`motion2video.generator.mesh_warp.MeshWarpConfig`) holds settings that
have no weights: the image size and ``net_scale`` (a 128 px model at net_scale 2 and a 256 px model at net_scale 4
see the body at the same scale) and ``sharpen``. This writes a copy of a checkpoint
with some of them changed, and its training summary, plus a note of what was changed::

    python scripts/mesh_settings.py runs/mesh256.safetensors --sharpen 0.2 \\
        -o motion2video/weights/frames-body-mesh-256.safetensors

Weights that need other shapes cannot be made this way (use ``train-frames --init-from``).
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint", help="a mesh frame generator (.safetensors or shipped name)")
    parser.add_argument("-o", "--output", required=True, help="where to write the copy (.safetensors)")
    parser.add_argument("--size", type=int, default=None, help="image size (the network's scale follows: size/64)")
    parser.add_argument("--sharpen", type=float, default=None, help="unsharp-mask amount of the sampled reference")
    args = parser.parse_args(argv)

    from motion2video.core.errors import InputError
    from motion2video.generator.checkpoint import load_frame_model, save_frame_model
    from motion2video.generator.mesh_warp import MeshWarpGenerator

    try:
        loaded = load_frame_model(args.checkpoint)
        if loaded.kind != "mesh":
            raise InputError(f"this is a {loaded.kind} frame model, not a mesh one", loaded.path)
        changes = {}
        if args.size is not None:
            changes.update(image_size=args.size, net_scale=max(1, args.size // 64))
        if args.sharpen is not None:
            changes["sharpen"] = args.sharpen
        try:
            config = replace(loaded.model.config, **changes)
        except ValueError as err:
            raise InputError(str(err)) from None
        net = MeshWarpGenerator(config)
        net.load_state_dict(loaded.model.state_dict())
        from safetensors import safe_open

        with safe_open(str(loaded.path), "pt") as f:
            train = json.loads(f.metadata().get("train", "{}"))
        train["settings_changed"] = {"from": str(args.checkpoint), **changes}
        out = save_frame_model(net, args.output, step=loaded.step, train=train)
    except InputError as err:
        print(f"mesh_settings: {err}", file=sys.stderr)
        return 2
    print(f"wrote {out}: {config.to_json()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
