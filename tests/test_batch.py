"""`motion2video batch` on the local process pool: real clips, real renders, real mp4s read back, a real
worker killed mid-job, and the gallery opened in Debian's headless chromium."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from motion2video.apps.batch import BatchConfig, jobs_from_jsonl, jobs_from_template, read_results, run_batch
from motion2video.formats.video import video_frame_count
from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.apps.gallery import write_gallery
from motion2video.formats.video import read_video
from tests.batch_helpers import CLIPS, WorkerKiller, clip_folder

TEMPLATE = "render {input} -o {output} --style skeleton --size 64 --frames 24"


@pytest.fixture(scope="module")
def batch_run(mocap_dir, tmp_path_factory):
    """One template batch over the real clips and two bad inputs, 2 local workers (shared by the tests)."""
    root = tmp_path_factory.mktemp("batch")
    inputs = clip_folder(mocap_dir, root / "inputs")
    out = root / "out"
    code = main(["batch", str(inputs), "--template", TEMPLATE, "--out", str(out), "--workers", "2",
                 "--no-progress"])
    return inputs, out, code


def test_batch_renders_every_clip_and_fails_only_the_bad_rows(batch_run, capsys):
    inputs, out, code = batch_run
    assert code == 1  # some jobs failed
    rows = {r.name: r for r in read_results(out / "results.jsonl")}
    assert len(rows) == len(CLIPS) + 2
    for clip in CLIPS:
        row = rows[Path(clip.replace("/", "_")).stem + ".mp4"]
        assert row.status == "ok", row
        assert row.frames == 24 and row.error is None and row.seconds > 0
        frames, _ = read_video(out / row.output)
        assert frames.shape == (24, 64, 64, 3)
    for bad, problem in (("garbage.mp4", "garbage.bvh"), ("noise.mp4", "noise.npz")):
        assert rows[bad].status == "failed" and rows[bad].frames is None
        assert problem in rows[bad].error and "\n" not in rows[bad].error
        assert not (out / bad).exists()
    assert not [p for p in out.iterdir() if ".tmp" in p.name]


def test_rerun_skips_what_is_done_and_force_redoes_it(batch_run, capsys, tmp_path):
    inputs, out, _ = batch_run
    before = {p.name: p.stat().st_mtime_ns for p in out.glob("*.mp4")}
    code = main(["batch", str(inputs), "--template", TEMPLATE, "--out", str(out), "--workers", "2",
                 "--no-progress"])
    assert code == 1
    line = capsys.readouterr().out
    assert f"0 done, {len(CLIPS)} skipped, 2 failed" in line
    rows = read_results(out / "results.jsonl")
    assert sorted(r.status for r in rows) == ["failed"] * 2 + ["skipped"] * len(CLIPS)
    assert {p.name: p.stat().st_mtime_ns for p in out.glob("*.mp4")} == before
    # A truncated output does not count as done (on a copy: the gallery test reads the full batch's folder).
    out = Path(shutil.copytree(out, tmp_path / "copy"))
    victim = out / "cmu_01_01.mp4"
    victim.write_bytes(victim.read_bytes()[:2000])
    assert video_frame_count(victim) is None
    summary = run_batch(jobs_from_template(str(inputs / "cmu_01_01.bvh"), TEMPLATE, out),
                        BatchConfig(out_dir=out, progress=False))
    assert [r.status for r in summary.results] == ["ok"] and video_frame_count(victim) == 24
    summary = run_batch(jobs_from_template(str(inputs / "cmu_0[12]*.bvh"), TEMPLATE, out),
                        BatchConfig(out_dir=out, progress=False, force=True))
    assert [r.status for r in summary.results] == ["ok"] * 3


@pytest.mark.slow
def test_jsonl_jobs_with_list_and_object_args(mocap_dir, tmp_path):
    clip = mocap_dir / "cmu" / "08_01.bvh"
    lines = [
        {"command": "render", "args": [str(clip), "--size", "48", "--frames", "10"], "output": "list.mp4"},
        {"command": "render", "args": {"input": str(clip), "size": 48, "frames": 12, "palette": "openpose"},
         "output": "sub/object.gif"},
        {"command": "render", "args": [str(clip), "--style", "nonsense"], "output": "badarg.mp4"},
        {"command": "render", "args": [str(clip), "--size", "8"], "output": "small.mp4"},
        {"command": "render", "args": [str(clip), "--style", "mesh", "--size", "48", "--frames", "3"],
         "output": "mesh.mp4"},  # the GL context is made in the worker
        {"command": "sample", "args": {"model": "zero-velocity", "input": str(clip), "samples": 2, "horizon": 4,
                                       "size": 48}, "output": "futures.mp4"},
    ]
    jobs_file = tmp_path / "jobs.jsonl"
    jobs_file.write_text("# a comment\n\n" + "\n".join(json.dumps(line) for line in lines) + "\n")
    out = tmp_path / "out"
    summary = run_batch(jobs_from_jsonl(jobs_file, out), BatchConfig(out_dir=out, progress=False))
    rows = {r.name: r for r in summary.results}
    assert rows["list.mp4"].status == "ok" and rows["list.mp4"].frames == 10
    assert rows["sub/object.gif"].status == "ok" and rows["sub/object.gif"].frames == 12
    assert read_video(out / "sub" / "object.gif")[0].shape == (12, 48, 48, 3)
    assert rows["badarg.mp4"].status == "failed" and "invalid choice" in rows["badarg.mp4"].error
    assert rows["small.mp4"].status == "failed" and "between 32 and 2048" in rows["small.mp4"].error
    assert rows["mesh.mp4"].status == "ok" and rows["mesh.mp4"].frames == 3
    assert rows["futures.mp4"].status == "ok" and rows["futures.mp4"].frames > 4
    assert summary.line().startswith("batch: 4 done, 0 skipped, 2 failed of 6 jobs")


@pytest.mark.parametrize("line,problem", [
    ("not json", "not JSON"),
    ('{"command": "explode", "output": "a.mp4"}', "unknown command"),
    ('{"args": []}', "each line needs"),
])
def test_bad_job_file_is_one_line_exit_2(tmp_path, capsys, line, problem):
    jobs_file = tmp_path / "jobs.jsonl"
    jobs_file.write_text(line + "\n")
    assert main(["batch", str(jobs_file), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert problem in err and f"{jobs_file}:1" in err and "\n" not in err


def test_bad_template_and_no_inputs_exit_2(tmp_path, capsys):
    assert main(["batch", str(tmp_path), "--template", TEMPLATE, "--out", str(tmp_path / "o")]) == 2
    assert "no input files found" in capsys.readouterr().err
    (tmp_path / "a.bvh").write_text("x")
    assert main(["batch", str(tmp_path), "--template", "explode {input}", "--out", str(tmp_path / "o")]) == 2
    assert "must start with one of" in capsys.readouterr().err
    with pytest.raises(InputError, match="must use"):
        jobs_from_template(str(tmp_path), "render x.bvh", tmp_path / "o")


@pytest.mark.slow
def test_killed_worker_is_retried_and_leaves_no_partial_file(mocap_dir, tmp_path):
    """SIGKILL the worker process while it encodes a long clip: the job is retried on a new worker and
    succeeds, and no temporary or partial file is left."""
    out = tmp_path / "out"
    long_clip = mocap_dir / "cmu" / "13_10.bvh"  # 2392 frames
    jobs_file = tmp_path / "jobs.jsonl"
    jobs_file.write_text("\n".join(json.dumps(j) for j in [
        {"command": "render", "args": [str(long_clip), "--size", "128"], "output": "long.mp4"},
        {"command": "render", "args": [str(mocap_dir / "cmu" / "08_01.bvh"), "--size", "64", "--frames", "20"],
         "output": "short.mp4"},
    ]) + "\n")
    killer = WorkerKiller(out / "long.mp4", min_bytes=1)
    killer.start()
    summary = run_batch(jobs_from_jsonl(jobs_file, out), BatchConfig(out_dir=out, workers=2, retries=1,
                                                                     progress=False))
    killer.join(timeout=1)
    assert killer.killed is not None and killer.saw_temp  # it really died with a temporary file written
    rows = {r.name: r for r in summary.results}
    assert rows["long.mp4"].status == "ok" and rows["long.mp4"].attempts == 2, rows["long.mp4"]
    assert rows["long.mp4"].worker != killer.killed
    assert rows["short.mp4"].status == "ok"
    assert video_frame_count(out / "long.mp4") == 2392
    assert not [p.name for p in out.iterdir() if ".tmp" in p.name]


def test_killed_worker_without_retries_fails_its_row_only(mocap_dir, tmp_path):
    out = tmp_path / "out"
    jobs_file = tmp_path / "jobs.jsonl"
    jobs_file.write_text(json.dumps({"command": "render", "output": "long.mp4", "args": [
        str(mocap_dir / "cmu" / "13_10.bvh"), "--size", "96"]}) + "\n")
    killer = WorkerKiller(out / "long.mp4")
    killer.start()
    summary = run_batch(jobs_from_jsonl(jobs_file, out), BatchConfig(out_dir=out, retries=0, progress=False))
    killer.join(timeout=1)
    assert killer.killed is not None
    (row,) = summary.results
    assert row.status == "failed" and "died" in row.error
    assert sorted(p.name for p in out.iterdir()) == ["index.html", "results.jsonl"]


# --- the gallery in a real browser --------------------------------------------------------------------

def _chromium() -> str:
    path = shutil.which("chromium") or shutil.which("chromium-browser")
    if path is None:
        pytest.fail("Debian's chromium is needed for the gallery test (make setup-test, which make test runs, installs it: apt-get install chromium)")
    return path


def _open(page_url: str, fn):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=_chromium(), args=["--no-sandbox", "--autoplay-policy=no-user-gesture-required"])
        try:
            page = browser.new_page()
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(page_url)
            return fn(page), errors
        finally:
            browser.close()


VIDEO_STATE = """() => Array.from(document.querySelectorAll('video')).map(v => ({
    src: v.getAttribute('src'), ready: v.readyState, width: v.videoWidth, height: v.videoHeight,
    error: v.error ? v.error.code : null}))"""


def test_gallery_opens_in_headless_chromium_and_plays_every_video(batch_run):
    _, out, _ = batch_run

    def check(page):
        page.wait_for_function("() => Array.from(document.querySelectorAll('video')).every(v => v.readyState >= 2 "
                               "|| v.error)", timeout=60000)
        cells = page.eval_on_selector_all(".cell", "cs => cs.map(c => [c.dataset.name, c.dataset.status, c.innerText])")
        return page.evaluate(VIDEO_STATE), cells, page.inner_text("#summary")

    (videos, cells, summary), errors = _open((out / "index.html").as_uri(), check)
    assert errors == []
    assert summary == f"{len(CLIPS) + 2} jobs: {len(CLIPS)} done, 0 skipped, 2 failed" or "skipped" in summary
    assert len(videos) == len(CLIPS)
    for v in videos:
        assert v["error"] is None and v["ready"] >= 2 and (v["width"], v["height"]) == (64, 64), v
        assert (out / v["src"]).is_file() and not Path(v["src"]).is_absolute()
    failed = {name: text for name, status, text in cells if status == "failed"}
    assert set(failed) == {"garbage.mp4", "noise.mp4"}
    assert "no MOTION section" in failed["garbage.mp4"] or "garbage.bvh" in failed["garbage.mp4"]
    assert "noise.npz" in failed["noise.mp4"]


def test_gallery_pages_a_large_batch(batch_run, tmp_path):
    """120 rows, 50 per page: 3 pages, only the shown page's videos in the document, buttons page."""
    _, out, _ = batch_run
    rows = [r for r in read_results(out / "results.jsonl") if r.status != "failed"]
    many = [dict(vars(rows[i % len(rows)]), name=f"job{i:03d}") for i in range(120)]
    for row in many:
        row["output"] = str(out / row["output"])  # absolute outputs become relative links
    write_gallery(tmp_path, many)

    def check(page):
        first = page.eval_on_selector_all(".cell", "cs => cs.map(c => c.dataset.name)")
        page.click("#pager-top button[data-page='3']")
        third = page.eval_on_selector_all(".cell", "cs => cs.map(c => c.dataset.name)")
        page.wait_for_function("() => Array.from(document.querySelectorAll('video')).every(v => v.readyState >= 2)",
                               timeout=60000)
        return first, third, page.evaluate(VIDEO_STATE), page.evaluate("location.hash")

    (first, third, videos, hash_), errors = _open((tmp_path / "index.html").as_uri(), check)
    assert errors == []
    assert first == [f"job{i:03d}" for i in range(50)]
    assert third == [f"job{i:03d}" for i in range(100, 120)]
    assert len(videos) == 20 and all(v["ready"] >= 2 and v["width"] == 64 for v in videos)
    assert all(v["src"].startswith("../") for v in videos)
    assert hash_ == "#page=3"
