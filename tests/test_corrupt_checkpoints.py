"""Corrupt checkpoints: a truncated file, damaged or missing metadata, and a format version from a
later motion2video each give one line naming the file and the problem, exit 2, and no output, from every
command that loads a checkpoint. The files are made from the real shipped weights."""

from __future__ import annotations

from pathlib import Path

import pytest
from safetensors import safe_open
from safetensors.torch import load_file, save_file

from motion2video.models.checkpoint import WEIGHTS_DIR
from motion2video.cli import main

REPO = Path(__file__).resolve().parents[1]
DEMO = REPO / "demo_inputs"


def _copy_with(src: Path, dst: Path, change) -> Path:
    """``src``'s tensors with its metadata changed by ``change(dict) -> dict``."""
    with safe_open(str(src), framework="pt") as f:
        metadata = dict(f.metadata() or {})
    save_file(load_file(str(src)), str(dst), metadata=change(metadata))
    return dst


def _truncated(src: Path, dst: Path) -> Path:
    data = src.read_bytes()
    dst.write_bytes(data[: len(data) // 2])
    return dst


def _damaged_record(metadata: dict) -> dict:
    metadata["motion2video"] = metadata["motion2video"][:40]  # cut JSON
    return metadata


def _bad_frames_config(metadata: dict) -> dict:
    metadata["config"] = '{"channels": "many"'
    return metadata


def motion_cases(tmp: Path) -> dict[str, tuple[Path, str]]:
    src = WEIGHTS_DIR / "mtvae-add.safetensors"
    return {
        "truncated": (_truncated(src, tmp / "truncated.safetensors"), "not a readable safetensors checkpoint"),
        "garbage": (_write(tmp / "garbage.safetensors", b"\x00\x01not a checkpoint"), "not a readable safetensors"),
        "no metadata record": (_copy_with(src, tmp / "norecord.safetensors",
                                          lambda m: {k: v for k, v in m.items() if k != "motion2video"}),
                               "'motion2video' record is missing"),
        "damaged metadata": (_copy_with(src, tmp / "damaged.safetensors", _damaged_record), "damaged checkpoint metadata"),
        "no metadata at all": (_copy_with(src, tmp / "bare.safetensors", lambda m: {}), "not a motion2video checkpoint"),
        "future format": (_copy_with(src, tmp / "future.safetensors", lambda m: {**m, "format_version": "7"}),
                          "format version 7 is newer"),
        "format version not a number": (_copy_with(src, tmp / "nan.safetensors", lambda m: {**m, "format_version": "x"}),
                                        "format_version 'x' is not a number"),
    }


def frame_cases(tmp: Path) -> dict[str, tuple[Path, str]]:
    src = WEIGHTS_DIR / "frames-body-128.safetensors"
    return {
        "truncated": (_truncated(src, tmp / "ftruncated.safetensors"), "cannot read the checkpoint"),
        "damaged config": (_copy_with(src, tmp / "fconfig.safetensors", _bad_frames_config), "damaged checkpoint metadata"),
        "future format": (_copy_with(src, tmp / "ffuture.safetensors", lambda m: {**m, "format_version": "2"}),
                          "format version 2 is newer"),
        "damaged step": (_copy_with(src, tmp / "fstep.safetensors", lambda m: {**m, "step": "many"}),
                         "damaged checkpoint metadata"),
    }


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _fails_cleanly(argv: list[str], capsys, ckpt: Path, phrase: str, outputs: list[Path]) -> None:
    code = main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and "error:" in lines[0] and "Traceback" not in err, err
    assert str(ckpt) in lines[0] and phrase in lines[0], lines[0]
    for out in outputs:
        assert not out.exists(), out
        assert not list(out.parent.glob(f".{out.stem}*")), "a temporary file was left behind"


@pytest.mark.parametrize("case", sorted(motion_cases(Path("/tmp"))))
def test_motion_checkpoint_is_refused_by_every_command(case, tmp_path, capsys, mocap_dir):
    ckpt, phrase = motion_cases(tmp_path)[case]
    clip = str(DEMO / "walk_to_run.npz")
    out = tmp_path / "out.mp4"
    _fails_cleanly(["sample", "--model", str(ckpt), clip, "--samples", "2", "-o", str(out)], capsys, ckpt, phrase, [out])
    _fails_cleanly(["synthesize", "--motion-model", str(ckpt), "--frame-model", "frames-body-128", clip,
                    "--reference", str(DEMO / "reference_body_128.png"), "--samples", "2", "-o", str(out)],
                   capsys, ckpt, phrase, [out])
    _fails_cleanly(["evaluate", "--model", str(ckpt), "--data", str(mocap_dir / "cmu" / "08_01.bvh")],
                   capsys, ckpt, phrase, [])
    _fails_cleanly(["transfer", "--model", str(ckpt), "--sample", "2", "--target", clip, "-o", str(out)],
                   capsys, ckpt, phrase, [out])


@pytest.mark.parametrize("case", ["truncated", "future format", "no metadata record"])
def test_corrupt_resume_checkpoint_is_refused(case, tmp_path, capsys, mocap_dir):
    """``train --resume`` reads OUT.last.safetensors: a damaged one is one line, exit 2, and no OUT."""
    src, phrase = motion_cases(tmp_path)[case]
    out = tmp_path / "run.safetensors"
    last = tmp_path / "run.last.safetensors"
    src.rename(last)
    (tmp_path / "run.last.optim.safetensors").write_bytes(b"")
    code = main(["train", "--model", "mtvae-add", "--data", str(mocap_dir / "cmu"), "-o", str(out), "--steps", "2",
                 "--resume", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "run.last" in err and not out.exists(), err


@pytest.mark.parametrize("case", sorted(frame_cases(Path("/tmp"))))
def test_frame_checkpoint_is_refused(case, tmp_path, capsys):
    ckpt, phrase = frame_cases(tmp_path)[case]
    out = tmp_path / "out.mp4"
    _fails_cleanly(["synthesize", "--motion-model", "mtvae-add", "--frame-model", str(ckpt),
                    str(DEMO / "walk_to_run.npz"), "--reference", str(DEMO / "reference_body_128.png"),
                    "--samples", "2", "-o", str(out)], capsys, ckpt, phrase, [out, tmp_path / "out-structure.mp4"])


def test_written_checkpoints_record_their_format_version(tmp_path):
    """What save_checkpoint / save_frame_model write carries format_version, and reads back."""
    from motion2video.models.checkpoint import load_model, save_checkpoint
    from motion2video.generator.checkpoint import load_frame_model, save_frame_model

    bundle = load_model("mtvae-add")
    motion = save_checkpoint(tmp_path / "m.safetensors", model=bundle.model, meta=bundle.meta)
    frames = save_frame_model(load_frame_model("frames-body-128").model, tmp_path / "f.safetensors", step=3)
    for path in (motion, frames):
        with safe_open(str(path), framework="pt") as f:
            assert f.metadata()["format_version"] == "1"
    assert load_model(motion).meta.model == "mtvae-add" and load_frame_model(frames).step == 3
