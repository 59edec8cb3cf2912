"""Personalisation: `train-frames --video V --init-from frames-body-128` fine-tunes the shipped warp
generator on the first 80% of a real video and scores it and the generic model on the tail by the reconstruction
protocol; `evaluate-frames --video-start-fraction` scores any model on that tail; the video's track is cached."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.cli import main
from motion2video.generator.checkpoint import load_frame_model
from tests.test_pose import _cut_video


@pytest.fixture(autouse=True)
def private_cache(tmp_path_factory, monkeypatch):
    """Track and pose caches go to a temporary folder, not the user's ~/.cache."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.fixture(scope="module")
def dancer30(dancer_video, tmp_path_factory) -> Path:
    return _cut_video(dancer_video, tmp_path_factory.mktemp("clip") / "dancer30.avi", 30)


@pytest.mark.slow
def test_train_frames_video_fine_tunes_and_scores_the_tail(dancer30, tmp_path, capsys):
    out, report = tmp_path / "dancer.safetensors", tmp_path / "dancer.json"
    assert main(["train-frames", "--video", str(dancer30), "--init-from", "frames-body-128", "-o", str(out),
                 "--steps", "2", "--video-frames", "3", "--json", str(report), "--threads", "1",
                 "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "personalised / generic L1" in printed and "generic frames-body-128" in printed
    payload = json.loads(report.read_text())
    p, g = payload["personalised"], payload["generic"]
    for scores in (p, g):
        assert 0 < scores["l1"] < 1 and scores["person_psnr"] > 0 and scores["akd"] is not None
    assert payload["l1_ratio"] == pytest.approx(p["l1"] / g["l1"], abs=1e-3)
    # 80% of 30 frames trained on (0..23), the tail's 3 targets scored against frame 0
    assert payload["train"]["frames"] == 24 and payload["train"]["last_frame"] == 23
    assert payload["train"]["tail_start"] == 24 and payload["tail"]["frames"] == [0, 28]
    assert set(payload["tail"]["results"]) == {"generator", "frames-body-128", "copy-reference", "limb-warp"}
    # the fine-tune keeps the shipped model's architecture (bicubic sampling, net scale) and records the video
    tuned, shipped = load_frame_model(out), load_frame_model("frames-body-128")
    assert tuned.kind == "warp" and tuned.config == shipped.config and tuned.step == 2
    # evaluate-frames --video-start-fraction 0.8 is the same protocol on the same tail: the same numbers
    again = tmp_path / "tail.json"
    assert main(["evaluate-frames", "--model", str(out), "--video", str(dancer30), "--video-frames", "3",
                 "--video-start-fraction", "0.8", "--baseline-model", "frames-body-128", "--json", str(again)]) == 0
    tail = json.loads(again.read_text())
    assert tail["frames"] == [0, 28] and tail["start_fraction"] == 0.8
    assert tail["results"]["generator"]["l1"] == p["l1"] and tail["results"]["frames-body-128"]["l1"] == g["l1"]
    assert tail["results"]["generator"]["person_psnr"] == p["person_psnr"]


def _write_video(path: Path, frames: list[np.ndarray], fps: float = 25.0) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (frames[0].shape[1], frames[0].shape[0]))
    for frame in frames:
        writer.write(frame)
    writer.release()
    return path


@pytest.mark.slow
def test_bad_videos_are_one_line_and_nothing_is_written(dancer_video, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    junk = tmp_path / "junk.avi"
    junk.write_text("not a video")
    short = _cut_video(dancer_video, tmp_path / "short.avi", 6)
    empty = _write_video(tmp_path / "empty.avi", [np.full((240, 320, 3), 128, np.uint8)] * 12)
    cases = [
        (tmp_path / "missing.avi", "no such video file"),
        (junk, "cannot read the video"),
        (short, "too short: 6 frames"),
        (empty, "no person"),
    ]
    for video, message in cases:
        argv = ["train-frames", "--video", str(video), "--init-from", "frames-body-128", "-o",
                str(out / "x.safetensors"), "--steps", "1", "--json", str(out / "x.json"), "--no-progress"]
        assert main(argv) == 2, video
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err
    # options that mean nothing on a video, and a fine-tune with no model to start from
    assert main(["train-frames", "--video", str(short), "-o", str(out / "x.safetensors")]) == 2
    assert "--init-from" in capsys.readouterr().err
    assert main(["train-frames", "--video", str(short), "--init-from", "frames-body-128", "--model-kind", "analogy",
                 "-o", str(out / "x.safetensors")]) == 2
    assert "leave out --model-kind" in capsys.readouterr().err
    assert main(["train-frames", "--domain", "body", "--json", str(out / "x.json"), "-o",
                 str(out / "x.safetensors")]) == 2
    assert main(["evaluate-frames", "--model", "frames-body-128", "--video", str(short),
                 "--video-start-fraction", "1.5"]) == 2
    assert list(out.iterdir()) == []
