"""Video and image writing, plus the layouts used to show results (borders, labels, grids, contact sheets).

- mp4: H.264 (libx264, yuv420p) with the frame rate passed as an exact fraction
  (``Fraction(fps).limit_denominator(100000)``: 30000/1001 stays 30000/1001), by one of two encoders:

  - ``"ffmpeg"`` (the default): raw RGB frames are piped into imageio-ffmpeg's ffmpeg binary, a separate
    process, so rendering and encoding overlap on two cores (its exit status is checked: a failed encode
    raises with ffmpeg's message);
  - ``"pyav"``: the frames are encoded in this process by PyAV's libx264 (no second process, no pipe:
    about a third less CPU per frame). ``motion2video batch`` workers use it: a worker is then exactly one
    core, and N workers fill N cores.

  Chosen per writer (``encoder=``) or for the process by ``$MOTION2VIDEO_ENCODER``. Odd frame sizes are
  padded to even by repeating the last row / column (yuv420p needs even sizes); nothing is rescaled.
- GIF: by extension, through the same ffmpeg binary with a palette per frame (so it streams too). GIF
  stores frame delays in 1/100 s, so its rate is only approximate (30 fps is stored as 3/100 s per frame).
- Streaming: :class:`VideoWriter` (and :func:`write_video`, which accepts any iterable of frames or chunks)
  encode frames as they arrive; :func:`iter_grid` / :func:`iter_observed_future` tile clips lazily. A long
  clip is never held in memory.
- Writes are atomic: the file is written to a temporary name in the same directory and renamed with
  ``os.replace``; on any failure the temporary file is removed and the error is raised, so no partial file
  is ever left behind. A destination whose directory cannot be written raises
  :class:`~motion2video.core.errors.InputError` before anything is encoded. Missing parent directories are
  created.

All frames are RGB uint8: (T, H, W, 3) for clips, (H, W, 3) for images.
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import subprocess
import tempfile
import threading
from fractions import Fraction
from pathlib import Path
from typing import Iterable, Iterator, Sequence

import cv2
import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np

from motion2video.core import interrupts
from motion2video.core.errors import InputError

VIDEO_SUFFIXES = (".mp4", ".gif")
IMAGE_SUFFIXES = (".png",)
X264_PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower", "veryslow")
# Encoder threads of libx264 (default: ffmpeg's own choice, about one per core). `motion2video batch` sets 1
# in its workers: the workers already fill the cores, and x264's extra threads only contend with them.
ENCODER_THREADS_ENV = "MOTION2VIDEO_ENCODER_THREADS"
# The mp4 encoder when a writer names none: "ffmpeg" (a separate process) or "pyav" (in this process).
ENCODER_ENV = "MOTION2VIDEO_ENCODER"
ENCODERS = ("ffmpeg", "pyav")
GREEN = (0, 200, 0)  # observed frames
RED = (220, 0, 0)  # predicted frames
_FONT = cv2.FONT_HERSHEY_SIMPLEX


# --- checks -------------------------------------------------------------------------------------------

def _check_clip(frames: np.ndarray, what: str = "frames") -> np.ndarray:
    frames = np.asarray(frames)
    if frames.ndim != 4 or frames.shape[-1] != 3 or frames.shape[0] < 1:
        raise ValueError(f"{what} must have shape (T, H, W, 3) with T >= 1, got {frames.shape}")
    if frames.dtype != np.uint8:
        raise ValueError(f"{what} must be uint8, got {frames.dtype}")
    return frames


def _check_image(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[-1] != 3 or image.dtype != np.uint8:
        raise ValueError(f"image must be (H, W, 3) uint8, got {image.shape} {image.dtype}")
    return image


def _clip_or_image(frames: np.ndarray) -> tuple[np.ndarray, bool]:
    """(T, H, W, 3) or (H, W, 3) uint8 -> (T, H, W, 3) and whether the input was a single image."""
    frames = np.asarray(frames)
    if frames.ndim == 3:
        return _check_clip(frames[None]), True
    return _check_clip(frames), False


def _exact_fps(fps: float | Fraction, path: Path) -> Fraction:
    try:
        value = float(fps)
    except (TypeError, ValueError):
        raise InputError(f"fps must be a number, got {fps!r}", path) from None
    if not math.isfinite(value) or value <= 0:
        raise InputError(f"fps must be a positive number, got {fps}", path)
    return fps if isinstance(fps, Fraction) else Fraction(value).limit_denominator(100000)


def _open_temp(path: Path) -> Path:
    """Check that ``path``'s directory can be written and create the temporary file beside it.

    Raises InputError (naming the path) when the directory cannot be created or written.
    """
    parent = path.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"cannot create the output directory {parent}: {err.strerror or err}", path) from None
    if path.is_dir():
        raise InputError("the output path is a directory", path)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"the output directory {parent} is not writable", path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}", dir=parent)
    except OSError as err:
        raise InputError(f"cannot write in the output directory {parent}: {err.strerror or err}", path) from None
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it private; the output gets the usual permissions
    return Path(tmp)


def _commit(tmp: Path, path: Path, write) -> Path:
    """Run ``write(tmp)``, then rename tmp -> path; remove tmp and re-raise on any failure."""
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


# --- writing and reading ------------------------------------------------------------------------------

def pad_to_even(frames: np.ndarray) -> np.ndarray:
    """Pad (T, H, W, 3) frames to even H and W by repeating the last row / column (no-op when even)."""
    frames = _check_clip(frames)
    pad_h, pad_w = frames.shape[1] % 2, frames.shape[2] % 2
    if not (pad_h or pad_w):
        return frames
    return np.pad(frames, ((0, 0), (0, pad_h), (0, pad_w), (0, 0)), mode="edge")


def write_video(
    path: str | Path,
    frames: np.ndarray | Iterable[np.ndarray],
    fps: float | Fraction,
    *,
    n_frames: int | None = None,
    crf: int = 18,
    preset: str = "medium",
    encoder: str | None = None,
) -> Path:
    """Write an mp4 (H.264, yuv420p) or a GIF, chosen by the file extension; atomically and streaming.

    Args:
        path: destination ``.mp4`` or ``.gif``.
        frames: a (T, H, W, 3) uint8 RGB array, or any iterable of (H, W, 3) frames and/or (t, H, W, 3)
            chunks (a generator is consumed once, chunk by chunk: only one chunk is in memory at a time).
        fps: frames per second (float or Fraction), passed to the encoder as an exact fraction.
        n_frames: the expected frame count, when known; a different count raises ValueError and writes
            nothing.
        crf: x264 constant rate factor (0 lossless .. 51 worst; mp4 only).
        preset: x264 preset (``"ultrafast"`` .. ``"veryslow"``; mp4 only).
        encoder: ``"ffmpeg"`` or ``"pyav"`` (mp4 only; default ``$MOTION2VIDEO_ENCODER`` or ``"ffmpeg"``).
    Returns:
        The written path.
    """
    if isinstance(frames, np.ndarray):
        frames = [_check_clip(frames)]
    with VideoWriter(path, fps, crf=crf, preset=preset, encoder=encoder) as writer:
        for chunk in frames:
            writer.write(chunk)
        if writer.num_frames == 0:
            raise ValueError("frames must have shape (T, H, W, 3) with T >= 1, got no frames")
        if n_frames is not None and writer.num_frames != int(n_frames):
            raise ValueError(f"expected {n_frames} frames, got {writer.num_frames}")
    return writer.path


def _encoder_threads() -> int:
    """libx264 threads from ``$MOTION2VIDEO_ENCODER_THREADS``; 0 = the encoder's own choice."""
    threads = os.environ.get(ENCODER_THREADS_ENV, "").strip()
    return int(threads) if threads.isdigit() else 0


