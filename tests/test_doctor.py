"""`motion2video doctor` and the one-line message for a missing GL library.

A machine without Debian's libosmesa6 is emulated at the dynamic-loader boundary: a ``sitecustomize`` module on
the child processes' PYTHONPATH makes every ``ctypes.CDLL`` load of libOSMesa fail with the OSError the loader
raises for a missing file. Everything above it (PyOpenGL, pyrender, the renderers, the CLI, doctor's own child
processes) runs for real."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

NO_OSMESA = '''
import ctypes

_real_init = ctypes.CDLL.__init__


def _init(self, name, *args, **kwargs):
    if name and "OSMesa" in str(name):
        raise OSError(f"{name}: cannot open shared object file: No such file or directory")
    _real_init(self, name, *args, **kwargs)


ctypes.CDLL.__init__ = _init
'''


def _cli(argv: list[str], cwd: Path, *, without_osmesa: bool) -> subprocess.CompletedProcess:
    paths = [str(REPO)]
    if without_osmesa:
        site = cwd / "no_osmesa"
        site.mkdir(exist_ok=True)
        (site / "sitecustomize.py").write_text(NO_OSMESA)
        paths.insert(0, str(site))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(paths), "TQDM_DISABLE": "1", "PYOPENGL_PLATFORM": "osmesa"}
    return subprocess.run([sys.executable, "-m", "motion2video.cli", *argv], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)


@pytest.mark.slow
def test_doctor_on_this_machine(tmp_path):
    run = _cli(["doctor", "--json", str(tmp_path / "doctor.json")], tmp_path, without_osmesa=False)
    assert run.returncode == 0, run.stdout + run.stderr
    out = run.stdout
    for line in ("ok      torch:", "ok      ffmpeg:", "ok      PyAV:", "ok      GL osmesa (libOSMesa): renders",
                 "ok      Anny body model:", "ok      pose estimator (BlazePose):", "ok      checkpoint mtvae-add: loads",
                 "ok      checkpoint frames-body-128",
                 "mesh and face styles: available"):
        assert line in out, out
    assert (tmp_path / "doctor.json").is_file()


@pytest.mark.slow
def test_missing_osmesa_is_one_line_naming_the_package(tmp_path, mocap_dir):
    clip = str(mocap_dir / "cmu" / "08_01.bvh")
    out = tmp_path / "mesh.mp4"
    run = _cli(["render", clip, "--style", "mesh", "--frames", "3", "--size", "48", "-o", str(out), "--no-progress"],
               tmp_path, without_osmesa=True)
    lines = [line for line in run.stderr.splitlines() if line.strip()]
    assert run.returncode == 2, run.stderr
    assert len(lines) == 1 and "Traceback" not in run.stderr, run.stderr
    for phrase in ("libOSMesa", "sudo apt-get install libosmesa6", "--style skeleton", "heatmap"):
        assert phrase in lines[0], lines[0]
    assert not out.exists()
    # Styles without GL still work on that machine.
    run = _cli(["render", clip, "--style", "skeleton", "--frames", "3", "--size", "48", "-o", str(out),
                "--no-progress"], tmp_path, without_osmesa=True)
    assert run.returncode == 0 and out.is_file(), run.stderr


@pytest.mark.slow
def test_doctor_without_osmesa_says_what_to_install(tmp_path):
    run = _cli(["doctor"], tmp_path, without_osmesa=True)
    out = run.stdout
    assert run.returncode == 0, out + run.stderr  # GL is not essential: skeleton and heatmap need none
    assert "MISSING GL osmesa (libOSMesa): libOSMesa is not installed" in out, out
    assert "fix: the mesh and face styles need the OSMesa library" in out and "apt-get install libosmesa6" in out
    assert "ok      GL egl (libEGL): renders" in out  # the other backend is probed on its own
