"""SIGINT / SIGTERM in the middle of real work: one line, exit 130 / 143, no file at the output path
and no temporary file left behind. Every test starts the real command in a subprocess, waits until it is
writing, then signals it: SIGINT to its process group (what Ctrl-C in a terminal does), SIGTERM to the process
alone (what `kill PID` and schedulers do)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from motion2video.formats.io import load_motion
from motion2video.formats.video import video_frame_count

REPO = Path(__file__).resolve().parents[1]
DEMO = REPO / "demo_inputs"


def _temporaries(folder: Path) -> list[Path]:
    """Files the atomic writers use before the rename (``.NAME.*.tmp.EXT`` / ``.NAME.*.partial.EXT``)."""
    return [p for p in folder.rglob(".*") if p.is_file() and (".tmp" in p.name or ".partial" in p.name)]


def _as_in_a_terminal() -> None:
    """In the child: SIGINT as a terminal's foreground job gets it. A test runner started in the background of
    a non-interactive shell (CI, `make test &`) passes SIGINT on as ignored, and Python then never raises
    KeyboardInterrupt."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(argv: list[str], cwd: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO), "TQDM_DISABLE": "1"}
    return subprocess.Popen([sys.executable, "-m", "motion2video.cli", *argv], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=_as_in_a_terminal)


def _wait_until(proc: subprocess.Popen, ready, timeout: float = 240.0) -> None:
    end = time.monotonic() + timeout
    while not ready():
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"the command ended before it was interrupted (exit {proc.returncode}): {err[-2000:]}")
        if time.monotonic() > end:
            proc.kill()
            pytest.fail("the command never started writing")
        time.sleep(0.05)


def _interrupt(proc: subprocess.Popen, sig: int) -> tuple[int, str, str]:
    if sig == signal.SIGINT:
        os.killpg(proc.pid, sig)  # Ctrl-C: the whole group (the command and its ffmpeg / workers)
    else:
        os.kill(proc.pid, sig)
    try:
        out, err = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("the command did not stop after the signal")
    return proc.returncode, out, err


def _check_stopped(code: int, err: str, sig: int, command: str) -> None:
    expected = 130 if sig == signal.SIGINT else 143
    lines = [line for line in err.strip().splitlines() if line.strip()]
    assert code == expected, (code, err[-2000:])
    assert len(lines) == 1 and lines[0].startswith(f"motion2video {command}: "), err[-2000:]
    assert ("interrupted" if sig == signal.SIGINT else "terminated") in lines[0]
    assert "Traceback" not in err


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_long_mesh_render(sig, tmp_path, mocap_dir):
    out = tmp_path / "out" / "long.mp4"
    proc = _start(["render", str(mocap_dir / "cmu" / "13_10.bvh"), "--style", "mesh", "--size", "96",
                   "-o", str(out), "--no-progress"], tmp_path)
    # Encoding has begun: the temporary video beside the output holds frames.
    _wait_until(proc, lambda: any(p.stat().st_size > 0 for p in _temporaries(tmp_path)))
    code, _, err = _interrupt(proc, sig)
    _check_stopped(code, err, sig, "render")
    assert not out.exists() and _temporaries(tmp_path) == []


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_synthesize(sig, tmp_path):
    out = tmp_path / "futures.mp4"
    proc = _start(["synthesize", "--motion-model", "mtvae-add", "--frame-model", "frames-body-128",
                   str(DEMO / "walk_to_run.npz"), "--reference", str(DEMO / "reference_body_128.png"),
                   "--samples", "5", "--horizon", "400", "-o", str(out)], tmp_path)
    _wait_until(proc, lambda: any(p.stat().st_size > 0 for p in _temporaries(tmp_path)))
    code, _, err = _interrupt(proc, sig)
    _check_stopped(code, err, sig, "synthesize")
    assert not out.exists() and not (tmp_path / "futures-structure.mp4").exists()
    assert not (tmp_path / "futures-sheet.png").exists() and _temporaries(tmp_path) == []


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_train(sig, tmp_path, mocap_dir):
    out = tmp_path / "run.safetensors"
    config = '{"model": {"hidden_dim": 16, "latent_dim": 4}, "train": {"batch_size": 8, "checkpoint_every": 3}}'
    proc = _start(["train", "--model", "cvae", "--data", str(mocap_dir / "cmu"), "-o", str(out), "--steps", "100000",
                   "--config", config, "--no-progress", "--threads", "1"], tmp_path)
    _wait_until(proc, lambda: (tmp_path / "run.last.safetensors").exists())  # training steps are running
    code, _, err = _interrupt(proc, sig)
    _check_stopped(code, err, sig, "train")
    assert not out.exists() and _temporaries(tmp_path) == []
    # The periodic checkpoint (written atomically) is what --resume continues from.
    assert (tmp_path / "run.last.safetensors").stat().st_size > 0


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_batch(sig, tmp_path, mocap_dir):
    out_dir = tmp_path / "out"
    proc = _start(["batch", str(mocap_dir / "cmu" / "0[1-9]_0*.bvh"), "--out", str(out_dir), "--workers", "2",
                   "--template", "render {input} -o {output} --style mesh --size 64 --frames 400", "--no-progress"],
                  tmp_path)
    _wait_until(proc, lambda: any(p.stat().st_size > 0 for p in _temporaries(tmp_path)))
    code, _, err = _interrupt(proc, sig)
    _check_stopped(code, err, sig, "batch")
    assert _temporaries(tmp_path) == []
    assert not (out_dir / "results.jsonl").exists()
    # A job that finished before the signal is whole, no partial video: whole is the clip's own length capped at
    # --frames (02_01 has 339 frames at 120 fps, 01_01 2,752).
    for video in out_dir.glob("*.mp4"):
        whole = min(400, load_motion(mocap_dir / "cmu" / f"{video.stem}.bvh").num_frames)
        assert video_frame_count(video) == whole, (video, whole)


