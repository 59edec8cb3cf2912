"""``motion2video doctor``: what this machine can do, what is missing, and how to fix each missing thing.

Every check is a small function returning a :class:`Check`. The GL backends are probed in child processes,
because PyOpenGL fixes its platform (OSMesa or EGL) once per process: each child renders one triangle with
:class:`renderers.mesh.MeshRenderer` and reports whether any pixel was drawn.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

GL_PROBE_TIMEOUT_S = 120.0


@dataclass(frozen=True)
class Check:
    """One line of the report.

    Attributes:
        name: what was checked.
        ok: whether it works.
        detail: what was found (version, path, size, time).
        fix: what to do when it does not work ("" when ok).
        essential: whether motion2video's main jobs need it (doctor exits 1 when an essential check fails).
    """

    name: str
    ok: bool
    detail: str
    fix: str = ""
    essential: bool = True


def check_python() -> Check:
    from motion2video import __version__

    return Check("motion2video", True, f"{__version__} on Python {sys.version.split()[0]} ({sys.executable})")


def check_torch() -> Check:
    try:
        import torch
    except ImportError as err:
        return Check("torch", False, f"not importable ({err})",
                     "pip install torch==2.13.0 (the CPU wheel; `make setup` does it)")
    return Check("torch", True, f"{torch.__version__}, {torch.get_num_threads()} threads by default, "
                 f"{os.cpu_count()} CPUs; CUDA {'available' if torch.cuda.is_available() else 'not available (CPU)'}")


def check_ffmpeg() -> Check:
    try:
        import imageio_ffmpeg

        exe = imageio_ffmpeg.get_ffmpeg_exe()
        first = subprocess.run([exe, "-version"], capture_output=True, text=True, timeout=30).stdout.splitlines()
    except Exception as err:  # noqa: BLE001 - any failure here is the finding
        return Check("ffmpeg", False, f"not usable ({type(err).__name__}: {err})",
                     "pip install imageio-ffmpeg (it ships an ffmpeg binary)")
    return Check("ffmpeg", True, f"{first[0] if first else '?'} ({exe})")


def check_pyav() -> Check:
    """PyAV and its libx264: the in-process mp4 encoder of batch workers and the read-back checks."""
    try:
        import av

        has_x264 = "libx264" in av.codecs_available
    except Exception as err:  # noqa: BLE001 - any failure here is the finding
        return Check("PyAV", False, f"not usable ({type(err).__name__}: {err})", "pip install av")
    if not has_x264:
        return Check("PyAV", False, f"{av.__version__} has no libx264 encoder",
                     "pip install a PyAV wheel from PyPI (they bundle libx264)")
    return Check("PyAV", True, f"{av.__version__} with libx264 (libavcodec {'.'.join(map(str, av.library_versions['libavcodec']))})")


def probe_gl(platform: str) -> Check:
    """Render one triangle with ``platform`` in a child process (see the module docstring)."""
    from renderers.mesh import GL_LIBRARIES, gl_unavailable_message

    name, package = GL_LIBRARIES[platform]
    start = time.perf_counter()
    code = f"from motion2video.apps.doctor import _gl_child; _gl_child({platform!r})"
    env = {**os.environ, "PYOPENGL_PLATFORM": platform}
    try:
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                             timeout=GL_PROBE_TIMEOUT_S)
        result = json.loads(run.stdout.strip().splitlines()[-1]) if run.stdout.strip() else {}
    except (subprocess.TimeoutExpired, json.JSONDecodeError, IndexError) as err:
        result = {"ok": False, "error": f"{type(err).__name__}: {err}"}
    seconds = time.perf_counter() - start
    label = f"GL {platform} (lib{name})"
    if result.get("ok"):
        return Check(label, True, f"renders ({result.get('library')}; first frame in {seconds:.1f} s with start-up)",
                     essential=False)
    if result.get("missing"):
        return Check(label, False, f"lib{name} is not installed", gl_unavailable_message(platform), essential=False)
    error = result.get("error") or (run.stderr.strip().splitlines() or ["no output"])[-1]
    return Check(label, False, f"does not render: {error}",
                 f"check the {package} installation (`sudo apt-get install --reinstall {package}`)", essential=False)


def _gl_child(platform: str) -> None:
    """In a child process: render one triangle with ``platform``; print a JSON line."""
    import numpy as np

    from motion2video.core.camera import PinholeCamera
    from renderers.mesh import MeshRenderer, gl_library

    library = gl_library(platform)
    if library is None:
        print(json.dumps({"ok": False, "missing": True}))
        return
    try:
        camera = PinholeCamera(position=(0.0, -3.0, 0.0), target=(0.0, 0.0, 0.0), yfov=0.8, width=32, height=32)
        vertices = np.array([[-0.5, 0.0, -0.5], [0.5, 0.0, -0.5], [0.0, 0.0, 0.5]], np.float32)
        frame = MeshRenderer(32, 32, platform=platform).render_mesh(
            vertices, np.array([[0, 1, 2]]), vertex_colors=(1.0, 0.2, 0.2), camera=camera)
        drawn = int(np.count_nonzero(frame.mask))
        print(json.dumps({"ok": drawn > 0, "library": library, "error": None if drawn else "nothing was drawn"}))
    except Exception as err:  # noqa: BLE001 - the report says what failed
        print(json.dumps({"ok": False, "library": library, "error": f"{type(err).__name__}: {err}"}))


def check_gl_default() -> Check:
    """Which backend the mesh and face styles use (``PYOPENGL_PLATFORM``, default osmesa)."""
    platform = os.environ.get("PYOPENGL_PLATFORM", "osmesa")
    return Check("GL backend used", True, f"{platform} (set PYOPENGL_PLATFORM=osmesa or egl to choose)",
                 essential=False)


def check_anny_cache() -> Check:
    """Anny builds its model data on first use (about 40 s) into ``~/.cache/anny`` (``ANNY_CACHE_DIR``)."""
    try:
        from anny.paths import get_anny_cache_path
    except ImportError as err:
        return Check("Anny body model", False, f"not importable ({err})", "pip install anny")
    folder = Path(get_anny_cache_path())
    files = [p for p in folder.rglob("*.safetensors")] if folder.is_dir() else []
    if not files:
        return Check("Anny body model", True, f"installed; its cache {folder} is not built yet: the first mesh or "
                     "face render builds it (about 40 s, about 0.8 GB)", essential=False)
    size = sum(p.stat().st_size for p in files) / 2**20
    return Check("Anny body model", True, f"cache built: {folder}, {len(files)} files, {size:.0f} MB (built once, on "
                 "the first mesh or face render: about 40 s)", essential=False)


def check_pose_estimator() -> Check:
    """The bundled BlazePose models (photos and videos of people) load in LiteRT and run one detection."""
    import time

    import numpy as np

    try:
        from motion2video.pose.blazepose import BlazePose, DETECTOR_FILE, LANDMARK_FILE
        start = time.perf_counter()
        model = BlazePose(num_threads=1)
        model.detect(np.zeros((64, 64, 3), np.uint8))
        ms = (time.perf_counter() - start) * 1000
    except (ImportError, ValueError, RuntimeError, OSError) as err:
        return Check("pose estimator (BlazePose)", False, f"cannot run ({type(err).__name__}: {err})",
                     "pip install ai-edge-litert==2.3.0; the two .tflite files belong in motion2video/weights/ "
                     "(weights/blazepose.md)", essential=False)
    size = (DETECTOR_FILE.stat().st_size + LANDMARK_FILE.stat().st_size) / 2**20
    return Check("pose estimator (BlazePose)", True, f"LiteRT runs the bundled models ({size:.1f} MB), loaded and "
                 f"ran in {ms:.0f} ms", essential=False)


def check_checkpoints() -> list[Check]:
    """Every shipped checkpoint loads (motion models and frame generators)."""
    from motion2video.models.checkpoint import WEIGHTS_DIR, load_model
    from motion2video.core.errors import InputError
    from motion2video.generator.checkpoint import load_frame_model

    checks = []
    for path in sorted(WEIGHTS_DIR.glob("*.safetensors")):
        name = path.name[: -len(".safetensors")]
        loader = load_frame_model if name.startswith("frames-") else load_model
        try:
            loader(path)
        except (InputError, OSError, RuntimeError) as err:
            checks.append(Check(f"checkpoint {name}", False, str(err),
                                "restore motion2video/weights from the repository (git checkout -- motion2video/weights)"))
            continue
        checks.append(Check(f"checkpoint {name}", True, f"loads ({path.stat().st_size / 2**20:.1f} MB)"))
    if not checks:
        checks.append(Check("shipped checkpoints", False, f"none in {WEIGHTS_DIR}",
                            "restore motion2video/weights from the repository"))
    return checks


def run_checks() -> list[Check]:
    checks = [check_python(), check_torch(), check_ffmpeg(), check_pyav(), check_gl_default()]
    checks += [probe_gl(platform) for platform in ("osmesa", "egl")]
    checks.append(check_anny_cache())
    checks.append(check_pose_estimator())
    checks += check_checkpoints()
    return checks


def report(checks: list[Check]) -> str:
    """The checks as text: one line each, ``ok`` / ``MISSING``, and the fix under a missing one."""
    lines = []
    for c in checks:
        lines.append(f"{'ok     ' if c.ok else 'MISSING'} {c.name}: {c.detail}")
        if not c.ok and c.fix:
            lines.append(f"        fix: {c.fix}")
    gl_ok = [c for c in checks if c.name.startswith("GL ") and c.name != "GL backend used" and c.ok]
    lines.append("mesh and face styles: " + ("available" if gl_ok else "NOT available (no GL backend renders); "
                                             "skeleton and heatmap styles work without GL"))
    return "\n".join(lines)
