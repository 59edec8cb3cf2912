"""Many independent jobs (``render`` / ``sample`` / ``synthesize`` / ...), run on a local process pool or Ray.

What ``motion2video batch`` does, as plain functions:

- :func:`jobs_from_jsonl` / :func:`jobs_from_template` build the job list: each :class:`Job` is one
  sub-command with its own arguments and output path.
- :func:`run_batch` runs them with :func:`run_local` (a ``ProcessPoolExecutor`` of ``workers`` reused
  processes) or :func:`run_ray` (Ray tasks, ``max_retries`` for crashed workers), skipping jobs whose output
  already reads back as a video (unless ``force``), and writes ``results.jsonl`` (one row per job) and the
  gallery ``index.html`` (:mod:`motion2video.apps.gallery`) into the output folder.
- Each job runs the sub-command's own code in the worker process (:func:`run_job`): the command parser and
  ``run`` function, exactly as on the command line, so every check and the atomic writer apply. An
  :class:`~motion2video.core.errors.InputError` (or any other exception) fails that job's row only. GL contexts
  (mesh / face styles) are created lazily inside each worker process and never leave it.
- Outputs are written atomically by the commands (temporary file + rename). A worker killed mid-job can
  leave only its temporary file (``.NAME.*.tmpSUFFIX``); it is removed before the job is retried and when
  the batch ends, so no partial file ever sits under an output's name.
"""

from __future__ import annotations

import contextlib
import glob
import io
import json
import os
import shlex
import signal
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Iterable

from motion2video.core.errors import InputError
from motion2video.formats.video import ENCODER_ENV, ENCODER_THREADS_ENV, video_frame_count

ENGINES = ("local", "ray")
COMMANDS = ("render", "sample", "synthesize", "transfer", "analogy")
MOTION_SUFFIXES = (".bvh", ".txt", ".npz", ".json", ".csv")
RESULTS_NAME = "results.jsonl"


@dataclass(frozen=True)
class Job:
    """One sub-command invocation.

    Attributes:
        name: unique name of the job (the output's path relative to the output folder).
        command: a sub-command of :data:`COMMANDS`.
        args: its command-line arguments, without ``-o``.
        output: the output video (absolute path).
        input: the input shown in results and the gallery (the first positional argument by default).
    """

    name: str
    command: str
    args: tuple[str, ...]
    output: str
    input: str = ""


@dataclass
class JobResult:
    """One row of ``results.jsonl``.

    Attributes:
        name, command, input: as in :class:`Job`.
        output: the output path relative to the output folder.
        status: ``"ok"``, ``"skipped"`` (output already there and valid) or ``"failed"``.
        seconds: wall time of the job's last attempt in the worker (0 for skipped).
        frames: frames in the output video (None when failed).
        error: the one-line error of a failed job, else None.
        attempts: how many times the job was started (a crashed worker counts one).
    """

    name: str
    command: str
    input: str
    output: str
    status: str
    seconds: float = 0.0
    frames: int | None = None
    error: str | None = None
    attempts: int = 0
    worker: int | None = None

    def to_json(self) -> str:
        return json.dumps(asdict(self))


@dataclass(frozen=True)
class BatchConfig:
    """How to run a batch.

    Attributes:
        out_dir: output folder (results.jsonl, index.html; relative job outputs live under it).
        engine: ``"local"`` or ``"ray"``.
        workers: worker processes (local) or CPUs of a local Ray instance.
        address: Ray cluster address (``"auto"`` or ``HOST:PORT``); None starts a local Ray instance.
        retries: extra attempts for a job whose worker crashed.
        force: redo jobs whose output already exists.
        progress: show a progress bar.
        gallery: write ``index.html``.
    """

    out_dir: Path
    engine: str = "local"
    workers: int = 1
    address: str | None = None
    retries: int = 2
    force: bool = False
    progress: bool = True
    gallery: bool = True


