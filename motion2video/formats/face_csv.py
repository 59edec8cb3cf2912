"""Live Link Face CSV (ARKit blendshapes) -> :class:`~motion2video.core.motion.FaceMotion`.

Two header variants are read:

- Live Link Face app takes: ``Timecode,BlendShapeCount,EyeBlinkLeft,...,HeadYaw,HeadPitch,HeadRoll,...``
  with timecodes ``HH:MM:SS:FF.fff`` at a 60 fps timecode rate, one row every second frame (~30 rows/s).
- LLV UDP captures (``llv/dao.csv``): ``FrameNumber,SubFrame,FpsNum,FpsDen,BlendShapeCount,...`` then the
  same columns; the rate is ``FpsNum / FpsDen`` and ``FrameNumber`` gives each row's frame.

What the loader does:

- Blendshape columns (PascalCase) are matched case-insensitively to :data:`~motion2video.core.motion.ARKIT_NAMES`
  and put in Anny's order; all 52 must be present. Eye-rotation columns are not used (the eyeLook*
  blendshapes carry gaze).
- A row is *tracking lost* when it lacks values (``Timecode,0`` rows, or empty fields) or when all its
  blendshapes are exactly zero. Lost rows are not treated as a neutral face: they are dropped and the clip
  is rebuilt on a uniform time grid by linear interpolation between the valid rows around them (this also
  fills frames the capture dropped). Values are clipped to [0, 1] (raw values overshoot to ~1.08).
- Row times come from the timecode (or FrameNumber); the frame rate is estimated from the median row
  spacing (60 fps timecode, rows 2 frames apart -> 30 fps). Without usable times the rate comes from the
  ``fps`` argument or the folder's ``manifest.csv``.
- Head rotation: ``HeadYaw/HeadPitch/HeadRoll`` are radians (``llv/dao.csv`` ranges over about +-0.4;
  degrees would be an imperceptible motion). They become one axis-angle vector in the project's z-up head
  frame (face looking along -y, its left side +x, as Anny): rotation = Rz(yaw) @ Rx(pitch) @ R(-y)(roll),
  i.e. positive yaw turns the face towards its own left, positive pitch tilts it down, positive roll
  tilts the top of the head towards its own right shoulder. These sign conventions are our reading of
  ARKit's and were not checked against video. Columns that are all zero (head streaming off, as in every
  ``livelinkface/`` take) give zero rotation. Head translation is zero (the CSV has none).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.formats.manifest import find_manifest_entry
from motion2video.formats.resample import round_fps
from motion2video.core.motion import ARKIT_NAMES, FACE_DIM, NUM_EXPRESSIONS, FaceMotion

HEAD_COLUMNS = ("headyaw", "headpitch", "headroll")
TIMECODE_RATE = 60.0


@dataclass(frozen=True)
class FaceCsv:
    """A face CSV as read, before resampling.

    Attributes:
        path: the file.
        times: (R,) seconds of each row from the first row; NaN where the row has no time.
        blendshapes: (R, 52) raw values in ARKIT_NAMES order (unclipped); NaN on lost rows.
        head_ypr: (R, 3) HeadYaw, HeadPitch, HeadRoll in radians (zeros when the columns are absent).
        valid: (R,) False on tracking-lost rows.
        fps: the rate estimated from the row times, or None when the rows carry no usable times.
    """

    path: str
    times: np.ndarray
    blendshapes: np.ndarray
    head_ypr: np.ndarray
    valid: np.ndarray
    fps: float | None

    @property
    def num_rows(self) -> int:
        return int(self.valid.shape[0])

    @property
    def num_lost(self) -> int:
        return int((~self.valid).sum())


def parse_timecode(text: str, rate: float = TIMECODE_RATE) -> float:
    """``HH:MM:SS:FF.fff`` -> seconds (FF counts frames at ``rate``). Raises ValueError when malformed."""
    parts = text.strip().split(":")
    if len(parts) != 4:
        raise ValueError(f"timecode {text!r} is not HH:MM:SS:FF")
    hours, minutes, seconds = int(parts[0]), int(parts[1]), int(parts[2])
    frames = float(parts[3])
    return (hours * 60 + minutes) * 60 + seconds + frames / rate


def _float(text: str) -> float:
    """A CSV cell as float; NaN when empty. Raises ValueError for non-numbers."""
    text = text.strip()
    return float(text) if text else float("nan")


def read_face_csv(path: str | Path, *, timecode_rate: float = TIMECODE_RATE) -> FaceCsv:
    """Read a Live Link Face / LLV CSV into a :class:`FaceCsv` (see the module docstring)."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:
            rows = list(csv.reader(f))
    except UnicodeDecodeError:
        raise InputError("not a text CSV file", path) from None
    if not rows:
        raise InputError("the file is empty", path)
    header = [h.strip().lower() for h in rows[0]]
    column = {name: i for i, name in enumerate(header)}
    missing = [n for n in ARKIT_NAMES if n.lower() not in column]
    if missing:
        raise InputError(f"missing blendshape column(s) {', '.join(missing[:5])}"
                         f"{' ...' if len(missing) > 5 else ''} (not a Live Link Face CSV?)", path)
    shape_cols = [column[n.lower()] for n in ARKIT_NAMES]
    head_cols = [column.get(n) for n in HEAD_COLUMNS]
    has_timecode = "timecode" in column
    has_frame_number = all(k in column for k in ("framenumber", "fpsnum", "fpsden"))
    body = [(i + 1, r) for i, r in enumerate(rows) if i > 0 and any(cell.strip() for cell in r)]
    if not body:
        raise InputError("no data rows (empty face motion)", path)

    num = len(body)
    shapes = np.full((num, NUM_EXPRESSIONS), np.nan)
    head = np.zeros((num, 3))
    times = np.full(num, np.nan)
    fps_declared: float | None = None
    for r, (line, row) in enumerate(body):  # line: 1-based line number in the file
        try:
            if has_timecode and len(row) > column["timecode"] and row[column["timecode"]].strip():
                times[r] = parse_timecode(row[column["timecode"]], timecode_rate)
            elif has_frame_number and len(row) > max(column["framenumber"], column["fpsnum"], column["fpsden"]):
                rate = _float(row[column["fpsnum"]]) / _float(row[column["fpsden"]])
                if np.isfinite(rate) and rate > 0:
                    fps_declared = rate
                    times[r] = _float(row[column["framenumber"]]) / rate
            if len(row) < len(header):  # "Timecode,0" and other short rows: tracking lost
                continue
            shapes[r] = [_float(row[c]) for c in shape_cols]
            head[r] = [_float(row[c]) if c is not None else 0.0 for c in head_cols]
        except ValueError as err:
            raise InputError(f"line {line}: {' '.join(str(err).split())[:80]}", path) from None
    valid = np.all(np.isfinite(shapes), axis=1) & np.any(shapes != 0, axis=1)
    valid &= np.all(np.isfinite(head), axis=1)
    shapes[~valid] = np.nan
    head[~valid] = 0.0
    if not valid.any():
        raise InputError("tracking is lost on every row (no face data)", path)

    fps = _estimate_fps(times, fps_declared)
    if fps is not None:
        times = times - np.nanmin(times)
        # Rows are consecutive captures: gaps of lost tracking are short. A span far beyond the rows' count
        # is a damaged timecode or frame number (it would otherwise resample to billions of frames).
        if times[-1] > 10.0 * num / fps + 60.0:
            raise InputError(f"the row times span {times[-1]:.3g} s for {num} rows at {fps:g} fps: a damaged "
                             "timecode or frame number", path)
    else:
        times = np.full(num, np.nan)
    return FaceCsv(path=str(path), times=times, blendshapes=shapes, head_ypr=head, valid=valid, fps=fps)


