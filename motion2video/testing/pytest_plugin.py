"""pytest plugin for golden-frame regression tests of renders; registered as ``motion2video`` through the
``pytest11`` entry point, so installing the package is enough (disable with ``-p no:motion2video``).

- Fixture ``golden_frames``: ``golden_frames(source, metric="max", tolerance=1)`` compares a frame array, a video
  file (``.mp4`` / ``.gif``) or a ``Motion`` rendered in a style (``style=``, ``size=``, ``palette=``) with the
  golden named after the test (``name=`` to choose), in ``golden_root`` (default ``golden/`` beside the test file;
  override the ``golden_root`` fixture in a conftest to move it). ``indices=`` / ``every=`` keep chosen frames.
  It calls :func:`motion2video.testing.golden.assert_frames_match`; see there for the metrics and the checks.
- ``--update-golden`` (or ``UPDATE_GOLDEN=1``) writes the goldens instead of comparing.
- ``--golden-results DIR``: failing comparisons write ``actual_XXX.png`` and ``diff_XXX.png`` (golden | actual |
  diff with the numbers) to ``DIR/<golden name>/`` (default ``$MOTION2VIDEO_TEST_OUTPUT`` or ``./test_output``).
- At the end of the session: ``golden frames: C compared, W written, F failed, U unused``, then the failed
  goldens and the golden directories on disk (in the golden roots the session used) that no test used.

This module imports only pytest at start-up; the image code loads on the first comparison.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

_NAME_RE = re.compile(r"[^A-Za-z0-9_.-]+")


@dataclass
class GoldenSession:
    """What the golden_frames fixture did in this session (kept in ``config.stash``)."""

    compared: int = 0
    written: list[Path] = field(default_factory=list)
    failed: list[tuple[str, Path]] = field(default_factory=list)  # (test node id, golden dir)
    used: dict[Path, str] = field(default_factory=dict)  # resolved golden dir -> node id of its test
    roots: set[Path] = field(default_factory=set)
    deselected: int = 0


_SESSION = pytest.StashKey[GoldenSession]()
_WORKER_KEY = "motion2video_golden"  # what a pytest-xdist worker sends its controller


def _to_record(state: GoldenSession) -> dict:
    """A worker's golden state as plain data (xdist sends ``workeroutput`` across processes)."""
    return {"compared": state.compared, "written": [str(p) for p in state.written],
            "failed": [[nodeid, str(p)] for nodeid, p in state.failed],
            "used": {str(p): nodeid for p, nodeid in state.used.items()}, "roots": [str(p) for p in state.roots]}


def _merge_record(state: GoldenSession, record: dict) -> None:
    """Add a worker's golden state (:func:`_to_record`) to the controller's, for the one summary."""
    state.compared += int(record["compared"])
    state.written += [Path(p) for p in record["written"]]
    state.failed += [(nodeid, Path(p)) for nodeid, p in record["failed"]]
    state.used.update({Path(p): nodeid for p, nodeid in record["used"].items()})
    state.roots.update(Path(p) for p in record["roots"])


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("golden-frames", "golden-frame regression tests of renders (motion2video)")
    group.addoption("--update-golden", action="store_true", default=False,
                    help="write the goldens of the golden_frames fixture instead of comparing (UPDATE_GOLDEN=1 "
                         "does the same)")
    group.addoption("--golden-results", metavar="DIR", default=None,
                    help="failing golden comparisons write actual_XXX.png and diff_XXX.png (golden | actual | diff) "
                         "to DIR/<golden name>/ (default: $MOTION2VIDEO_TEST_OUTPUT or ./test_output)")


def pytest_configure(config: pytest.Config) -> None:
    config.stash[_SESSION] = GoldenSession()


def pytest_sessionfinish(session: pytest.Session) -> None:
    """In a pytest-xdist worker: hand what the golden_frames fixture did to the controller, which prints the
    summary (a worker's own summary is not shown)."""
    output = getattr(session.config, "workeroutput", None)
    state = session.config.stash.get(_SESSION, None)
    if output is not None and state is not None:
        output[_WORKER_KEY] = _to_record(state)


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error) -> None:
    """pytest-xdist's controller, as each worker finishes: merge its golden state (:func:`pytest_sessionfinish`)."""
    record = getattr(node, "workeroutput", {}).get(_WORKER_KEY)
    if record is not None:
        _merge_record(node.config.stash[_SESSION], record)


def pytest_deselected(items: list) -> None:
    if items:
        items[0].config.stash[_SESSION].deselected += len(items)


def golden_name(test_name: str) -> str:
    """A test's name as a golden directory name: ``test_walk[leftright-96]`` -> ``test_walk_leftright-96``."""
    return _NAME_RE.sub("_", test_name).strip("_") or "golden"