@dataclass
class BatchSummary:
    results: list[JobResult] = field(default_factory=list)
    seconds: float = 0.0
    results_path: Path | None = None
    gallery_path: Path | None = None

    def count(self, status: str) -> int:
        return sum(r.status == status for r in self.results)

    def line(self) -> str:
        return (f"batch: {self.count('ok')} done, {self.count('skipped')} skipped, {self.count('failed')} failed "
                f"of {len(self.results)} jobs in {self.seconds:.1f} s")


# --- job lists ----------------------------------------------------------------------------------------

def _output_path(out_dir: Path, output: str) -> Path:
    path = Path(output)
    return path if path.is_absolute() else out_dir / path


def _job_name(out_dir: Path, output: Path) -> str:
    try:
        return str(output.resolve().relative_to(out_dir.resolve()))
    except ValueError:
        return str(output)


def _check_unique(jobs: list[Job], where: str) -> list[Job]:
    seen: dict[str, str] = {}
    for job in jobs:
        if job.output in seen:
            raise InputError(f"two jobs write the same output {job.output} ({seen[job.output]} and {job.name})", where)
        seen[job.output] = job.name
    if not jobs:
        raise InputError("no jobs", where)
    return jobs


def jobs_from_jsonl(path: str | Path, out_dir: str | Path) -> list[Job]:
    """Read a JSONL job file: one object per line, ``{"command": "render", "args": [...], "output": "a.mp4"}``.

    ``args`` is a list of command-line arguments, or an object ``{"input": "x.bvh", "style": "mesh",
    "no_progress": true}`` (keys become ``--key value`` with ``_`` as ``-``; ``true`` is a bare flag;
    ``input`` / ``inputs`` are positional). ``output`` is relative to ``out_dir`` unless absolute; an
    optional ``"input"`` names the job's input for the results (default: the first positional argument).
    Blank lines and lines starting with ``#`` are skipped. Raises InputError naming the file and line.
    """
    path, out_dir = Path(path), Path(out_dir)
    if not path.is_file():
        raise InputError("no such job file", path)
    jobs = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        where = f"{path}:{number}"
        try:
            record = json.loads(line)
        except json.JSONDecodeError as err:
            raise InputError(f"not JSON: {err.msg}", where) from None
        if not isinstance(record, dict) or "command" not in record or "output" not in record:
            raise InputError('each line needs {"command": ..., "args": ..., "output": ...}', where)
        command = str(record["command"])
        if command not in COMMANDS:
            raise InputError(f"unknown command {command!r}; choose one of {', '.join(COMMANDS)}", where)
        args = record.get("args", [])
        if isinstance(args, dict):
            args = _args_from_mapping(args)
        elif not isinstance(args, list):
            raise InputError("args must be a list of strings or an object", where)
        args = tuple(str(a) for a in args)
        output = _output_path(out_dir, str(record["output"]))
        shown = str(record.get("input") or next((a for a in args if not a.startswith("-")), ""))
        jobs.append(Job(_job_name(out_dir, output), command, args, str(output), shown))
    return _check_unique(jobs, str(path))


def _args_from_mapping(mapping: dict) -> list[str]:
    positional, options = [], []
    for key, value in mapping.items():
        if key in ("input", "inputs"):
            positional += [str(v) for v in (value if isinstance(value, list) else [value])]
        elif value is True:
            options.append(f"--{key.replace('_', '-')}")
        elif value is False or value is None:
            continue
        else:
            options += [f"--{key.replace('_', '-')}", str(value)]
    return positional + options


def find_inputs(spec: str) -> list[Path]:
    """A folder (its motion files, :data:`MOTION_SUFFIXES`, not recursive) or a glob pattern (``**``
    recurses), sorted. Raises InputError when nothing matches."""
    folder = Path(spec)
    if folder.is_dir():
        found = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in MOTION_SUFFIXES
                       and not p.name.startswith("."))
    else:
        found = sorted(Path(p) for p in glob.glob(spec, recursive=True) if Path(p).is_file())
    if not found:
        raise InputError("no input files found (a folder of motion files or a glob pattern)", spec)
    return found