class _FFmpegProcess:
    """Frames piped as raw RGB into a separate ffmpeg process writing ``tmp`` (mp4 or GIF)."""

    def __init__(self, tmp: Path, path: Path, width: int, height: int, rate: Fraction, *, gif: bool,
                 crf: int, preset: str):
        self.path = path
        head = [imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-hide_banner", "-loglevel", "error",
                "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{width}x{height}",
                "-r", f"{rate.numerator}/{rate.denominator}", "-i", "-", "-an"]
        if gif:
            cmd = head + ["-vf", "split[a][b];[a]palettegen=stats_mode=single:reserve_transparent=0[p];"
                          "[b][p]paletteuse=new=1:dither=none", "-loop", "0", "-f", "gif", str(tmp)]
        else:
            threads = _encoder_threads()
            cmd = head + ["-c:v", "libx264", *(["-threads", str(threads)] if threads else []), "-preset", preset,
                          "-crf", str(crf), "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4", str(tmp)]
        self._log = tempfile.TemporaryFile()
        # Its own session: Ctrl-C reaches this process, which stops the encoder and removes the temporary
        # file; an encoder interrupted on its own would fail the write before the interrupt is seen.
        self._proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=self._log,
                                      start_new_session=True)

    def write(self, clip: np.ndarray) -> None:
        try:
            self._proc.stdin.write(np.ascontiguousarray(clip).tobytes())
        except BrokenPipeError:
            pass  # ffmpeg quit early; its exit status and message are reported by finish()

    def finish(self) -> None:
        try:
            self._proc.stdin.close()
        except BrokenPipeError:
            pass
        code = self._proc.wait()
        if code != 0:
            self._log.seek(0)
            message = " ".join(self._log.read().decode("utf-8", "replace").split())[-500:]
            raise RuntimeError(f"ffmpeg failed writing {self.path} (exit {code}): ...{message}")

    def close(self) -> None:
        """Stop the encoder if it still runs (after a failure or an interrupt) and release its log."""
        if self._proc.poll() is None:
            self._proc.kill()
            self._proc.wait()
        self._log.close()


