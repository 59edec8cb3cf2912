"""`motion2video render` as a user runs it: real clips in, real mp4 files read back; bad input gets one line,
exit code 2 and no output file."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.formats.manifest import read_manifest
from motion2video.formats.io import load_motion, resample_motion
from motion2video.apps.render import render_motion
from motion2video.formats.video import probe_frame_rate, read_video

REPO = Path(__file__).resolve().parents[1]


def _run(argv: list[str], capsys) -> tuple[int, str, str]:
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize("style,clip", [
    ("skeleton", "mocap/cmu/08_01.bvh"),
    ("heatmap", "mocap/deepmimic/humanoid3d_walk.bvh"),
    ("mesh", "mocap/mass/mass_kick.bvh"),
    ("face", "face/llv/dao.csv"),
    # The readers beyond BVH: a DeepMimic motion file, an exp-map benchmark file, an acrnn salsa clip.
    ("skeleton", "mocap/deepmimic-cmu/49_06.txt"),
    ("mesh", "mocap/deepmimic/txt/humanoid3d_spinkick.txt"),
    ("skeleton", "mocap/cmu-bench/test/soccer/soccer_1.txt"),
    ("skeleton", "mocap/acrnn/salsa_03b.bvh"),
])
def test_render_each_style_to_a_real_mp4(style, clip, shared_dir, tmp_path, capsys):
    out = tmp_path / f"{style}.mp4"
    code, printed, err = _run(["render", str(shared_dir / "data" / clip), "-o", str(out), "--style", style,
                               "--size", "64", "--fps", "25", "--start", "3", "--frames", "10", "--no-progress"],
                              capsys)
    assert code == 0, err
    frames, fps = read_video(out)
    assert frames.shape == (10, 64, 64, 3)
    assert probe_frame_rate(out) == 25
    assert frames.std() > 2.0  # something was drawn
    assert f"wrote {out}" in printed
    # The video shows the same frames the library renders for that range (within the codec's error).
    motion = resample_motion(load_motion(shared_dir / "data" / clip), 25.0).slice(3, 10)
    expected = render_motion(motion, style=style, size=64)
    assert np.abs(frames.astype(float) - expected).mean() < 6.0


def test_render_gif_keeps_the_clip_rate(tmp_path, capsys):
    out = tmp_path / "walk.gif"
    code, _, err = _run(["render", str(REPO / "demo_inputs" / "walk_to_run.npz"), "-o", str(out), "--size", "48",
                         "--frames", "5", "--no-progress"], capsys)
    assert code == 0, err
    frames, _ = read_video(out)
    assert frames.shape == (5, 48, 48, 3)


def test_help_shows_examples(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["render", "--help"])
    assert exit_info.value.code == 0
    text = capsys.readouterr().out
    assert "examples:" in text and "--style mesh" in text


def test_every_help_example_is_one_command_per_line(capsys):
    """A help example continued onto the next line ends in a backslash; one written with a single backslash in the
    module's string would be joined into one line with a run of spaces inside."""
    from motion2video.cli import COMMANDS

    commands = [name.replace("_", "-") for name in COMMANDS]
    for name in commands:
        with pytest.raises(SystemExit):
            main([name, "--help"])
        text = capsys.readouterr().out
        examples = text.split("examples:", 1)[1].split("\n\n", 1)[0] if "examples:" in text else ""
        for line in examples.splitlines():
            command = line.split(" #")[0].rstrip()  # aligned comments may follow a run of spaces
            assert not re.search(r"\S {4,}\S", command), f"{name} --help joins two example lines: {line!r}"


def _npz(path: Path, **arrays) -> Path:
    np.savez(path, **arrays)
    return path


def _bad_inputs(tmp: Path) -> dict[str, tuple[list[str], str]]:
    """name -> (argv, a phrase the one-line error must contain)."""
    good = str(REPO / "demo_inputs" / "wave.npz")
    walk = np.zeros((4, 17, 3), np.float32)
    nan = walk.copy()
    nan[2, 5, 1] = np.nan
    (tmp / "garbage.bvh").write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 zero 0\n")
    (tmp / "clip.xyz").write_text("1 2 3\n")
    (tmp / "a_file").write_text("not a folder")
    return {
        "missing file": ([str(tmp / "nope.bvh")], "nope.bvh"),
        "unknown input extension": ([str(tmp / "clip.xyz")], "clip.xyz"),
        "NaN joints": ([str(_npz(tmp / "nan.npz", joints=nan, fps=25.0, skeleton="h36m-17"))], "NaN"),
        "Inf joints": ([str(_npz(tmp / "inf.npz", joints=np.where(np.isnan(nan), np.inf, nan), fps=25.0,
                                 skeleton="h36m-17"))], "Inf"),
        "wrong-shaped joints": ([str(_npz(tmp / "shape.npz", joints=np.zeros((4, 17, 5), np.float32), fps=25.0,
                                          skeleton="h36m-17"))], "shape"),
        "empty sequence": ([str(_npz(tmp / "empty.npz", joints=np.zeros((0, 17, 3), np.float32), fps=25.0,
                                     skeleton="h36m-17"))], "empty"),
        "fps 0 in the file": ([str(_npz(tmp / "fps0.npz", joints=walk, fps=0.0, skeleton="h36m-17"))], "fps"),
        "negative --fps": ([good, "--fps", "-5"], "fps"),
        "unparseable BVH": ([str(tmp / "garbage.bvh")], "garbage.bvh"),
        "output folder under a file": ([good, "-o", str(tmp / "a_file" / "no" / "out.mp4")], "a_file is a file"),
        "output folder is a file": ([good, "-o", str(tmp / "a_file" / "out.mp4")], "a_file"),
        "unknown output extension": ([good, "-o", str(tmp / "out.avi")], "extension"),
        "size below 32": ([good, "--size", "16"], "between 32 and 2048"),
        "size above 2048": ([good, "--size", "4096"], "between 32 and 2048"),
        "face style on a body clip": ([good, "--style", "face"], "face motion"),
        "start past the end": ([good, "--start", "100000"], "outside the clip"),
    }