def jobs_from_template(inputs: str, template: str, out_dir: str | Path, *, suffix: str = ".mp4") -> list[Job]:
    """One job per input file from a command template.

    Args:
        inputs: a folder or a glob (see :func:`find_inputs`).
        template: e.g. ``"render {input} -o {output} --style skeleton"``; fields ``{input}`` (the path),
            ``{output}``, ``{stem}`` (input name without extension) and ``{name}`` (the output's name
            without extension). ``-o {output}`` may be left out.
        out_dir: the output folder; the output is ``NAME + suffix`` with NAME the input's path relative
            to the inputs' common folder, ``/`` replaced by ``__`` and the extension dropped.
    """
    out_dir = Path(out_dir)
    files = find_inputs(inputs)
    try:
        tokens = shlex.split(template)
    except ValueError as err:
        raise InputError(f"cannot parse the template: {err}") from None
    if not tokens or tokens[0] not in COMMANDS:
        raise InputError(f"the template must start with one of {', '.join(COMMANDS)}: {template!r}")
    if not any("{input}" in t for t in tokens[1:]):
        raise InputError(f"the template must use {{input}}: {template!r}")
    root = os.path.commonpath([os.path.abspath(f.parent) for f in files])
    jobs = []
    for f in files:
        name = os.path.relpath(os.path.abspath(f.with_suffix("")), root).replace(os.sep, "__")
        output = out_dir / f"{name}{suffix}"
        fields = {"input": str(f), "output": str(output), "stem": f.stem, "name": name}
        try:
            args = [t.format(**fields) for t in tokens[1:]]
        except (KeyError, IndexError) as err:
            raise InputError(f"unknown template field {err}: {template!r}") from None
        args = _drop_output_option(args, str(output))
        jobs.append(Job(_job_name(out_dir, output), tokens[0], tuple(args), str(output), str(f)))
    return _check_unique(jobs, inputs)


def _drop_output_option(args: list[str], output: str) -> list[str]:
    out, skip = [], False
    for i, a in enumerate(args):
        if skip:
            skip = False
            continue
        if a in ("-o", "--output"):
            if i + 1 < len(args) and args[i + 1] != output:
                raise InputError(f"the template's output {args[i + 1]!r} must be {{output}}")
            skip = True
            continue
        out.append(a)
    return out


# --- one job, in a worker -----------------------------------------------------------------------------

def temp_files_of(output: str | Path) -> list[Path]:
    """Temporary files the atomic writers leave for ``output`` when killed (``.STEM.*.tmpSUFFIX``)."""
    output = Path(output)
    if not output.parent.is_dir():
        return []
    return sorted(output.parent.glob(f".{glob.escape(output.stem)}.*.tmp{output.suffix}"))


def remove_temp_files(output: str | Path) -> None:
    for tmp in temp_files_of(output):
        tmp.unlink(missing_ok=True)


_PARSER = None


def init_worker() -> None:
    """Worker start-up: no progress bars, one torch thread, the command line parser (and with it the
    command modules) imported once, so every job after the first pays no import cost."""
    global _PARSER
    os.environ.setdefault("TQDM_DISABLE", "1")
    # A worker is one core: it encodes in its own process (no ffmpeg process beside it) with one x264 thread,
    # and the workers together fill the cores.
    os.environ.setdefault(ENCODER_ENV, "pyav")
    os.environ.setdefault(ENCODER_THREADS_ENV, "1")
    if _PARSER is None:
        import cv2

        from motion2video.cli import build_parser
        import motion2video.apps.render  # noqa: F401  (the renderers most jobs use)
        import renderers.skeleton  # noqa: F401

        cv2.setNumThreads(1)  # as the encoder: parallelism comes from the workers, not from threads inside one
        _PARSER = build_parser()