def _estimate_fps(times: np.ndarray, declared: float | None) -> float | None:
    """The row rate: the declared rate (LLV) or 1 / median row spacing (timecode); None when the rows do
    not all carry increasing times."""
    if not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
        return None  # missing times, or not increasing (e.g. a timecode crossing midnight)
    if declared is not None:
        return round_fps(declared)
    if len(times) < 2:
        return None
    return round_fps(1.0 / float(np.median(np.diff(times))))


def head_ypr_to_axis_angle(ypr: np.ndarray) -> np.ndarray:
    """Head yaw/pitch/roll (radians) -> axis-angle in the z-up head frame (see the module docstring).

    Args:
        ypr: (T, 3) yaw, pitch, roll.
    Returns:
        (T, 3) axis-angle vectors (radians) of Rz(yaw) @ Rx(pitch) @ R(-y)(roll).
    """
    ypr = np.asarray(ypr, dtype=np.float64)

    def quat(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:  # (T, 4) as (w, x, y, z)
        half = 0.5 * angle[:, None]
        return np.concatenate([np.cos(half), np.sin(half) * axis[None, :]], axis=1)

    def mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # Hamilton product, (T, 4)
        aw, av = a[:, :1], a[:, 1:]
        bw, bv = b[:, :1], b[:, 1:]
        w = aw * bw - np.sum(av * bv, axis=1, keepdims=True)
        v = aw * bv + bw * av + np.cross(av, bv)
        return np.concatenate([w, v], axis=1)

    q = mul(mul(quat(np.array([0.0, 0.0, 1.0]), ypr[:, 0]), quat(np.array([1.0, 0.0, 0.0]), ypr[:, 1])),
            quat(np.array([0.0, -1.0, 0.0]), ypr[:, 2]))
    q = q * np.where(q[:, :1] < 0, -1.0, 1.0)  # w >= 0: angle in [0, pi]
    norm_v = np.linalg.norm(q[:, 1:], axis=1)
    angle = 2.0 * np.arctan2(norm_v, q[:, 0])
    scale = np.where(norm_v > 1e-12, angle / np.maximum(norm_v, 1e-12), 2.0)  # small-angle limit: 2 v
    return q[:, 1:] * scale[:, None]


def load_face_csv(path: str | Path, *, fps: float | None = None, label: str | None = None) -> FaceMotion:
    """Load a Live Link Face / LLV CSV as a FaceMotion on a uniform time grid.

    Args:
        path: the .csv file.
        fps: output frame rate. None: the rate estimated from the row times, else the manifest's.
        label: action label (None: the manifest's ``content`` when a manifest lists the file).
    Returns:
        FaceMotion (T, 58): 52 expressions clipped to [0, 1], head axis-angle, zero translation.
    """
    face = read_face_csv(path)
    entry = find_manifest_entry(path) if (fps is None and face.fps is None) or label is None else None
    if label is None and entry is not None:
        label = entry.label or None
    rate = fps if fps is not None else face.fps if face.fps is not None else (entry.fps if entry else None)
    if rate is None:
        raise InputError("cannot tell the frame rate (no timecode, no manifest entry): pass fps", path)
    if not np.isfinite(rate) or rate <= 0:
        raise InputError(f"fps must be a positive number, got {rate}", path)

    ok = face.valid
    values = np.concatenate([face.blendshapes, face.head_ypr], axis=1)  # (R, 55)
    if face.fps is not None:
        t_in = face.times[ok]  # seconds of the valid rows
        num_out = int(np.floor(face.times[-1] * rate + 0.5)) + 1
    else:
        t_in = np.nonzero(ok)[0] / rate  # rows are consecutive frames at `rate`
        num_out = face.num_rows
    t_out = np.arange(num_out) / rate
    grid = np.stack([np.interp(t_out, t_in, values[ok, c]) for c in range(values.shape[1])], axis=1)

    params = np.zeros((num_out, FACE_DIM))
    params[:, :NUM_EXPRESSIONS] = np.clip(grid[:, :NUM_EXPRESSIONS], 0.0, 1.0)
    params[:, NUM_EXPRESSIONS:NUM_EXPRESSIONS + 3] = head_ypr_to_axis_angle(grid[:, NUM_EXPRESSIONS:])
    return FaceMotion(params.astype(np.float32), float(rate), {}, str(path), label)
