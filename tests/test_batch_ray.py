"""`motion2video batch --engine ray` on a real local Ray instance with 2 CPUs (one per module: Ray starts
slowly on 2 shared cores): real clips, a bad input, and a worker killed mid-job."""

from __future__ import annotations

import json

import pytest
import ray  # the ray extra: `make test` installs it

from motion2video.apps.batch import BatchConfig, init_ray, jobs_from_jsonl, jobs_from_template, run_batch
from motion2video.formats.video import video_frame_count
from motion2video.formats.video import read_video
from tests.batch_helpers import CLIPS, WorkerKiller, clip_folder

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def ray_cluster():
    init_ray(2)
    yield ray
    ray.shutdown()


def test_ray_batch_of_real_clips_with_a_bad_input(ray_cluster, mocap_dir, tmp_path):
    inputs = clip_folder(mocap_dir, tmp_path / "inputs")
    out = tmp_path / "out"
    jobs = jobs_from_template(str(inputs), "render {input} -o {output} --size 64 --frames 20", out)
    summary = run_batch(jobs, BatchConfig(out_dir=out, engine="ray", workers=2, progress=False))
    rows = {r.name: r for r in summary.results}
    assert len(rows) == len(CLIPS) + 2
    ok = [r for r in rows.values() if r.status == "ok"]
    assert len(ok) == len(CLIPS) and all(r.frames == 20 for r in ok)
    assert len({r.worker for r in ok}) >= 2  # both Ray workers did some of it
    for r in ok:
        assert read_video(out / r.output)[0].shape == (20, 64, 64, 3)
    assert rows["garbage.mp4"].status == "failed" and "garbage.bvh" in rows["garbage.mp4"].error
    assert rows["noise.mp4"].status == "failed" and "noise.npz" in rows["noise.mp4"].error
    assert (out / "index.html").is_file() and len((out / "results.jsonl").read_text().splitlines()) == len(rows)
    again = run_batch(jobs, BatchConfig(out_dir=out, engine="ray", workers=2, progress=False))
    assert again.count("skipped") == len(CLIPS) and again.count("failed") == 2


def test_ray_retries_a_killed_worker_and_leaves_no_partial_file(ray_cluster, mocap_dir, tmp_path):
    out = tmp_path / "out"
    jobs_file = tmp_path / "jobs.jsonl"
    jobs_file.write_text("\n".join(json.dumps(j) for j in [
        {"command": "render", "args": [str(mocap_dir / "cmu" / "13_10.bvh"), "--size", "128"], "output": "long.mp4"},
        {"command": "render", "args": [str(mocap_dir / "cmu" / "08_01.bvh"), "--size", "64", "--frames", "20"],
         "output": "short.mp4"},
    ]) + "\n")
    killer = WorkerKiller(out / "long.mp4")
    killer.start()
    summary = run_batch(jobs_from_jsonl(jobs_file, out), BatchConfig(out_dir=out, engine="ray", workers=2,
                                                                     retries=2, progress=False))
    killer.join(timeout=1)
    assert killer.killed is not None and killer.saw_temp
    rows = {r.name: r for r in summary.results}
    assert rows["long.mp4"].status == "ok" and rows["long.mp4"].worker != killer.killed
    assert rows["short.mp4"].status == "ok"
    assert video_frame_count(out / "long.mp4") == 2392
    assert not [p.name for p in out.iterdir() if ".tmp" in p.name]