def test_an_interrupt_swallowed_by_a_finaliser_is_delivered_again():
    """SIGTERM landing inside a ``__del__`` (here raised from one, as the signal handler would) is not lost: it is
    sent again and stops the code at the next ordinary line (the race that once let a terminated render finish)."""
    from motion2video.cli import Terminated, install_signal_handlers
    from motion2video.core import interrupts

    class Freed:
        def __del__(self):
            raise Terminated()

    old_handler, old_hook = signal.getsignal(signal.SIGTERM), sys.unraisablehook
    try:
        install_signal_handlers()
        with pytest.raises(Terminated):
            Freed()  # dropped at once: its __del__ raises inside the finaliser
            for _ in range(1000):  # the re-sent signal is handled at one of these lines
                time.sleep(0.001)
    finally:
        signal.signal(signal.SIGTERM, old_handler)
        sys.unraisablehook = old_hook
        interrupts.clear()  # what main does once the interrupt has stopped the command


def _dropped_by_a_finaliser() -> None:
    """What the CLI's handler records before it raises, the KeyboardInterrupt then lost in a ``__del__``."""
    from motion2video.core import interrupts

    interrupts.note(KeyboardInterrupt)


def _dropped_by_a_library() -> None:
    """The CLI's SIGINT handler raising inside a library's bare ``except:``, which drops it without a word (no
    finaliser, so no unraisable hook and no re-sent signal)."""
    from motion2video import cli

    try:
        cli._raise_interrupted(signal.SIGINT, None)
    except BaseException:  # noqa: BLE001 - what the library does
        pass


@pytest.mark.parametrize("drop", [_dropped_by_a_finaliser, _dropped_by_a_library], ids=["finaliser", "library"])
def test_a_dropped_interrupt_stops_the_next_video_chunk(drop, tmp_path):
    """A Ctrl-C dropped on its way stays recorded: the video writer raises it at its next chunk, and neither the
    video nor its temporary file is left; it counts as raised again, so the re-sent signal a finaliser's drop
    started is not sent any more. Without the record, a command whose interrupt a library dropped ran on to the
    end and exited 0 (a SIGINT'd mesh render, under load)."""
    from motion2video.core import interrupts
    from motion2video.formats.video import VideoWriter

    out = tmp_path / "clip.mp4"
    frames = np.zeros((4, 32, 32, 3), np.uint8)
    try:
        with pytest.raises(KeyboardInterrupt):
            with VideoWriter(out, 25) as writer:
                writer.write(frames)
                drop()
                dropped_at = interrupts.raised()
                writer.write(frames)  # raised here
                pytest.fail("the second chunk was encoded after the interrupt")
        assert interrupts.raised() == dropped_at + 1
    finally:
        interrupts.clear()
    assert not out.exists() and _temporaries(tmp_path) == []