def _init_pool_worker() -> None:
    """Initializer of the local pool's processes: Ctrl-C reaches the whole process group, and the driver
    decides (it stops the workers and removes their temporary files); a worker must not die half-way on its
    own and print a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _exit_on_sigterm)
    init_worker()


def _exit_on_sigterm(signum, frame) -> None:
    """A pool worker told to stop unwinds (its writers remove their temporary files, ffmpeg is stopped, and
    multiprocessing's own clean-up runs) instead of vanishing."""
    sys.exit(143)


def run_job(job: Job) -> JobResult:
    """Run one job in this process: parse its arguments with the real command line parser and call the
    command. Never raises for a failing job: the error becomes the row's one-line ``error``."""
    init_worker()
    start = time.perf_counter()
    result = JobResult(job.name, job.command, job.input, job.name, "failed", attempts=1, worker=os.getpid())
    remove_temp_files(job.output)  # a previous attempt killed mid-write
    stderr = io.StringIO()
    try:
        Path(job.output).parent.mkdir(parents=True, exist_ok=True)
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(stderr):
            args = _PARSER.parse_args([job.command, *job.args, "-o", job.output])
            code = int(args.run(args) or 0)
        if code != 0:
            raise RuntimeError(f"exit code {code}")
        frames = video_frame_count(job.output, decode_first=False)
        if frames is None:
            raise RuntimeError(f"the output {job.output} does not read back as a video")
        result.status, result.frames = "ok", frames
    except SystemExit as err:  # argparse: bad arguments
        lines = [l for l in stderr.getvalue().splitlines() if l.strip()]
        result.error = lines[-1] if lines else f"bad arguments (exit {err.code})"
    except InputError as err:
        result.error = str(err)
    except Exception as err:  # noqa: BLE001 - any failure of one job is that job's row
        result.error = " ".join(f"{type(err).__name__}: {err}".split())[:500]
    result.seconds = time.perf_counter() - start
    return result


# --- engines ------------------------------------------------------------------------------------------

OnResult = Callable[[JobResult], None]


class LocalPool:
    """A pool of ``workers`` reused worker processes (spawned, so no GL or torch state is inherited; each
    runs :func:`init_worker` once). Use as a context manager; :meth:`run` may be called many times."""

    def __init__(self, workers: int) -> None:
        import multiprocessing

        self.workers = int(workers)
        self._context = multiprocessing.get_context("spawn")
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=self._context,
                                             initializer=_init_pool_worker)
        return self._pool

    def warm(self) -> None:
        """Start every worker process now (and import the commands), instead of on the first jobs."""
        pool = self._executor()
        list(pool.map(_warm, [0.5] * self.workers))

    def run(self, jobs: list[Job], *, retries: int, on_result: OnResult) -> None:
        """Run ``jobs``, calling ``on_result`` with each row as it finishes.

        At most ``workers`` jobs are in flight. When a worker dies (the pool breaks), every job that was in
        flight counts an attempt and is resubmitted to a new pool while it has attempts left (1 + retries).
        """
        pending = list(reversed(jobs))
        attempts = {job.name: 0 for job in jobs}
        running: dict = {}
        while pending or running:
            pool = self._executor()
            broken = False
            while pending and len(running) < self.workers:
                job = pending.pop()
                attempts[job.name] += 1
                try:
                    running[pool.submit(run_job, job)] = job
                except BrokenProcessPool:
                    attempts[job.name] -= 1
                    pending.append(job)
                    broken = True
                    break
            if running:
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in done:
                    job = running.pop(future)
                    try:
                        row = future.result()
                    except BrokenProcessPool:
                        broken = True
                        remove_temp_files(job.output)
                        if attempts[job.name] <= retries:
                            pending.append(job)
                        else:
                            on_result(_crashed(job, attempts[job.name]))
                        continue
                    row.attempts = attempts[job.name]
                    on_result(row)
            if broken and not running:  # every in-flight future has failed: start a new pool
                self._pool.shutdown(wait=True, cancel_futures=True)
                self._pool = None

    def close(self, *, kill: bool = False) -> None:
        """Shut the pool down; ``kill`` stops the workers at once (jobs in flight are abandoned: their
        temporary files are the caller's to remove) instead of waiting for them."""
        if self._pool is not None:
            if kill:  # SIGTERM: each worker unwinds its job (see _exit_on_sigterm)
                for process in list(getattr(self._pool, "_processes", {}).values()):
                    process.terminate()
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> "LocalPool":
        return self

    def __exit__(self, exc_type, *exc) -> None:
        self.close(kill=exc_type is not None and issubclass(exc_type, BaseException)
                   and not issubclass(exc_type, Exception))


