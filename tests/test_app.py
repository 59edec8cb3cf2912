"""`motion2video app` in a real browser: the CLI serves the page, headless Chromium (Debian's, through Playwright)
uploads a photo and a real BVH clip, presses Animate, waits for the futures to play, downloads the files and reads
them back with the project's readers; a video too long and a photo with nobody in it show the CLI's one-line
message, and the app keeps serving; the behaviour transfer tab plays and downloads likewise."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video import load_motion, read_video

REPO = Path(__file__).resolve().parents[1]
FUTURE_FRAMES = 8
OBSERVED = 16  # mtvae-add's observed window


def _chromium() -> str:
    path = shutil.which("chromium") or shutil.which("chromium-browser")
    if path is None:
        pytest.fail("Debian's chromium is needed for the app test (make setup-test, which make test runs, installs it: "
                    "apt-get install chromium)")
    return path


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def app_url(tmp_path_factory):
    """The app served by the CLI on a free port with the fastest models (mtvae-add, frames-body-128), one future of
    8 frames; its address as printed."""
    work = tmp_path_factory.mktemp("app-work")
    env = {**os.environ, "PYTHONPATH": str(REPO), "PYOPENGL_PLATFORM": "osmesa"}
    command = [sys.executable, "-m", "motion2video.cli", "app", "--port", str(_free_port()), "--motion-model",
               "mtvae-add", "--frame-model", "frames-body-128", "--samples", "1", "--horizon", str(FUTURE_FRAMES),
               "--work-dir", str(work)]
    proc = subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        line, deadline = "", time.monotonic() + 120
        while "serving on" not in line and time.monotonic() < deadline and proc.poll() is None:
            line = proc.stdout.readline()
        if "serving on" not in line:
            pytest.fail(f"the app did not start: {line!r} (exit code {proc.poll()})")
        url = line.split("serving on ")[1].split()[0]
        assert url.startswith("http://127.0.0.1:")  # the local address by default
        yield url
    finally:
        proc.terminate()  # SIGTERM: the CLI stops like Ctrl-C
        assert proc.wait(timeout=30) == 143


def _status(page, selector: str, text: str) -> str:
    """The status line once the run is over and it names ``text``."""
    page.wait_for_function("([s, t]) => { const e = document.querySelector(s); "
                           "return e && e.innerText.includes(t) && !e.innerText.includes('processing') }",
                           arg=[selector, text], timeout=120_000)
    return page.inner_text(selector).strip()


def _file_shown(page, selector: str, name: str, shown: bool = True) -> None:
    """Wait until a file box (``selector``) shows the uploaded file ``name`` (or, with ``shown=False``, no longer
    shows it). The box writes the name's stem and extension in separate elements, so its text is read whole."""
    page.wait_for_function("([s, n, shown]) => { const e = document.querySelector(s); "
                           "return !!e && e.textContent.replace(/\\s/g, '').includes(n) === shown }",
                           arg=[selector, name, shown], timeout=180_000)


def _downloads(page, folder: Path, selector: str) -> dict[str, Path]:
    """Click every download link of a downloads list (``selector``) and save what the browser receives."""
    folder.mkdir()
    files = {}
    for link in page.locator(f"{selector} a[download]").all():
        with page.expect_download() as info:
            link.click()
        download = info.value
        files[download.suggested_filename] = folder / download.suggested_filename
        download.save_as(files[download.suggested_filename])
    return files