def test_an_interrupt_sent_again_after_the_command_ended_is_not_sent():
    """The re-sent signal of a swallowed interrupt is not sent when an interrupt was raised since (at a chunk, or
    by another signal), when nothing is pending, or after ``main`` has its exit code: at interpreter exit it would
    kill the process with the signal (exit -2 instead of 130)."""
    from motion2video import cli
    from motion2video.core import interrupts

    old_sigint, old_sigterm, old_hook = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM), \
        sys.unraisablehook
    try:
        cli.install_signal_handlers()
        interrupts.note(KeyboardInterrupt)
        dropped_at = interrupts.raised()
        cli._finished.set()
        cli._send_again(signal.SIGINT, dropped_at)  # a SIGINT here would raise KeyboardInterrupt in this test
        cli._finished.clear()
        interrupts.note(KeyboardInterrupt)  # raised again since
        cli._send_again(signal.SIGINT, dropped_at)
        interrupts.clear()
        cli._send_again(signal.SIGINT, interrupts.raised())  # nothing pending
        for _ in range(100):
            time.sleep(0.001)
    finally:
        signal.signal(signal.SIGINT, old_sigint)
        signal.signal(signal.SIGTERM, old_sigterm)
        sys.unraisablehook = old_hook
        interrupts.clear()


def test_a_ctrl_c_while_the_encoder_starts_leaves_no_encoder_and_no_file(tmp_path, monkeypatch):
    """In this process, no subprocess around it: a SIGINT that arrives just after the encoder process started,
    before the writer had stored it, is held back until the writer has it. The writer then stops the encoder and
    removes its temporary file. Without the hold, the encoder was left running, unknown to the writer, and wrote
    the temporary file once its input closed (a ``.tmp.mp4`` a clean-clone ``make test`` left once)."""
    import gc

    from motion2video.formats import video

    started = []
    real_init = video._FFmpegProcess.__init__

    def init_then_ctrl_c(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        started.append(self._proc)
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C now: the writer has not stored this encoder yet

    monkeypatch.setattr(video._FFmpegProcess, "__init__", init_then_ctrl_c)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal (CI may ignore it)
    try:
        with pytest.raises(KeyboardInterrupt):
            with video.VideoWriter(tmp_path / "out.mp4", 25, encoder="ffmpeg") as writer:
                for _ in range(20):
                    writer.write(np.zeros((4, 32, 32, 3), np.uint8))
    finally:
        signal.signal(signal.SIGINT, previous)
    gc.collect()  # an encoder nobody holds sees its input close here
    assert len(started) == 1
    try:
        code = started[0].wait(timeout=30)
    except subprocess.TimeoutExpired:
        started[0].kill()
        pytest.fail("the encoder was left running, unknown to the writer")
    assert code == -signal.SIGKILL  # stopped by the writer (VideoWriter's close), not ended by its input
    assert sorted(tmp_path.iterdir()) == []


def test_a_ctrl_c_taken_by_another_thread_is_held_too():
    """The kernel may hand a Ctrl-C to any thread that does not block it (a process with helper threads); Python
    still raises it in the main thread. Inside the hold it is kept until the block ends, then raised."""
    import threading

    from motion2video.formats import video

    stop = threading.Event()
    helper = threading.Thread(target=stop.wait, daemon=True)
    helper.start()  # started before the hold: SIGINT is not blocked in it
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal (CI may ignore it)
    reached = False
    try:
        with pytest.raises(KeyboardInterrupt):
            with video._interrupts_held():
                signal.pthread_kill(helper.ident, signal.SIGINT)
                time.sleep(0.2)  # without the hold, the KeyboardInterrupt is raised in here
                reached = True
    finally:
        signal.signal(signal.SIGINT, previous)
        stop.set()
    assert reached
    assert signal.getsignal(signal.SIGINT) is previous