class _PyAVEncoder:
    """Frames encoded in this process by PyAV's libx264 into an mp4 at ``tmp``.

    Frame i has pts i in a time base of 1 / rate (kept here: the stream's own time base becomes the mp4
    track's once the header is written), so the muxer stores the exact rate, the same packet timestamps as
    the ffmpeg process writes (:func:`probe_frame_rate` reads them back).
    """

    def __init__(self, tmp: Path, path: Path, width: int, height: int, rate: Fraction, *, crf: int, preset: str):
        import av

        self.path, self._av, self._next_pts, self._time_base = path, av, 0, Fraction(1) / rate
        self._container = av.open(str(tmp), "w", format="mp4", options={"movflags": "+faststart"})
        try:
            self._stream = self._container.add_stream("libx264", rate=rate)
            self._stream.width, self._stream.height, self._stream.pix_fmt = width, height, "yuv420p"
            self._stream.time_base = self._time_base
            self._stream.codec_context.thread_count = _encoder_threads()
            self._stream.options = {"crf": str(crf), "preset": preset}
        except self._av.FFmpegError as err:
            self.close()
            raise self._error(err) from None

    def _error(self, err: Exception) -> RuntimeError:
        return RuntimeError(f"libx264 (in-process) failed writing {self.path}: {' '.join(str(err).split())[:500]}")

    def write(self, clip: np.ndarray) -> None:
        try:
            for image in clip:
                frame = self._av.VideoFrame.from_ndarray(np.ascontiguousarray(image), format="rgb24")
                frame.pts, frame.time_base = self._next_pts, self._time_base
                self._next_pts += 1
                self._container.mux(self._stream.encode(frame))
        except self._av.FFmpegError as err:
            raise self._error(err) from None

    def finish(self) -> None:
        try:
            self._container.mux(self._stream.encode(None))  # flush the frames x264 still holds
            self._container.close()
        except self._av.FFmpegError as err:
            raise self._error(err) from None

    def close(self) -> None:
        try:
            self._container.close()
        except self._av.FFmpegError:
            pass  # closing after a failure: the temporary file is removed anyway


@contextlib.contextmanager
def _interrupts_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back for the block (in the main thread; elsewhere nothing changes): one that
    arrives meanwhile is delivered, and raised, when the block ends.

    :class:`VideoWriter` starts its encoder inside this block. A Ctrl-C that Python raised while
    ``subprocess.Popen`` waited for the encoder to start, or before the writer had stored it, left an encoder the
    writer did not know about: it could not stop it, and the encoder wrote the temporary file when its input
    closed, after the writer had removed it (a ``.tmp.mp4`` left beside the output of an interrupted
    ``synthesize``, seen once in a clean-clone ``make test``). The encoder inherits the held mask; it runs in its
    own session and is stopped by SIGKILL (:meth:`_FFmpegProcess.close`) or by the end of its input, so it never
    needs those two signals.

    The mask holds a signal back from this thread only; the kernel hands a signal sent to the process to any
    thread that does not block it (a process with helper threads: a test worker's, a library's), and Python then
    runs its handler in the main thread all the same. So the Python handlers are replaced for the block too: a
    signal that arrives is recorded and raised again once the block ends and the handlers are back.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    arrived: list[int] = []
    replaced = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        handler = signal.getsignal(sig)
        if handler is not None:  # None: a handler not installed from Python, left alone
            replaced[sig] = handler
            signal.signal(sig, lambda signum, _frame: arrived.append(signum))
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
        for sig, handler in replaced.items():
            signal.signal(sig, handler)
        for sig in dict.fromkeys(arrived):
            signal.raise_signal(sig)