def _warm(seconds: float) -> int:
    init_worker()
    time.sleep(seconds)  # keep this worker busy so the next warm-up call starts another one
    return os.getpid()


def run_local(jobs: list[Job], *, workers: int, retries: int, on_result: OnResult) -> None:
    """Run ``jobs`` on a :class:`LocalPool` of ``workers`` processes (see :meth:`LocalPool.run`)."""
    with LocalPool(workers) as pool:
        pool.run(jobs, retries=retries, on_result=on_result)


def _crashed(job: Job, attempts: int) -> JobResult:
    return JobResult(job.name, job.command, job.input, job.name, "failed",
                     error=f"the worker process died {attempts} time(s) running this job", attempts=attempts)


def init_ray(workers: int, address: str | None = None) -> None:
    """``ray.init``: connect to ``address`` or start a local instance with ``workers`` CPUs (no dashboard).

    Workers get this process's ``sys.path`` as PYTHONPATH (so they import the same motion2video) and no
    progress bars. A local instance runs its workers at niceness 0 like the local pool's (Ray's default
    is 15, measured here: on a machine shared with other jobs that starves them and made Ray 2x slower than
    the pool); set ``RAY_worker_niceness`` to override, or pass it to ``ray start`` for a cluster.
    """
    import ray

    env = {"env_vars": {"TQDM_DISABLE": "1", "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}}
    if address is None:
        os.environ.setdefault("RAY_worker_niceness", "0")
        ray.init(num_cpus=workers, include_dashboard=False, runtime_env=env, log_to_driver=False)
    else:
        ray.init(address=address, runtime_env=env, log_to_driver=False)


def warm_ray(workers: int) -> None:
    """Start ``workers`` Ray worker processes now (and import the commands in them)."""
    import ray

    warm = ray.remote(num_cpus=1)(_warm)
    ray.get([warm.remote(1.0) for _ in range(workers)])


def _ray_task(job: Job) -> JobResult:
    return run_job(job)


_RAY_TASKS: dict = {}


def _ray_task_with(retries: int):
    """The Ray remote function for :func:`run_job` (made once per retry count, so it is exported once)."""
    import ray

    if retries not in _RAY_TASKS:
        _RAY_TASKS[retries] = ray.remote(num_cpus=1, max_retries=retries, retry_exceptions=False)(_ray_task)
    return _RAY_TASKS[retries]


def run_ray(jobs: list[Job], *, workers: int, retries: int, address: str | None, on_result: OnResult) -> None:
    """Run ``jobs`` as Ray tasks (1 CPU each, ``max_retries=retries`` when a worker dies).

    Connects to ``address`` (``"auto"``: the cluster started with ``ray start``) or, when None, starts a
    local Ray instance with ``workers`` CPUs (and shuts it down at the end). Outputs must be on a filesystem
    every node can write (or per-node folders gathered afterwards); see docs/cli.md, "batch".
    """
    try:
        import ray
    except ImportError:
        raise InputError("--engine ray needs Ray: pip install 'motion2video[ray]'") from None
    started = False
    if not ray.is_initialized():
        init_ray(workers, address)
        started = True
    try:
        task = _ray_task_with(retries)
        refs = {task.remote(job): job for job in jobs}
        while refs:
            done, _ = ray.wait(list(refs), num_returns=1)
            for ref in done:
                job = refs.pop(ref)
                try:
                    row = ray.get(ref)
                except ray.exceptions.RayError as err:
                    remove_temp_files(job.output)
                    row = _crashed(job, retries + 1)
                    row.error = f"{row.error}: {' '.join(str(err).split())[:300]}"
                on_result(row)
    finally:
        if started and address is None:
            ray.shutdown()


# --- the batch ----------------------------------------------------------------------------------------

def run_batch(jobs: list[Job], config: BatchConfig) -> BatchSummary:
    """Run a batch; see the module docstring. Returns the rows in job order and the summary."""
    if config.engine not in ENGINES:
        raise InputError(f"unknown engine {config.engine!r}; choose one of {', '.join(ENGINES)}")
    if config.workers < 1:
        raise InputError(f"--workers must be >= 1, got {config.workers}")
    if config.retries < 0:
        raise InputError(f"--retries must be >= 0, got {config.retries}")
    from tqdm import tqdm

    from motion2video.core.atomic import atomic_output

    out_dir = Path(config.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    rows: dict[str, JobResult] = {}
    todo = []
    for job in jobs:
        frames = None if config.force else video_frame_count(job.output)
        if frames is not None:
            rows[job.name] = JobResult(job.name, job.command, job.input, job.name, "skipped", frames=frames)
        else:
            todo.append(job)
    results_path = out_dir / RESULTS_NAME
    bar = tqdm(total=len(jobs), initial=len(rows), unit="job", desc=f"batch ({config.engine})",
               disable=not config.progress, file=sys.stderr)
    with atomic_output(results_path) as tmp, open(tmp, "w") as log:
        for row in rows.values():
            log.write(row.to_json() + "\n")

        def on_result(row: JobResult) -> None:
            rows[row.name] = row
            log.write(row.to_json() + "\n")
            log.flush()
            bar.update(1)
            if row.status == "failed":
                bar.write(f"failed: {row.name}: {row.error}")

        try:
            if todo and config.engine == "local":
                run_local(todo, workers=config.workers, retries=config.retries, on_result=on_result)
            elif todo:
                run_ray(todo, workers=config.workers, retries=config.retries, address=config.address,
                        on_result=on_result)
        finally:
            bar.close()
            for job in todo:
                remove_temp_files(job.output)
    summary = BatchSummary([rows[job.name] for job in jobs], time.perf_counter() - start, results_path)
    if config.gallery:
        from motion2video.apps.gallery import write_gallery

        summary.gallery_path = write_gallery(out_dir, summary.results)
    return summary


def read_results(path: str | Path) -> list[JobResult]:
    """Rows of a ``results.jsonl``."""
    return [JobResult(**json.loads(line)) for line in Path(path).read_text().splitlines() if line.strip()]


def load_jobs(source: str, out_dir: str | Path, *, template: str | None = None, suffix: str = ".mp4") -> list[Job]:
    """The jobs of ``motion2video batch``: from a command ``template`` over the files of ``source`` (a folder or
    a glob), or from ``source`` as a JSONL job file. InputError for an output folder that is a file, or a source
    that is neither."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError("the output folder is a file", out_dir)
    if template is not None:
        return jobs_from_template(source, template, out_dir, suffix=suffix)
    if str(source).endswith(".jsonl"):
        return jobs_from_jsonl(source, out_dir)
    raise InputError("give a .jsonl job file, or a folder / glob with --template", source)


def describe(jobs: Iterable[Job]) -> str:
    """One line per job, for ``--dry-run``."""
    return "\n".join(f"{job.name}: motion2video {job.command} {shlex.join(job.args)} -o {job.output}" for job in jobs)