def test_app_animates_a_photo_and_keeps_serving_after_bad_input(app_url, shared_dir, tmp_path):
    from playwright.sync_api import sync_playwright

    wall = tmp_path / "wall.png"
    cv2.imwrite(str(wall), np.full((240, 180, 3), 200, np.uint8))  # a photo with nobody in it
    photo = shared_dir / "data" / "photos" / "woman_blue_tracksuit.jpg"
    clip = shared_dir / "data" / "mocap" / "mass" / "mass_walk.bvh"  # 1.1 s of real capture at 120 fps
    long_video = shared_dir / "data" / "video" / "dancer.avi"  # 62.9 s, over the app's 30 s

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=_chromium(),
                                    args=["--no-sandbox", "--autoplay-policy=no-user-gesture-required"])
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 1000}, accept_downloads=True)
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(app_url)
            page.wait_for_selector("#animate")
            page.locator("#clip input[type=file]").set_input_files(long_video)
            _file_shown(page, "#clip", "dancer.avi")
            page.click("#animate")  # with the demo photo
            too_long = _status(page, "#status", "dancer.avi")
            page.click("#clip button[aria-label=Clear]")
            # the cleared box re-renders its upload area: give the file to the new input, not the one going away
            _file_shown(page, "#clip", "dancer.avi", shown=False)
            page.wait_for_selector("#clip input[type=file]", state="attached", timeout=60_000)

            page.locator("#clip input[type=file]").set_input_files(clip)
            _file_shown(page, "#clip", "mass_walk.bvh")
            page.locator("#photo input[type=file]").set_input_files(wall)
            page.wait_for_selector("#photo img", timeout=180_000)

            page.click("#animate")
            message = _status(page, "#status", "wall.png")
            assert message.startswith("motion2video synthesize: error:") and "wall.png" in message
            assert "no person found" in message and "\n" not in message  # the CLI's one line

            page.locator("#photo input[type=file]").set_input_files(photo)  # the app still serves: a real photo now
            page.click("#animate")
            page.wait_for_function("""() => { const v = document.querySelector('#futures video');
                const s = document.querySelector('#structure video');
                return v && v.readyState >= 2 && v.currentTime > 0 && !v.paused && s && s.readyState >= 2 }""",
                                   timeout=180_000)
            structure = page.evaluate("() => { const v = document.querySelector('#structure video'); "
                                      "return v ? [v.readyState, v.videoWidth, v.videoHeight] : null }")
            status = page.inner_text("#status")
            page.screenshot(path=tmp_path / "app.png", full_page=True)
            files = _downloads(page, tmp_path / "downloads", "#downloads")

            page.get_by_role("tab", name="Behaviour transfer").click()  # bundled walk re-enacts the bundled jump
            page.locator("#transfer-style label", has_text="skeleton").click()
            page.locator("#transfer-adapt input").uncheck()
            page.click("#transfer")
            page.wait_for_function("""() => { const v = document.querySelector('#transfer-video video');
                return v && v.readyState >= 2 && v.currentTime > 0 }""", timeout=180_000)
            transfer_status = page.inner_text("#transfer-status")
            transfer_files = _downloads(page, tmp_path / "transfer", "#transfer-downloads")
            assert errors == []
        finally:
            browser.close()

    assert too_long.startswith("motion2video synthesize: error:") and too_long.endswith(
        "dancer.avi: the video is 62.9 s long; at most 30 s is taken")
    assert f"1 future of {FUTURE_FRAMES} frames after {OBSERVED} observed" in status
    assert structure is not None and structure[0] >= 2 and structure[1:] == [128, 128]  # one cell
    assert sorted(files) == ["future_1.bvh", "future_1.npz", "futures-structure.mp4", "futures.mp4"]
    frames, fps = read_video(files["futures.mp4"])
    assert frames.shape == (OBSERVED + FUTURE_FRAMES, 128, 128, 3) and fps == pytest.approx(25.0)
    assert frames[:, 20:110, 20:110].std() > 10  # a person on a background, not a blank picture
    structure_frames, _ = read_video(files["futures-structure.mp4"])
    assert structure_frames.shape == frames.shape
    future = load_motion(files["future_1.npz"])
    assert future.skeleton == "h36m-17" and future.joints.shape == (OBSERVED + FUTURE_FRAMES, 17, 3)
    assert future.fps == 25.0 and np.isfinite(future.joints).all()
    bvh = load_motion(files["future_1.bvh"])
    assert bvh.skeleton == "h36m-17" and bvh.num_frames == OBSERVED + FUTURE_FRAMES
    # the BVH holds the same motion, up to its rig's fit: the pelvis path within a centimetre
    pelvis = bvh.joints[:, 0] - bvh.joints[0, 0]
    np.testing.assert_allclose(pelvis, future.joints[:, 0] - future.joints[0, 0], atol=0.01)

    assert transfer_status.startswith(f"the behaviour re-enacted for {FUTURE_FRAMES} frames")
    assert sorted(transfer_files) == ["reenacted.npz", "reenacted_1.bvh", "transfer.mp4"]
    side_by_side, _ = read_video(transfer_files["transfer.mp4"])
    assert side_by_side.shape[0] == 1 + FUTURE_FRAMES and side_by_side.shape[2] > side_by_side.shape[1]  # two cells
    reenacted = load_motion(transfer_files["reenacted.npz"])
    assert reenacted.joints.shape == (1 + FUTURE_FRAMES, 17, 3)
    assert load_motion(transfer_files["reenacted_1.bvh"]).num_frames == 1 + FUTURE_FRAMES


def test_the_cli_lists_app_without_importing_gradio():
    code = ("import sys; from motion2video.cli import build_parser; "
            "build_parser().parse_args(['app', '--port', '0']); print('gradio' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO,
                         env={**os.environ, "PYTHONPATH": str(REPO)})
    assert out.stdout.strip() == "False", out.stdout + out.stderr


def test_bad_app_options_give_one_line_and_exit_2(capsys):
    from motion2video.cli import main

    assert main(["app", "--port", "70000"]) == 2
    assert capsys.readouterr().err.strip() == "motion2video app: error: --port must be in 0..65535, got 70000"
    assert main(["app", "--samples", "0"]) == 2
    assert "--samples must be >= 1, got 0" in capsys.readouterr().err


def test_cancel_stops_a_run_at_its_next_step_and_leaves_no_file(tmp_path):
    """The page's Cancel (``App.stop``) pressed while the frames are generated: the API's next progress report
    raises, the handler says so and the run leaves nothing in the work folder."""
    from motion2video.apps.web import App, AppSettings

    app = App(AppSettings(work_dir=tmp_path))
    seen = []

    def bar(fraction, desc=None):  # Gradio's progress bar, pressing Cancel once the frames start
        seen.append(desc)
        if desc == "frames":
            app.stop()

    clip, photo = REPO / "demo_inputs" / "cmu_walk.npz", REPO / "demo_inputs" / "reference_body_128.png"
    outputs = app.animate(None, photo.name, None, clip.name, "mtvae-add", "frames-body-128", 1, 40, 0, False, False,
                          bar=bar)
    assert outputs == (None, None, None, "cancelled")
    assert seen == ["loading", "sampling", "structures", "frames"]
    assert list(tmp_path.iterdir()) == []

    video, structure, files, status = app.animate(None, photo.name, None, clip.name, "mtvae-add", "frames-body-128",
                                                  1, 4, 0, False, False, bar=lambda fraction, desc=None: None)
    assert status.startswith("1 future of 4 frames") and Path(video).is_file() and len(files) == 4