class VideoWriter:
    """A streaming, atomic video writer: frames go to an encoder as they come, the file appears on success.

    mp4 frames go to libx264 (yuv420p; odd sizes padded to even by repeating the last row / column), either
    piped into a separate ffmpeg process (``encoder="ffmpeg"``, the default) or encoded in this process by
    PyAV (``encoder="pyav"``; see the module docstring for when each is the better choice). GIF frames are
    piped into ffmpeg's GIF encoder with a palette computed per frame (``palettegen=stats_mode=single``), so
    GIF output streams too. The output goes to a temporary file in the destination's folder and is renamed
    onto ``path`` when the ``with`` block ends normally; on an exception or interrupt the encoder is stopped
    and the temporary file removed.

    Usage::

        with VideoWriter("out.mp4", 25) as writer:
            for chunk in chunks:            # (t, H, W, 3) or (H, W, 3) uint8
                writer.write(chunk)
        writer.num_frames, writer.width, writer.height

    Raises InputError (naming the path) on a bad extension, fps, crf, preset, encoder or an unwritable
    folder, before anything is encoded; RuntimeError with the encoder's message when the encode fails.
    """

    def __init__(self, path: str | Path, fps: float | Fraction, *, crf: int = 18, preset: str = "medium",
                 encoder: str | None = None):
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if suffix not in VIDEO_SUFFIXES:
            raise InputError(f"unsupported video extension {self.path.suffix!r}; use one of "
                             f"{', '.join(VIDEO_SUFFIXES)}", self.path)
        self.rate = _exact_fps(fps, self.path)
        if not 0 <= int(crf) <= 51:
            raise InputError(f"crf must be in 0..51, got {crf}", self.path)
        if suffix == ".mp4" and preset not in X264_PRESETS:
            raise InputError(f"unknown x264 preset {preset!r}; choose one of {', '.join(X264_PRESETS)}", self.path)
        encoder = encoder or os.environ.get(ENCODER_ENV, "").strip() or "ffmpeg"
        if encoder not in ENCODERS:
            raise InputError(f"unknown encoder {encoder!r} (from the argument or ${ENCODER_ENV}); choose one of "
                             f"{', '.join(ENCODERS)}", self.path)
        self.crf, self.preset, self.gif = int(crf), str(preset), suffix == ".gif"
        self.encoder = "ffmpeg" if self.gif else encoder
        self.num_frames = 0
        self.width = self.height = 0
        self._tmp: Path | None = None
        self._sink: _FFmpegProcess | _PyAVEncoder | None = None

    def __enter__(self) -> "VideoWriter":
        self._tmp = _open_temp(self.path)
        return self

    def _open_sink(self, width: int, height: int) -> _FFmpegProcess | _PyAVEncoder:
        if self.encoder == "pyav":
            return _PyAVEncoder(self._tmp, self.path, width, height, self.rate, crf=self.crf, preset=self.preset)
        return _FFmpegProcess(self._tmp, self.path, width, height, self.rate, gif=self.gif, crf=self.crf,
                              preset=self.preset)

    def write(self, frames: np.ndarray) -> None:
        """Encode one (H, W, 3) frame or a (t, H, W, 3) chunk of uint8 RGB frames (all the same size)."""
        if self._tmp is None:
            raise RuntimeError("VideoWriter.write outside its with-block")
        interrupts.raise_pending()  # a Ctrl-C / SIGTERM a finaliser swallowed stops the encode here
        clip, _ = _clip_or_image(frames)
        if self._sink is None:
            self.height, self.width = clip.shape[1:3]
            with _interrupts_held():  # the encoder is ours before an interrupt can stop the command
                if self.gif:
                    self._sink = self._open_sink(self.width, self.height)
                else:
                    self._sink = self._open_sink(self.width + self.width % 2, self.height + self.height % 2)
        elif clip.shape[1:3] != (self.height, self.width):
            raise ValueError(f"frame size changed from {self.width}x{self.height} to {clip.shape[2]}x{clip.shape[1]}")
        self._sink.write(clip if self.gif else pad_to_even(clip))
        self.num_frames += len(clip)

    def __exit__(self, exc_type, exc, tb) -> None:
        tmp, self._tmp = self._tmp, None
        try:
            if exc_type is None:
                if self._sink is None:
                    raise ValueError("frames must have shape (T, H, W, 3) with T >= 1, got no frames")
                self._sink.finish()
                os.replace(tmp, self.path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        finally:
            if self._sink is not None:
                self._sink.close()
            if exc_type is not None:
                tmp.unlink(missing_ok=True)


def probe_frame_rate(path: str | Path) -> Fraction:
    """The exact frame rate of an mp4, read back from its packet timestamps (like ffprobe).

    Runs ffmpeg's ``framecrc`` muxer on the video stream (no decoding) and returns
    ``time_base_den / (time_base_num * packet_duration)`` of the first packet.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such video file", path)
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(path), "-map", "0:v:0", "-c", "copy",
           "-f", "framecrc", "-"]
    result = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise InputError(f"ffmpeg cannot read the video: {result.stderr.strip().splitlines()[-1:]}", path)
    time_base = None
    for line in result.stdout.splitlines():
        if line.startswith("#tb 0:"):
            num, den = line.split(":", 1)[1].strip().split("/")
            time_base = Fraction(int(num), int(den))
        elif time_base is not None and line and not line.startswith("#"):
            duration = int(line.split(",")[3])
            return 1 / (time_base * duration)
    raise InputError("the video has no frames", path)


def video_frame_count(path: str | Path, *, decode_first: bool = True) -> int | None:
    """The number of frames of an mp4 / GIF that reads back completely, or None when the file is missing,
    empty, truncated, not of the container its extension says, or has no video.

    Read in this process through PyAV: every packet of the first video stream is demuxed (none may be
    corrupt), and with ``decode_first`` the first frame is decoded too. ``motion2video batch`` checks a job's
    own fresh output without the decode (its encoder just finished without an error) and an existing output
    it would skip with it.
    """
    import av

    path = Path(path)
    container_of = {".mp4": "mp4", ".gif": "gif"}
    wanted = container_of.get(path.suffix.lower())
    if wanted is None or not path.is_file() or path.stat().st_size == 0:
        return None
    count, decoded = 0, not decode_first
    try:
        with av.open(str(path)) as container:
            if wanted not in container.format.name.split(",") or not container.streams.video:
                return None
            for packet in container.demux(container.streams.video[0]):
                if packet.size == 0:
                    continue  # the demuxer's end-of-stream marker
                if packet.is_corrupt:
                    return None
                count += 1
                if not decoded and packet.decode():
                    decoded = True
    except (av.FFmpegError, OSError, ValueError):
        return None
    return count if count and decoded else None


def read_video(path: str | Path) -> tuple[np.ndarray, float]:
    """Read a whole mp4 or GIF.

    Returns:
        frames (T, H, W, 3) uint8 RGB, and fps (exact for mp4, from the GIF frame delay otherwise).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such video file", path)
    if path.suffix.lower() == ".gif":
        frames = iio.imread(path, index=None, mode="RGB")  # (T, H, W, 3)
        meta = iio.immeta(path, index=0)
        return np.asarray(frames, np.uint8), 1000.0 / float(meta["duration"])
    reader = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    meta = next(reader)
    width, height = meta["size"]
    frames = [np.frombuffer(buf, np.uint8).reshape(height, width, 3) for buf in reader]
    if not frames:
        raise InputError("the video has no frames", path)
    return np.stack(frames), float(probe_frame_rate(path))


def write_image(path: str | Path, image: np.ndarray) -> Path:
    """Write an (H, W, 3) uint8 RGB image as PNG, atomically (same rules as :func:`write_video`)."""
    path = Path(path)
    image = _check_image(image)
    if path.suffix.lower() not in IMAGE_SUFFIXES:
        raise InputError(f"unsupported image extension {path.suffix!r}; use .png", path)
    ok, data = cv2.imencode(".png", np.ascontiguousarray(image[..., ::-1]))
    if not ok:
        raise RuntimeError(f"OpenCV could not encode a PNG for {path}")
    tmp = _open_temp(path)
    return _commit(tmp, path, lambda p: p.write_bytes(data.tobytes()))


def read_image(path: str | Path) -> np.ndarray:
    """Read an image file as (H, W, 3) uint8 RGB."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such image file", path)
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        raise InputError("cannot decode the image", path)
    return np.ascontiguousarray(bgr[..., ::-1])


# --- layouts ------------------------------------------------------------------------------------------

def add_border(frames: np.ndarray, colour: tuple[int, int, int], width: int = 4) -> np.ndarray:
    """Paint a ``width``-pixel frame of ``colour`` over the outer pixels (the size does not change).

    Args:
        frames: (T, H, W, 3) or (H, W, 3) uint8.
    Returns:
        A new array of the same shape.
    """
    clip, single = _clip_or_image(frames)
    out = clip.copy()
    w = int(width)
    if w > 0:
        c = np.asarray(colour, np.uint8)
        out[:, :w], out[:, -w:], out[:, :, :w], out[:, :, -w:] = c, c, c, c
    return out[0] if single else out


def label(
    frames: np.ndarray,
    text: str,
    *,
    colour: tuple[int, int, int] = (255, 255, 255),
    background: tuple[int, int, int] = (0, 0, 0),
    corner: str = "top-left",
    inset: int = 0,
) -> np.ndarray:
    """Write ``text`` on every frame, in a solid box in a corner (the size does not change).

    The font (OpenCV Hershey simplex, anti-aliased) scales with the frame height and shrinks until the
    text fits the width. Only ASCII prints (OpenCV's fonts have no other glyphs).

    Args:
        frames: (T, H, W, 3) or (H, W, 3) uint8.
        text: one line of text; empty text returns a copy.
        corner: ``"top-left"`` or ``"bottom-left"``.
        inset: distance in pixels from the frame edge (e.g. a border's width).
    Returns:
        A new array of the same shape.
    """
    if corner not in ("top-left", "bottom-left"):
        raise ValueError(f"corner must be 'top-left' or 'bottom-left', got {corner!r}")
    clip, single = _clip_or_image(frames)
    out = clip.copy()
    if text:
        height, width = out.shape[1:3]
        room = max(width - 2 * inset - 6, 8)
        scale = max(height / 512.0, 0.3)
        (tw, th), base = cv2.getTextSize(text, _FONT, scale, 1)
        while tw > room and scale > 0.25:
            scale *= 0.9
            (tw, th), base = cv2.getTextSize(text, _FONT, scale, 1)
        box_h = th + base + 6
        top = inset if corner == "top-left" else height - inset - box_h
        x0 = inset
        out[:, max(top, 0):max(top + box_h, 0), x0:min(x0 + tw + 6, width)] = np.asarray(background, np.uint8)
        for t in range(out.shape[0]):
            cv2.putText(out[t], text, (x0 + 3, top + 3 + th), _FONT, scale, tuple(int(c) for c in colour), 1,
                        cv2.LINE_AA)
    return out[0] if single else out


def _hold_last(clip: np.ndarray, length: int) -> np.ndarray:
    """Pad (T, H, W, 3) to ``length`` frames by repeating the last frame."""
    if clip.shape[0] >= length:
        return clip
    return np.concatenate([clip, np.repeat(clip[-1:], length - clip.shape[0], axis=0)], axis=0)


def grid(
    clips: list[np.ndarray],
    labels: list[str] | None = None,
    columns: int | None = None,
    *,
    gap: int = 2,
    background: tuple[int, int, int] = (0, 0, 0),
) -> np.ndarray:
    """Tile clips of equal frame size into one clip.

    Shorter clips hold their last frame until the longest ends; empty cells are ``background``.

    Args:
        clips: K arrays (T_k, H, W, 3) uint8 (all the same H and W).
        labels: K texts drawn in each cell's top-left corner, or None.
        columns: cells per row (default ceil(sqrt(K))).
        gap: pixels between cells.
    Returns:
        (max T_k, rows*H + (rows-1)*gap, columns*W + (columns-1)*gap, 3) uint8.
    """
    if not clips:
        raise ValueError("grid needs at least one clip")
    clips = [_check_clip(c, f"clip {i}") for i, c in enumerate(clips)]
    height, width = clips[0].shape[1:3]
    for i, c in enumerate(clips):
        if c.shape[1:3] != (height, width):
            raise ValueError(f"clip {i} is {c.shape[2]}x{c.shape[1]} but clip 0 is {width}x{height}")
    if labels is not None:
        if len(labels) != len(clips):
            raise ValueError(f"{len(labels)} labels for {len(clips)} clips")
        clips = [label(c, text) for c, text in zip(clips, labels)]
    n = len(clips)
    cols = int(columns) if columns else math.ceil(math.sqrt(n))
    if cols < 1:
        raise ValueError(f"columns must be >= 1, got {columns}")
    rows = math.ceil(n / cols)
    length = max(c.shape[0] for c in clips)
    out = np.empty((length, rows * height + (rows - 1) * gap, cols * width + (cols - 1) * gap, 3), np.uint8)
    out[:] = np.asarray(background, np.uint8)
    for k, clip in enumerate(clips):
        r, c = divmod(k, cols)
        y, x = r * (height + gap), c * (width + gap)
        out[:, y:y + height, x:x + width] = _hold_last(clip, length)
    return out


def iter_single_frames(frames: np.ndarray | Iterable[np.ndarray]) -> Iterator[np.ndarray]:
    """Yield (H, W, 3) frames one by one from a (T, H, W, 3) array or an iterable of frames / chunks."""
    if isinstance(frames, np.ndarray):
        frames = [frames]
    for chunk in frames:
        clip, _ = _clip_or_image(chunk)
        yield from clip


def iter_chunks(frames: Iterable[np.ndarray], size: int = 32) -> Iterator[np.ndarray]:
    """Regroup an iterable of frames / chunks into (t <= size, H, W, 3) chunks (the last may be shorter)."""
    batch: list[np.ndarray] = []
    for frame in iter_single_frames(frames):
        batch.append(frame)
        if len(batch) == size:
            yield np.stack(batch)
            batch = []
    if batch:
        yield np.stack(batch)


def iter_grid(
    cells: Sequence[np.ndarray | Iterable[np.ndarray]],
    labels: list[str] | None = None,
    columns: int | None = None,
    *,
    gap: int = 2,
    background: tuple[int, int, int] = (0, 0, 0),
    chunk: int = 32,
) -> Iterator[np.ndarray]:
    """:func:`grid` as a stream: tile K clips given as arrays or iterables of frames / chunks.

    Each cell is consumed lazily, so only about ``chunk`` frames per cell are in memory at once. A cell that
    ends holds its last frame until every cell has ended; empty cells are ``background``.

    Args:
        cells: K clips, each a (T_k, H, W, 3) uint8 array or an iterable of (H, W, 3) frames / (t, H, W, 3)
            chunks, all with the same H and W.
        labels: K texts drawn in each cell's top-left corner, or None.
        columns: cells per row (default ceil(sqrt(K))).
        gap: pixels between cells.
        chunk: frames per yielded chunk.
    Yields:
        (t <= chunk, rows*H + (rows-1)*gap, columns*W + (columns-1)*gap, 3) uint8 chunks, max T_k frames in all.
    """
    if not cells:
        raise ValueError("grid needs at least one clip")
    if labels is not None and len(labels) != len(cells):
        raise ValueError(f"{len(labels)} labels for {len(cells)} clips")
    n = len(cells)
    cols = int(columns) if columns else math.ceil(math.sqrt(n))
    if cols < 1:
        raise ValueError(f"columns must be >= 1, got {columns}")
    rows = math.ceil(n / cols)
    streams = [iter_single_frames(c) for c in cells]
    last: list[np.ndarray | None] = [None] * n
    height = width = None
    while True:
        out = None
        for t in range(chunk):
            alive = False
            for k, stream in enumerate(streams):
                frame = next(stream, None)
                if frame is not None:
                    alive = True
                    if height is None:
                        height, width = frame.shape[:2]
                    elif frame.shape[:2] != (height, width):
                        raise ValueError(f"clip {k} is {frame.shape[1]}x{frame.shape[0]} but clip 0 is "
                                         f"{width}x{height}")
                    last[k] = label(frame, labels[k]) if labels is not None else frame
                elif last[k] is None:
                    raise ValueError(f"clip {k} must have shape (T, H, W, 3) with T >= 1, got no frames")
            if not alive:
                break
            if out is None:
                out = np.empty((chunk, rows * height + (rows - 1) * gap, cols * width + (cols - 1) * gap, 3),
                               np.uint8)
                out[:] = np.asarray(background, np.uint8)
            for k, frame in enumerate(last):
                r, c = divmod(k, cols)
                y, x = r * (height + gap), c * (width + gap)
                out[t, y:y + height, x:x + width] = frame
        else:
            t = chunk
        if out is None or t == 0:
            return
        yield out[:t]
        if t < chunk:
            return


def iter_observed_future(
    observed: np.ndarray,
    futures: Sequence[np.ndarray | Iterable[np.ndarray]],
    labels: list[str] | None = None,
    *,
    columns: int | None = None,
    border: int = 4,
    chunk: int = 32,
) -> Iterator[np.ndarray]:
    """:func:`observed_future_video` as a stream: the futures may be iterables of frames / chunks.

    Args:
        observed: (To, H, W, 3) uint8 observed frames (shared by every cell).
        futures: K predicted clips, arrays (Tf_k, H, W, 3) or iterables of frames / chunks.
        labels: K texts, or None.
    Yields:
        (t <= chunk, H', W', 3) uint8 chunks, To + max Tf_k frames in all.
    """
    observed = _check_clip(observed, "observed")
    if not futures:
        raise ValueError("observed_future_video needs at least one future")
    framed_obs = add_border(observed, GREEN, border)

    def cell(k: int, future) -> Iterator[np.ndarray]:
        text = labels[k] if labels is not None else ""
        for part in (framed_obs, *(add_border(f[None], RED, border) for f in iter_single_frames(future))):
            if part.shape[1:3] != observed.shape[1:3]:
                raise ValueError(f"future {k} frames are {part.shape[1:3]} but observed are {observed.shape[1:3]}")
            yield label(part, text, inset=border) if text else part

    if labels is not None and len(labels) != len(futures):
        raise ValueError(f"{len(labels)} labels for {len(futures)} futures")
    yield from iter_grid([cell(k, f) for k, f in enumerate(futures)], None, columns, chunk=chunk)


def observed_future_video(
    observed: np.ndarray,
    futures: list[np.ndarray],
    labels: list[str] | None = None,
    *,
    columns: int | None = None,
    border: int = 4,
) -> np.ndarray:
    """The papers' layout for K sampled futures of one observed clip.

    Every cell plays the same observed frames framed in GREEN, then its own predicted future framed in
    RED; the K cells are tiled with :func:`grid` (a shorter future holds its last frame).

    Args:
        observed: (To, H, W, 3) uint8 observed frames.
        futures: K arrays (Tf_k, H, W, 3) uint8 predicted frames.
        labels: K texts (e.g. ``"sample 1"``), or None.
    Returns:
        (To + max Tf_k, H', W', 3) uint8.
    """
    observed = _check_clip(observed, "observed")
    if not futures:
        raise ValueError("observed_future_video needs at least one future")
    framed_obs = add_border(observed, GREEN, border)
    cells = []
    for k, future in enumerate(futures):
        future = _check_clip(future, f"future {k}")
        if future.shape[1:3] != observed.shape[1:3]:
            raise ValueError(f"future {k} frames are {future.shape[1:3]} but observed are {observed.shape[1:3]}")
        cells.append(np.concatenate([framed_obs, add_border(future, RED, border)], axis=0))
    if labels is not None:
        if len(labels) != len(cells):
            raise ValueError(f"{len(labels)} labels for {len(cells)} futures")
        cells = [label(c, text, inset=border) for c, text in zip(cells, labels)]
    return grid(cells, None, columns)


def contact_sheet(
    frames: np.ndarray,
    every: int = 1,
    columns: int | None = None,
    *,
    numbered: bool = True,
    gap: int = 2,
) -> np.ndarray:
    """Frames 0, every, 2*every, ... of a clip tiled into one image.

    Args:
        frames: (T, H, W, 3) uint8.
        every: take one frame in ``every``.
        columns: cells per row (default min(count, 8)).
        numbered: write each frame's index in its bottom-left corner.
    Returns:
        (H', W', 3) uint8 image.
    """
    frames = _check_clip(frames)
    if int(every) < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    index = list(range(0, frames.shape[0], int(every)))
    cells = [frames[i:i + 1] for i in index]
    if numbered:  # bottom-left, so the frame number does not cover a label already in the frames
        cells = [label(c, str(i), corner="bottom-left") for c, i in zip(cells, index)]
    cols = int(columns) if columns else min(len(cells), 8)
    return grid(cells, None, cols, gap=gap)[0]