class GoldenFrames:
    """The ``golden_frames`` fixture's value: call it once per golden in a test."""

    def __init__(self, request: pytest.FixtureRequest, root: Path) -> None:
        self._config = request.config
        self._nodeid = request.node.nodeid
        self.default_name = golden_name(request.node.name)
        self.root = Path(root)

    @property
    def update(self) -> bool:
        from motion2video.testing.golden import update_requested

        return bool(self._config.getoption("update_golden")) or update_requested()

    def __call__(self, source, *, tolerance: float, metric: str = "max", name: str | None = None,
                 indices=None, every: int | None = None, style: str | None = None, size: int | None = None,
                 palette: str = "leftright", fps: float | None = None):
        """Compare ``source`` with the golden ``name`` (default: the test's name), or write it in update mode.

        Args:
            source: (T, H, W, 3) / (H, W, 3) uint8 frames, a ``.mp4`` / ``.gif`` path, or a Motion / FaceMotion
                (rendered with ``style``, ``size``, ``palette`` by ``motion2video.apps.render.render_motion``).
            tolerance, metric: largest allowed per-frame error in ``"max"``, ``"rel_l1"`` or ``"ssim"``
                (1 - SSIM).
            name: the golden's directory name under ``golden_root``.
            indices, every: compare chosen frame indices, or every k-th frame (default all).
            fps: a frame array's fps (videos and motions carry their own).
        Returns:
            :class:`motion2video.testing.golden.GoldenResult`.
        """
        __tracebackhide__ = True
        from motion2video.testing.golden import assert_frames_match, golden_clip

        state = self._config.stash[_SESSION]
        name = self.default_name if name is None else str(name)
        if name in ("", ".", "..") or "/" in name or "\\" in name:
            raise ValueError(f"golden name {name!r} must be a plain directory name")
        golden_dir = self.root / name
        key = golden_dir.resolve()
        if key in state.used:
            state.failed.append((self._nodeid, golden_dir))
            raise AssertionError(f"{name}: the golden {golden_dir} is already used by {state.used[key]}; give this "
                                 f"comparison its own name=")
        state.used[key] = self._nodeid
        state.roots.add(self.root)
        clip = golden_clip(source, style=style, size=size, palette=palette, fps=fps)
        results = self._config.getoption("golden_results")
        update = self.update
        try:
            result = assert_frames_match(clip.frames, golden_dir, tolerance=tolerance, metric=metric, name=name,
                                         out_dir=None if results is None else Path(results) / name,
                                         indices=indices, every=every, fps=clip.fps, update=update)
        except AssertionError:
            if not update:
                state.compared += 1
            state.failed.append((self._nodeid, golden_dir))
            raise
        if result.updated:
            state.written.append(golden_dir)
        else:
            state.compared += 1
        return result


@pytest.fixture
def golden_root(request: pytest.FixtureRequest) -> Path:
    """The folder of this test module's goldens: ``golden/`` beside the test file. Override it in a conftest
    to keep goldens elsewhere."""
    return Path(request.path).parent / "golden"


@pytest.fixture
def golden_frames(request: pytest.FixtureRequest, golden_root: Path) -> GoldenFrames:
    """Compare frames, a video file or a rendered Motion with a golden named after the test (see
    :class:`GoldenFrames`); ``--update-golden`` writes the goldens instead."""
    return GoldenFrames(request, golden_root)


def unused_goldens(roots: set[Path], used: set[Path]) -> list[Path]:
    """Golden directories in ``roots`` (directories holding ``frame_*.png`` or ``golden.json``) not in ``used``
    (resolved paths). A root that is missing, a file or unreadable contributes nothing."""
    from motion2video.testing.golden import is_golden_dir

    unused = []
    for root in sorted(roots):
        try:
            children = sorted(root.iterdir()) if root.is_dir() else []
        except OSError:
            continue
        unused += [child for child in children if child.resolve() not in used and is_golden_dir(child)]
    return unused


def _shown(path: Path, rootpath: Path) -> str:
    try:
        return str(path.resolve().relative_to(rootpath))
    except ValueError:
        return str(path)


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    state = config.stash.get(_SESSION, None)
    if state is None or not (state.compared or state.written or state.failed or state.roots):
        return
    tr = terminalreporter
    tr.write_sep("-", "golden frames")
    try:
        unused = unused_goldens(state.roots, set(state.used))
    except Exception as err:  # the summary must never break the session
        tr.write_line(f"golden frames: could not list unused goldens ({type(err).__name__}: {err})")
        unused = []
    tr.write_line(f"golden frames: {state.compared} compared, {len(state.written)} written, "
                  f"{len(state.failed)} failed, {len(unused)} unused")
    root = config.rootpath
    for nodeid, golden_dir in state.failed:
        tr.write_line(f"  FAILED  {_shown(golden_dir, root)}  ({nodeid})")
    for golden_dir in state.written:
        tr.write_line(f"  WRITTEN {_shown(golden_dir, root)}")
    for golden_dir in unused:
        tr.write_line(f"  UNUSED  {_shown(golden_dir, root)}")
    if unused and state.deselected:
        tr.write_line(f"  ({state.deselected} tests were deselected: the goldens of tests that did not run are "
                      f"listed as unused)")
