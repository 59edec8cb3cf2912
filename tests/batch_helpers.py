"""Shared pieces of the batch tests: a folder of real clips plus bad inputs, and killing a worker mid-job."""

from __future__ import annotations

import os
import signal
import threading
import time
from pathlib import Path

# Real clips of several sources and formats (CMU, ACRNN, MASS and DeepMimic BVH, a DeepMimic motion file).
# (Exp-map text clips read a skeleton.json from their folder, so they are not linked elsewhere.)
CLIPS = ("cmu/01_01.bvh", "cmu/02_01.bvh", "cmu/02_02.bvh", "cmu/05_01.bvh", "cmu/07_01.bvh",
         "acrnn/salsa_03b.bvh", "mass/mass_kick.bvh", "deepmimic/humanoid3d_walk.bvh",
         "deepmimic-cmu/49_06.txt", "cmu/06_01.bvh")


def clip_folder(mocap_dir: Path, folder: Path) -> Path:
    """``folder`` with links to :data:`CLIPS` (flattened names) and two bad inputs: a text file named
    ``.bvh`` and random bytes named ``.npz``."""
    folder.mkdir(parents=True, exist_ok=True)
    for clip in CLIPS:
        target = mocap_dir / clip
        link = folder / clip.replace("/", "_")
        link.symlink_to(target)
    (folder / "garbage.bvh").write_text("this is not a motion file\n")
    (folder / "noise.npz").write_bytes(os.urandom(2048))
    return folder


def temp_writers(output: Path) -> list[int]:
    """PIDs of processes that hold a temporary file of ``output`` (``.STEM.*.tmpSUFFIX``) open for writing:
    the worker itself when it encodes in-process (PyAV), or its ffmpeg child."""
    prefix = str(output.parent / f".{output.stem}.")
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            targets = [os.readlink(fd) for fd in (entry / "fd").iterdir()]
        except OSError:
            continue
        if any(t.startswith(prefix) and ".tmp" in t for t in targets):
            found.append(int(entry.name))
    return found


def worker_of(writer: int) -> int:
    """The batch worker behind a process writing an output: an ffmpeg encoder's parent, else itself."""
    try:
        argv0 = Path(f"/proc/{writer}/cmdline").read_bytes().split(b"\0")[0]
    except OSError:
        return writer
    return parent_pid(writer) if b"ffmpeg" in Path(argv0.decode(errors="replace")).name.encode() else writer


def parent_pid(pid: int) -> int:
    stat = Path(f"/proc/{pid}/stat").read_text()
    return int(stat.rsplit(")", 1)[1].split()[1])


class WorkerKiller(threading.Thread):
    """Waits until ``output``'s encoder is running with some frames written, then SIGKILLs the worker
    process that writes it (see :func:`worker_of`). ``killed`` holds the worker's pid."""

    def __init__(self, output: Path, *, timeout: float = 300.0, min_bytes: int = 1) -> None:
        super().__init__(daemon=True)
        self.output, self.timeout, self.min_bytes = output, timeout, min_bytes
        self.killed: int | None = None
        self.saw_temp: list[str] = []

    def run(self) -> None:
        end = time.monotonic() + self.timeout
        while time.monotonic() < end and self.killed is None:
            for pid in temp_writers(self.output):
                temps = list(self.output.parent.glob(f".{self.output.stem}.*.tmp{self.output.suffix}"))
                if not temps or temps[0].stat().st_size < self.min_bytes:
                    continue
                worker = worker_of(pid)
                self.saw_temp = [t.name for t in temps]
                os.kill(worker, signal.SIGKILL)
                self.killed = worker
                return
            time.sleep(0.02)
