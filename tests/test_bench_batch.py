"""scripts/bench.py batch end to end on a tiny configuration: real pools, real clips, real mp4 files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_bench_batch_writes_its_keys_from_the_frames_it_wrote(tmp_path, shared_dir):
    out = tmp_path / "bench.json"
    run = subprocess.run([sys.executable, str(ROOT / "scripts" / "bench.py"), "batch", "--json", str(out), "--clips", "3",
                          "--frames", "30", "--repeats", "1", "--no-ray", "--mesh-clips", "1", "--mesh-frames", "3"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    record = json.loads(out.read_text())
    assert record["workers2_vs_1"] > 0 and record["ray_vs_local"] is None
    assert set(record["encoders"]) == {"pyav", "ffmpeg"}
    assert record["encoders"]["pyav"]["workers2_vs_1"] == record["workers2_vs_1"]
    # every job rendered the frames asked for: the clips are chosen long enough, and the rates count them
    assert record["frames_written"] == {name: 3 * 30 for name in ("local1", "local2", "local1_ffmpeg", "local2_ffmpeg")}
    for clip in record["config"]["clip_files"]:
        assert (shared_dir / "data" / "mocap" / clip).is_file()
    capacity = record["capacity"]
    assert capacity["skeleton_video_s_per_core_s"] > 0 and capacity["core_hours_10000_clips_10s_mesh_256"] > 0