@pytest.mark.parametrize("case", sorted(_bad_inputs(Path("/tmp"))))
def test_bad_input_one_line_exit_2_no_output(case, tmp_path, capsys):
    argv, phrase = _bad_inputs(tmp_path)[case]
    out = tmp_path / "out.mp4"
    if "-o" not in argv:
        argv = [*argv, "-o", str(out)]
    before = set(tmp_path.rglob("*"))
    code, printed, err = _run(["render", *argv, "--no-progress"], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("motion2video render: error:"), err
    assert phrase in lines[0], lines[0]
    assert "Traceback" not in err and printed == ""
    assert set(tmp_path.rglob("*")) == before  # nothing written, not even a temporary file


def test_missing_output_folders_are_created(tmp_path, capsys, mocap_dir):
    out = tmp_path / "no" / "such" / "dir" / "out.mp4"
    code, printed, err = _run(["render", str(mocap_dir / "cmu" / "08_01.bvh"), "--frames", "5", "--size", "48",
                               "-o", str(out), "--no-progress"], capsys)
    assert code == 0, err
    assert out.is_file() and out.stat().st_size > 0
    assert [p.name for p in out.parent.iterdir()] == ["out.mp4"]  # no temporary file left beside it


@pytest.mark.slow
def test_every_mocap_clip_converts_and_renders(mocap_dir):
    """All 275 real clips (every reader): canonical joints, then a skeleton map and the Anny mesh of two frames
    each."""
    entries = read_manifest(mocap_dir / "manifest.csv")
    assert len(entries) == 275
    for name in sorted(entries):
        motion = load_motion(mocap_dir / name)
        assert motion.skeleton == "h36m-17" and motion.num_frames > 10, name
        pair = motion.slice(motion.num_frames // 2, 2)
        for style in ("skeleton", "mesh"):
            frames = render_motion(pair, style=style, size=48)
            assert frames.shape == (2, 48, 48, 3) and frames.std() > 2.0, (name, style)


def _modules_after(code: str) -> list[str]:
    """The command modules and heavy packages loaded by ``code`` in a fresh interpreter."""
    probe = (f"import sys\n{code}\nprint(sorted(m for m in sys.modules if m.startswith('motion2video.commands.') "
             "or m in ('torch', 'cv2', 'renderers')))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, cwd=REPO,
                         env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"})
    return ast.literal_eval(out.stdout.strip().splitlines()[-1])


def test_help_lists_every_command_without_importing_one():
    """The command modules import their applications (torch, OpenCV, the renderers) at their top: `--help` lists
    the commands from the CLI's table, a command line imports its own command's module only."""
    from motion2video.cli import COMMANDS, SUMMARIES

    listing = "from motion2video.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass"
    assert _modules_after(listing) == []
    doctor = "from motion2video.cli import main\ntry:\n    main(['doctor', '--help'])\nexcept SystemExit:\n    pass"
    assert _modules_after(doctor) == ["motion2video.commands.common", "motion2video.commands.doctor"]
    assert {path.stem for path in (REPO / "motion2video" / "commands").glob("*.py")} - {"__init__", "common"} \
        == set(COMMANDS) and len(SUMMARIES) == len(COMMANDS)


def test_a_misspelt_command_is_one_usage_error(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["sampel", "--samples", "3"])
    assert exit_info.value.code == 2
    assert "invalid choice: 'sampel'" in capsys.readouterr().err


def test_render_draws_the_person_of_a_video(dancer_video, tmp_path, capsys, monkeypatch):
    """A video in (the inputs table lists them): the dancer's pose is estimated, cached, and drawn at the video's
    rate; the second run reads the cache. A face style is refused in one line."""
    import cv2

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # the pose cache of this test only
    cap = cv2.VideoCapture(str(dancer_video))
    clip = tmp_path / "dancer12.avi"
    writer = None
    for _ in range(12):
        ok, frame = cap.read()
        assert ok
        if writer is None:
            writer = cv2.VideoWriter(str(clip), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, frame.shape[1::-1])
        writer.write(frame)
    writer.release()
    cap.release()
    out = tmp_path / "dancer.mp4"
    code, printed, err = _run(["render", str(clip), "-o", str(out), "--size", "128"], capsys)
    assert code == 0, err
    assert "12 frames" in printed and "25 fps" in printed
    frames, fps = read_video(out)
    assert frames.shape == (12, 128, 128, 3) and fps == pytest.approx(25.0)
    drawn = (np.abs(frames.astype(int) - frames[:, :1, :1].astype(int)).sum(-1) > 60).mean(axis=(1, 2))
    assert (drawn > 0.005).all()  # a skeleton in every frame
    assert "estimated" in err or "cache" in err
    code, _, err = _run(["render", str(clip), "-o", str(tmp_path / "again.mp4"), "--size", "128"], capsys)
    assert code == 0 and "read from the cache" in err
    code, _, err = _run(["render", str(clip), "-o", str(tmp_path / "face.mp4"), "--style", "face"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "dancer12.avi" in err and "body motion" in err
    assert not (tmp_path / "face.mp4").exists()
