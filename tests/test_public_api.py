"""The public API of ``import motion2video``: the names, their homes, a cheap package import, and a tiny motion
through save -> load -> render (render_motion and the streaming iter_frames) -> write_video -> read back."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import motion2video
from motion2video import InputError, Motion, iter_frames, load_motion, render_motion, save_motion, write_video
from motion2video.core.errors import InputError as CoreInputError
from motion2video.core.motion import Motion as CoreMotion
from motion2video.formats.io import load_motion as io_load_motion
from motion2video.formats.video import read_video
from motion2video.testing.golden import synthetic_walk

REPO = Path(__file__).resolve().parents[1]


def test_public_names_are_the_defining_modules_objects():
    # one name per thing: the package's names are the very objects of the modules that define them
    assert Motion is CoreMotion and InputError is CoreInputError and load_motion is io_load_motion
    for name in ("load_motion", "save_motion", "render_motion", "iter_frames", "write_video", "Motion",
                 "InputError"):
        assert name in motion2video.__all__ and name in dir(motion2video)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        motion2video.nope  # noqa: B018


def test_package_import_loads_no_heavy_module():
    code = ("import sys, motion2video; heavy = [m for m in ('torch', 'cv2', 'av', 'renderers', 'pyrender') "
            "if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=REPO, env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"})
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_round_trip_and_render_two_frames(tmp_path):
    walk = synthetic_walk(2, fps=25.0)  # (2, 17, 3)
    path = save_motion(walk, tmp_path / "walk.npz")
    motion = load_motion(path)
    assert isinstance(motion, Motion) and motion.fps == 25.0 and motion.skeleton == "h36m-17"
    np.testing.assert_array_equal(motion.joints, walk.joints)

    frames = render_motion(motion, style="skeleton", size=64)
    assert frames.shape == (2, 64, 64, 3) and frames.dtype == np.uint8 and frames.any()
    streamed = np.concatenate(list(iter_frames(motion, style="skeleton", size=64)))
    np.testing.assert_array_equal(streamed, frames)

    video = write_video(tmp_path / "walk.mp4", iter_frames(motion, style="skeleton", size=64), motion.fps)
    back, fps = read_video(video)
    assert back.shape == (2, 64, 64, 3) and fps == pytest.approx(25.0)
    error = np.abs(back.astype(np.int16) - frames).mean(axis=(1, 2, 3))  # (2,) per frame
    swapped = np.abs(back.astype(np.int16) - frames[::-1]).mean(axis=(1, 2, 3))
    assert np.all(error < 4.0) and np.all(error < swapped)  # H.264 at crf 18: each frame is its own drawn frame

    with pytest.raises(InputError, match="needs a face motion"):
        render_motion(motion, style="face", size=64)
