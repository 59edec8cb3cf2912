"""BVH motion capture: a numpy reader, forward kinematics and conversion to the canonical H36M-17 body.

Reading (:func:`read_bvh`) keeps the file's own skeleton and units (:class:`BvhClip`);
:func:`bvh_world_positions` runs forward kinematics over all frames at once; :func:`bvh_to_canonical`
and :func:`load_bvh` give a :class:`~motion2video.core.motion.Motion` in the project's frame (``h36m-17``,
metres, right-handed, z up, floor at z = 0).

BVH conventions used here:

- Every ``ROOT``/``JOINT`` has an ``OFFSET`` (its origin in the parent's frame at rest) and a
  ``CHANNELS`` list, any subset and any order of ``X/Y/Zposition`` and ``X/Y/Zrotation``.
- Rotation channels are Euler angles in degrees, applied *intrinsically in the listed order*: channels
  ``Zrotation Xrotation Yrotation`` give the local rotation ``Rz @ Rx @ Ry``.
- Position channels give the joint's translation in its parent's frame and replace the ``OFFSET``
  component on the same axis (the usual reading: the root's channels are its world position).
- ``End Site`` blocks become nodes named ``"<joint>:end"`` (the notation of
  :data:`motion2video.core.skeletons.RIG_JOINT_MAPS`).
- A ``.bvh.xz`` file is read through lzma.

Rigs: a rig of :data:`~motion2video.core.skeletons.RIG_JOINT_MAPS` is recognised by its joint names; any
other humanoid rig (:data:`NAMED_JOINTS_RIG`) is mapped to the body points from its joint names
(:func:`~motion2video.core.skeletons.map_joint_names`), where a rig map (``--rig-map FILE``,
:func:`read_rig_map`) names the joints the names do not tell; its unit and up axis are read off the body
(:func:`body_unit`, :func:`up_axes`) and its body points must pass Human3.6M's proportion test
(:data:`PROPORTION_BAND`).
"""

from __future__ import annotations

import json
import lzma
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError
from motion2video.formats.canonical import (
    Y_UP_TO_Z_UP,
    CanonicalClip,
    canonical_from_map,
    canonical_motion,
    to_project_frame,
)
from motion2video.formats.manifest import ManifestEntry, default_trim, resolve_manifest
from motion2video.formats.numbers import parse_number_rows
from motion2video.formats.resample import round_fps
from motion2video.core.motion import Motion
from motion2video.core.skeletons import (
    BODY_POINT_RIGS,
    H36M_17,
    L_ANKLE,
    L_HIP,
    L_KNEE,
    NECK,
    PELVIS,
    R_ANKLE,
    R_HIP,
    R_KNEE,
    RIG_JOINT_MAPS,
    map_joint_names,
    proportion_ratios,
)

CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
_CHANNEL_LOOKUP = {c.lower(): c for c in CHANNEL_NAMES}

# Metres per file unit, per rig. Chosen from the measured thigh lengths in the data README and checked
# against standing height (tests/test_formats_bvh.py): CMU's ASF/AMC unit is 1/0.45 inch; the cgspeed
# DAZ conversion, the MASS character and the converted DeepMimic humanoid are in centimetres. Resulting
# statures (pose-independent estimate of the tests): cmu-3dsmax 1.50 m, cmu-mb 1.53-1.56, cmu-amc 1.56,
# cmu-daz 1.60, deepmimic-humanoid 1.55-1.56, mass-character1 1.66-1.69.
RIG_UNITS: dict[str, float] = {
    "cmu-mb": 0.0254 / 0.45,
    "cmu-3dsmax": 0.0254 / 0.45,
    "cmu-amc": 0.0254 / 0.45,
    "cmu-daz": 0.01,
    "deepmimic-humanoid": 0.01,
    "mass-character1": 0.01,
    "motion2video-h36m": 1.0,  # the files motion2video writes (formats/bvh_write.py)
}

@dataclass(frozen=True)
class BvhClip:
    """A BVH file as written: its skeleton, channels and raw motion values, in file units.

    Attributes:
        path: the file it was read from (used in error messages).
        names: (N,) node names in file order; end sites are named ``"<joint>:end"``.
        parents: (N,) parent index per node, -1 for the root; parents precede children.
        offsets: (N, 3) float64 rest offsets in the parent's frame (file units, y up).
        channels: (N,) tuple of channel names per node (empty for end sites).
        channel_start: (N,) column of each node's first channel in ``values``.
        frame_time: seconds per frame as declared in the header.
        values: (T, C) float64 motion values, one row per frame.
    """

    path: str
    names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    channel_start: tuple[int, ...]
    frame_time: float
    values: np.ndarray

    @property
    def num_frames(self) -> int:
        return int(self.values.shape[0])

    @property
    def num_nodes(self) -> int:
        return len(self.names)

    @property
    def header_fps(self) -> float:
        """Frame rate from the header's ``Frame Time``, rounded to an integer when within 0.1% of one."""
        return round_fps(1.0 / self.frame_time)

    def index(self, name: str) -> int:
        return self.names.index(name)


# --- parsing --------------------------------------------------------------------------------------------

class _Tokens:
    """The hierarchy's whitespace-separated tokens with their 1-based line numbers."""

    def __init__(self, lines: list[str], source: str) -> None:
        self.items = [(tok, num) for num, line in enumerate(lines, 1) for tok in line.split()]
        self.pos = 0
        self.source = source
        self.last_line = len(lines)

    def peek(self) -> tuple[str, int] | None:
        return self.items[self.pos] if self.pos < len(self.items) else None

    def next(self, what: str) -> tuple[str, int]:
        item = self.peek()
        if item is None:
            raise InputError(f"line {self.last_line}: hierarchy ends early, expected {what}", self.source)
        self.pos += 1
        return item

    def expect(self, keyword: str) -> int:
        tok, num = self.next(keyword)
        if tok.upper() != keyword.upper():
            raise InputError(f"line {num}: expected {keyword}, got {tok!r}", self.source)
        return num

    def number(self, what: str) -> float:
        tok, num = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise InputError(f"line {num}: expected a number for {what}, got {tok!r}", self.source) from None
        if not np.isfinite(value):
            raise InputError(f"line {num}: {what} is not finite ({tok})", self.source)
        return value

    def rest_of_line(self, num: int) -> list[str]:
        """Tokens still on line ``num`` (a joint name may contain spaces), excluding a trailing ``{``."""
        out = []
        while (item := self.peek()) is not None and item[1] == num and item[0] != "{":
            out.append(item[0])
            self.pos += 1
        return out


def _parse_hierarchy(lines: list[str], source: str):
    """Returns (names, parents, offsets, channels) of the single ROOT hierarchy in ``lines``."""
    toks = _Tokens(lines, source)
    toks.expect("HIERARCHY")
    names: list[str] = []
    parents: list[int] = []
    offsets: list[tuple[float, float, float]] = []
    channels: list[tuple[str, ...]] = []
    stack: list[int] = []  # open joints
    while True:
        tok, num = toks.next("ROOT")
        key = tok.upper()
        if key in ("ROOT", "JOINT"):
            if key == "ROOT" and (stack or names):
                raise InputError(f"line {num}: only one ROOT per file is supported", source)
            if key == "JOINT" and not stack:
                raise InputError(f"line {num}: JOINT outside a ROOT block", source)
            name_tokens = toks.rest_of_line(num)
            if not name_tokens:
                raise InputError(f"line {num}: {key} without a name", source)
            name = " ".join(name_tokens)
            if name in names:
                raise InputError(f"line {num}: duplicate joint name {name!r}", source)
            toks.expect("{")
            toks.expect("OFFSET")
            offset = (toks.number("OFFSET x"), toks.number("OFFSET y"), toks.number("OFFSET z"))
            ch_line = toks.expect("CHANNELS")
            count_tok, count_line = toks.next("channel count")
            if not count_tok.isdigit():
                raise InputError(f"line {count_line}: expected a channel count, got {count_tok!r}", source)
            node_channels = []
            for _ in range(int(count_tok)):
                ch, ch_num = toks.next("a channel name")
                canonical = _CHANNEL_LOOKUP.get(ch.lower())
                if canonical is None:
                    raise InputError(f"line {ch_num}: unknown channel {ch!r}", source)
                if canonical in node_channels:
                    raise InputError(f"line {ch_line}: channel {canonical} listed twice", source)
                node_channels.append(canonical)
            names.append(name)
            parents.append(stack[-1] if stack else -1)
            offsets.append(offset)
            channels.append(tuple(node_channels))
            stack.append(len(names) - 1)
        elif key == "END":
            if not stack:
                raise InputError(f"line {num}: End Site outside a joint", source)
            toks.expect("Site")
            toks.expect("{")
            toks.expect("OFFSET")
            offset = (toks.number("OFFSET x"), toks.number("OFFSET y"), toks.number("OFFSET z"))
            toks.expect("}")
            base = f"{names[stack[-1]]}:end"
            name = base
            suffix = 2
            while name in names:  # a second end site on one joint (allowed, rare)
                name, suffix = f"{base}{suffix}", suffix + 1
            names.append(name)
            parents.append(stack[-1])
            offsets.append(offset)
            channels.append(())
        elif key == "}":
            if not stack:
                raise InputError(f"line {num}: unbalanced '}}'", source)
            stack.pop()
            if not stack:
                break
        else:
            raise InputError(f"line {num}: expected JOINT, End Site or '}}', got {tok!r}", source)
    extra = toks.peek()
    if extra is not None:
        raise InputError(f"line {extra[1]}: unexpected {extra[0]!r} after the ROOT block", source)
    return names, parents, offsets, channels


def _header_value(line: str, key: str, num: int, source: str) -> str:
    head, sep, value = line.partition(":")
    if not sep or " ".join(head.split()).lower() != key.lower():
        raise InputError(f"line {num}: expected '{key}:', got {line.strip()[:40]!r}", source)
    return value.strip()


# Frames parsed, and run through forward kinematics, per step: memory stays bounded by the chunk, not the
# clip (a 38k-frame capture peaked at 17 times its file size when parsed and posed all at once).
CHUNK_FRAMES = 2048


def parse_bvh(text: str, source: str = "<bvh>") -> BvhClip:
    """Parse BVH text. Raises :class:`InputError` (naming ``source`` and the line) when it is malformed.

    Args:
        text: the whole file.
        source: the file name used in messages.
    """
    return _parse_lines(iter(text.splitlines()), source)


def _parse_lines(lines, source: str, *, chunk: int = CHUNK_FRAMES) -> BvhClip:
    """Parse BVH from an iterator of lines (a file streams: the motion lines are parsed ``chunk`` at a time,
    so only the hierarchy and the (T, C) values are ever held, never the whole text)."""
    hierarchy: list[str] = []
    for line in lines:
        if line.strip().upper() == "MOTION":
            break
        hierarchy.append(line)
    else:
        raise InputError("no MOTION section (not a BVH file, or truncated)", source)
    motion_at = len(hierarchy)  # 0-based index of the MOTION line
    names, parents, offsets, channels = _parse_hierarchy(hierarchy, source)
    numbered = ((i, line) for i, line in enumerate(lines, motion_at + 2) if line.strip())

    # "Frames: N" and "Frame Time: dt", then one line per frame.
    header = [item for _, item in zip(range(2), numbered)]
    if len(header) < 2:
        raise InputError(f"line {motion_at + 1}: MOTION must be followed by 'Frames:' and 'Frame Time:'",
                         source)
    (frames_num, frames_line), (time_num, time_line) = header
    frames_text = _header_value(frames_line, "Frames", frames_num, source)
    if not frames_text.isdigit():
        raise InputError(f"line {frames_num}: frame count must be a non-negative integer, got {frames_text!r}",
                         source)
    num_frames = int(frames_text)
    time_text = _header_value(time_line, "Frame Time", time_num, source)
    try:
        frame_time = float(time_text)
    except ValueError:
        raise InputError(f"line {time_num}: Frame Time must be a number, got {time_text!r}", source) from None
    if not np.isfinite(frame_time) or frame_time <= 0:
        raise InputError(f"line {time_num}: Frame Time must be positive, got {time_text}", source)
    if num_frames == 0:
        raise InputError(f"line {frames_num}: the motion is empty (Frames: 0)", source)

    counts = [len(c) for c in channels]
    num_channels = int(sum(counts))
    if num_channels == 0:
        raise InputError("the hierarchy declares no channels", source)
    parts: list[np.ndarray] = []
    read, last = 0, time_num
    while read < num_frames:
        rows = [item for _, item in zip(range(min(chunk, num_frames - read)), numbered)]
        if rows:
            last = rows[-1][0]
            parts.append(parse_number_rows(rows, num_channels, source, what="motion value"))  # (t, C)
            read += len(rows)
        if read < num_frames and len(rows) < min(chunk, num_frames - read + len(rows)):
            raise InputError(f"line {last}: file ends after {read} of {num_frames} frames (truncated)", source)
    extra = next(numbered, None)
    if extra is not None:
        raise InputError(f"line {extra[0]}: more frame lines than the declared {num_frames}", source)
    values = parts[0] if len(parts) == 1 else np.concatenate(parts)  # (T, C)
    del parts

    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(int)
    return BvhClip(
        path=source,
        names=tuple(names),
        parents=tuple(parents),
        offsets=np.asarray(offsets, dtype=np.float64).reshape(-1, 3),
        channels=tuple(channels),
        channel_start=tuple(int(s) for s in starts),
        frame_time=frame_time,
        values=values,
    )


def is_bvh_path(path: str | Path) -> bool:
    """Whether a path names a BVH file: ``*.bvh`` or xz-compressed ``*.bvh.xz``."""
    name = Path(path).name.lower()
    return name.endswith(".bvh") or name.endswith(".bvh.xz")


def read_bvh(path: str | Path) -> BvhClip:
    """Read a BVH file (``.bvh``, or ``.bvh.xz`` through lzma); see :func:`parse_bvh`. The file is streamed
    line by line (the motion lines parsed :data:`CHUNK_FRAMES` at a time). Raises :class:`InputError` for a
    missing or malformed file."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    opener = lzma.open if path.name.lower().endswith(".xz") else open
    try:
        with opener(path, "rt", encoding="utf-8", errors="strict", newline=None) as f:
            return _parse_lines((line.rstrip("\n") for line in f), str(path))
    except UnicodeDecodeError:
        raise InputError("not a text file (BVH is plain text)", path) from None
    except (lzma.LZMAError, EOFError):
        raise InputError("not a readable xz file (corrupt or truncated)", path) from None


# --- forward kinematics ---------------------------------------------------------------------------------

def axis_rotations(angles_deg: np.ndarray, axis: str | np.ndarray) -> np.ndarray:
    """Rotation matrices about coordinate axes (right-hand rule).

    Args:
        angles_deg: (...,) angles in degrees.
        axis: ``"X"``, ``"Y"`` or ``"Z"``, or an int array (0/1/2 for X/Y/Z) broadcastable to
            ``angles_deg``.
    Returns:
        (..., 3, 3) float64 matrices.
    """
    a = np.deg2rad(np.asarray(angles_deg, dtype=np.float64))
    if isinstance(axis, str):
        if axis not in ("X", "Y", "Z"):
            raise ValueError(f"axis must be X, Y or Z, got {axis!r}")
        axis = "XYZ".index(axis)
    # Rodrigues about a coordinate axis e: R = I + sin(a) [e]x + (1 - cos(a)) [e]x^2.
    cross = _AXIS_CROSS[np.asarray(axis)]  # (..., 3, 3)
    s = np.sin(a)[..., None, None]
    c = np.cos(a)[..., None, None]
    return np.eye(3) + s * cross + (1.0 - c) * (cross @ cross)


# [e]x, the cross-product matrix of each coordinate axis e = x, y, z.
_AXIS_CROSS = np.array([
    [[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
    [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]],
    [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
])


def local_transforms(clip: BvhClip) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame local rotation and translation of every node.

    Returns:
        rotations: (T, N, 3, 3), the product of the node's rotation channels in listed order.
        translations: (T, N, 3), the OFFSET with position channels substituted on their axes.
    """
    num_frames, num_nodes = clip.num_frames, clip.num_nodes
    translations = np.broadcast_to(clip.offsets, (num_frames, num_nodes, 3)).copy()
    # slots[k][j]: column of node j's k-th rotation channel, or -1 (identity) when it has fewer.
    slots = np.full((3, num_nodes), -1)
    for j, (chans, start) in enumerate(zip(clip.channels, clip.channel_start)):
        k = 0
        for offset, ch in enumerate(chans):
            axis = "XYZ".index(ch[0])
            if ch.endswith("position"):
                translations[:, j, axis] = clip.values[:, start + offset]
            else:
                slots[k, j] = start + offset
                k += 1
    columns = np.nonzero(slots.max(axis=0) >= 0)[0]  # nodes with at least one rotation channel
    rotations = np.broadcast_to(np.eye(3), (num_frames, num_nodes, 3, 3)).copy()
    if columns.size == 0:
        return rotations, translations
    channel_axis = np.array(["XYZ".index(c[0]) for chans in clip.channels for c in chans])  # (C,)
    identity_col = clip.values.shape[1]  # an extra all-zero column: angle 0 -> identity
    values = np.concatenate([clip.values, np.zeros((num_frames, 1))], axis=1)  # (T, C + 1)
    axes = np.concatenate([channel_axis, [0]])
    product = None
    for k in range(3):
        cols = np.where(slots[k, columns] >= 0, slots[k, columns], identity_col)  # (Nr,)
        mats = axis_rotations(values[:, cols], axes[cols][None, :])  # (T, Nr, 3, 3)
        product = mats if product is None else product @ mats
    rotations[:, columns] = product
    return rotations, translations


def bvh_world_positions(clip: BvhClip, *, chunk: int = CHUNK_FRAMES) -> np.ndarray:
    """Forward kinematics: world position of every node (joints and end sites), vectorised over frames.

    Nodes are processed one tree depth at a time, all nodes of a depth at once; frames ``chunk`` at a time
    (every frame is posed on its own, so the result does not depend on ``chunk``; the (t, N, 3, 3) rotations
    exist for one chunk only).

    Returns:
        (T, N, 3) float64 positions in file units and file axes (y up).
    """
    if clip.num_frames <= chunk:
        return _world_positions(clip)
    out = np.empty((clip.num_frames, clip.num_nodes, 3))
    for s in range(0, clip.num_frames, chunk):
        out[s:s + chunk] = _world_positions(replace(clip, values=clip.values[s:s + chunk]))
    return out


def _world_positions(clip: BvhClip) -> np.ndarray:
    """:func:`bvh_world_positions` of all frames at once: (T, N, 3)."""
    rotations, translations = local_transforms(clip)
    parents = np.asarray(clip.parents)
    depth = np.zeros(clip.num_nodes, dtype=int)
    for j, p in enumerate(parents):
        depth[j] = depth[p] + 1 if p >= 0 else 0
    world_rot = np.empty_like(rotations)  # (T, N, 3, 3)
    world_pos = np.empty_like(translations)  # (T, N, 3)
    roots = np.nonzero(depth == 0)[0]
    world_rot[:, roots] = rotations[:, roots]
    world_pos[:, roots] = translations[:, roots]
    for level in range(1, depth.max() + 1):
        nodes = np.nonzero(depth == level)[0]
        par = parents[nodes]
        world_rot[:, nodes] = world_rot[:, par] @ rotations[:, nodes]
        offset = (world_rot[:, par] @ translations[:, nodes, :, None])[..., 0]  # (T, n, 3)
        world_pos[:, nodes] = world_pos[:, par] + offset
    return world_pos


def bvh_rest_positions(clip: BvhClip) -> np.ndarray:
    """Positions of every node in the rest pose (all rotations zero, root at its OFFSET).

    Returns:
        (N, 3) float64 positions in file units and axes.
    """
    pos = np.zeros((clip.num_nodes, 3))
    for j, p in enumerate(clip.parents):
        pos[j] = clip.offsets[j] + (pos[p] if p >= 0 else 0.0)
    return pos


# --- canonical conversion -------------------------------------------------------------------------------

def rig_joint_maps() -> dict[str, dict[str, str | tuple[str, str]]]:
    """All known rigs (:data:`motion2video.core.skeletons.RIG_JOINT_MAPS`)."""
    return RIG_JOINT_MAPS


def _map_node_names(mapping: dict[str, str | tuple[str, str]]) -> set[str]:
    out: set[str] = set()
    for target in mapping.values():
        out.update(target if isinstance(target, tuple) else (target,))
    return out


def detect_rig(names: tuple[str, ...] | list[str], source: str | None = None) -> str | None:
    """Name of the known rig whose mapped joints all occur in ``names`` (node names, end sites as
    ``"j:end"``), or None when none does (the rig is then mapped from its joint names).

    Raises :class:`InputError` when more than one matches.
    """
    present = set(names)
    found = [rig for rig, mapping in rig_joint_maps().items() if _map_node_names(mapping) <= present]
    if len(found) <= 1:
        return found[0] if found else None
    raise InputError(f"BVH joint names match several rigs ({', '.join(found)}); pass rig= explicitly", source)


# The rig name of a BVH whose body points come from its joint names (:func:`named_rig_mapping`).
NAMED_JOINTS_RIG = "named-joints"
# Every proportion of a rig mapped from its joint names lies in this band of Human3.6M's
# (:func:`~motion2video.core.skeletons.proportion_ratios`), as every known rig's does (tests).
PROPORTION_BAND = (0.8, 1.25)
# Candidate units of a rig mapped by names, metres per file unit: metres, centimetres, millimetres, inches,
# CMU's 1/0.45 inch. The one that makes the leg (thigh + shin) nearest LEG_METRES wins (:func:`body_unit`).
UNIT_CANDIDATES = (1.0, 0.01, 0.001, 0.0254, 0.0254 / 0.45)
LEG_METRES = 0.85


def read_rig_map(path: str | Path) -> dict[str, str]:
    """A rig map file: a JSON object, canonical body point -> joint name of the BVH (an end site as
    ``"<joint>:end"``), e.g. ``{"left_hip": "Thigh.L", "head": "Head:end"}``. Body points are the names of
    :data:`~motion2video.core.skeletons.H36M_17` (``pelvis``, ``right_hip``, ..., ``right_wrist``).

    Raises:
        InputError: a missing or malformed file, an unknown body point or a value that is not a string.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such rig map file", path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise InputError(f"not a JSON rig map ({err})", path) from None
    if not isinstance(data, dict) or not all(isinstance(v, str) for v in data.values()):
        raise InputError('a rig map is a JSON object of body point -> joint name, e.g. {"left_hip": "Thigh.L"}',
                         path)
    unknown = sorted(set(data) - set(H36M_17.joints))
    if unknown:
        raise InputError(f"unknown body point(s) {', '.join(unknown)}; the body points are "
                         f"{', '.join(H36M_17.joints)}", path)
    return dict(data)


def named_rig_mapping(clip: BvhClip, rig_map: dict[str, str] | None = None) -> dict[str, str | tuple[str, str]]:
    """Body point -> node name of a rig outside the known table: guessed from the joint names
    (:func:`~motion2video.core.skeletons.map_joint_names`), ``rig_map`` winning where it names a point.

    Raises:
        InputError: one line naming the body points no joint was found for, or a joint of ``rig_map`` the
            file lacks.
    """
    guessed, missing = map_joint_names(clip.names, clip.parents)
    given = dict(rig_map or {})
    absent = sorted({v for v in given.values() if v not in clip.names})
    if absent:
        raise InputError(f"the rig map names joint(s) the file lacks: {', '.join(absent)}", clip.path)
    missing = [m for m in missing if m not in given]
    if missing:
        raise InputError(f"cannot map this BVH rig to the body: no joint found for {', '.join(missing)}; "
                         "name them in a rig map (--rig-map FILE, JSON body point -> joint name)", clip.path)
    return {**guessed, **given}


def with_head_top(clip: BvhClip, mapping: dict[str, str | tuple[str, str]]) -> BvhClip:
    """A head-top end site of (nearly) zero length, under a tenth of the head joint's own offset (Bandai's
    rig: exactly 0), continued along the head's own bone: its offset becomes the head joint's offset from
    its parent, so it points where the head points (bones lie along the joints' rest offsets). Other clips
    are returned unchanged."""
    top = mapping.get("head")
    if not isinstance(top, str) or not top.endswith(":end"):
        return clip
    end, head = clip.index(top), clip.parents[clip.index(top)]
    head_length = float(np.linalg.norm(clip.offsets[head]))
    if head_length <= 1e-9 or np.linalg.norm(clip.offsets[end]) >= 0.1 * head_length:
        return clip
    offsets = clip.offsets.copy()
    offsets[end] = clip.offsets[head]
    return replace(clip, offsets=offsets)


def body_unit(raw: np.ndarray) -> float:
    """Metres per file unit of a rig mapped by names: the candidate of :data:`UNIT_CANDIDATES` that makes
    the median leg (thigh + shin, both sides) nearest :data:`LEG_METRES`.

    Args:
        raw: (T, 17, 3) the mapped joints in file units.
    """
    seg = lambda a, b: np.linalg.norm(raw[:, a] - raw[:, b], axis=-1)  # noqa: E731  (T,)
    leg = float(np.median(0.5 * (seg(R_HIP, R_KNEE) + seg(R_KNEE, R_ANKLE) + seg(L_HIP, L_KNEE)
                                 + seg(L_KNEE, L_ANKLE))))
    if not np.isfinite(leg) or leg <= 0:
        return 1.0
    return min(UNIT_CANDIDATES, key=lambda u: abs(np.log(leg * u / LEG_METRES)))


def up_axes(raw: np.ndarray, source: str) -> np.ndarray:
    """The (3, 3) matrix taking a rig's file axes to the project's (z up): y up (BVH's convention) or z up,
    told by the median pelvis -> neck direction over the clip.

    Args:
        raw: (T, 17, 3) the mapped joints in file units.
    Raises:
        InputError: when the body points along neither +y nor +z.
    """
    up = np.median(raw[:, NECK] - raw[:, PELVIS], axis=0)  # (3,)
    axis = int(np.argmax(np.abs(up)))
    if axis == 1 and up[1] > 0:
        return Y_UP_TO_Z_UP
    if axis == 2 and up[2] > 0:
        return np.eye(3)
    raise InputError("cannot tell the rig's up axis: its body points neither along +y nor along +z", source)


def canonical_from_nodes(nodes: np.ndarray, names: tuple[str, ...], rig: str) -> np.ndarray:
    """Pick the canonical H36M-17 joints out of per-node positions of a BVH ``rig``.

    Args:
        nodes: (T, N, 3) node positions (any units and axes).
        names: (N,) node names.
        rig: a key of :func:`rig_joint_maps`.
    Returns:
        (T, 17, 3) positions in :data:`~motion2video.core.skeletons.H36M_17` order.
    """
    return canonical_from_map(nodes, names, rig_joint_maps()[rig], body_points=rig not in BODY_POINT_RIGS)


# A BVH clip in the project frame (the shared container of every mocap reader).
CanonicalBvh = CanonicalClip


def canonical_positions(clip: BvhClip, *, rig: str | None = None, rig_map: dict[str, str] | None = None,
                        chunk: int = CHUNK_FRAMES) -> CanonicalClip:
    """Forward kinematics, rig detection, unit and axis conversion for a whole clip (no floor shift);
    ``fps`` of the result is the header's rate. Frames are posed ``chunk`` at a time (the result does not
    depend on it); the canonical body points (:func:`~motion2video.core.skeletons.h36m_body_points`) are
    then built once from the whole clip's nearest joints, as they take whole-clip medians and maxima.

    A rig outside the known table, or any rig with ``rig_map`` (:func:`read_rig_map`), is mapped from its
    joint names (:func:`named_canonical_positions`)."""
    rig = detect_rig(clip.names, clip.path) if rig is None and rig_map is None else rig
    if rig is None or rig == NAMED_JOINTS_RIG:
        return named_canonical_positions(clip, rig_map=rig_map, chunk=chunk)
    if rig not in rig_joint_maps():
        raise InputError(f"unknown rig {rig!r}; known: {', '.join(rig_joint_maps())}", clip.path)
    unit = RIG_UNITS[rig]
    nodes = np.empty((clip.num_frames, clip.num_nodes, 3))  # (T, N, 3) metres, z up, posed chunk by chunk
    for s in range(0, clip.num_frames, chunk):
        nodes[s:s + chunk] = to_project_frame(_world_positions(replace(clip, values=clip.values[s:s + chunk])),
                                              unit)
    joints = canonical_from_nodes(nodes, clip.names, rig)  # (T, 17, 3)
    return CanonicalClip(joints=joints, nodes=nodes, names=clip.names, rig=rig, unit=unit, fps=clip.header_fps)


def named_canonical_positions(clip: BvhClip, *, rig_map: dict[str, str] | None = None,
                              chunk: int = CHUNK_FRAMES) -> CanonicalClip:
    """:func:`canonical_positions` of a rig mapped from its joint names (:func:`named_rig_mapping`): a
    zero-length head end site continued along the head (:func:`with_head_top`), the unit and up axis read
    off the body (:func:`body_unit`, :func:`up_axes`), the body points built as for every rig, then held
    to Human3.6M's proportions (:data:`PROPORTION_BAND`).

    Raises:
        InputError: body points not found, or a mapping whose body fails the proportion test (one line).
    """
    mapping = named_rig_mapping(clip, rig_map)
    clip = with_head_top(clip, mapping)
    nodes = np.empty((clip.num_frames, clip.num_nodes, 3))  # (T, N, 3) file units and axes
    for s in range(0, clip.num_frames, chunk):
        nodes[s:s + chunk] = _world_positions(replace(clip, values=clip.values[s:s + chunk]))
    raw = canonical_from_map(nodes, clip.names, mapping, body_points=False)  # (T, 17, 3) file units
    unit = body_unit(raw)
    nodes = to_project_frame(nodes, unit, up_axes(raw, clip.path))  # (T, N, 3) metres, z up
    joints = canonical_from_map(nodes, clip.names, mapping)  # (T, 17, 3) on Human3.6M's body points
    ratios = proportion_ratios(joints)
    off = {k: v for k, v in ratios.items() if not PROPORTION_BAND[0] <= v <= PROPORTION_BAND[1]}
    if off:
        said = ", ".join(f"{k} {v:.2f}" for k, v in off.items())
        raise InputError(f"the joints mapped to the body give proportions outside {PROPORTION_BAND[0]}-"
                         f"{PROPORTION_BAND[1]} of Human3.6M's ({said}; mapping: "
                         + ", ".join(f"{k}={v}" for k, v in mapping.items())
                         + "); name the joints in a rig map (--rig-map FILE)", clip.path)
    return CanonicalClip(joints=joints, nodes=nodes, names=clip.names, rig=NAMED_JOINTS_RIG, unit=unit,
                         fps=clip.header_fps)


def bvh_to_canonical(
    clip: BvhClip,
    *,
    rig: str | None = None,
    fps: float | None = None,
    start: int = 0,
    frames: int | None = None,
    target_fps: float | None = None,
    label: str | None = None,
    canonical: CanonicalClip | None = None,
    rig_map: dict[str, str] | None = None,
) -> Motion:
    """Convert a parsed BVH clip to a canonical ``h36m-17`` Motion (metres, z up, floor at z = 0).

    Order of operations: forward kinematics; rig detection from joint names; units to metres with
    :data:`RIG_UNITS`; y-up -> z-up (:func:`to_project_frame`); trimming to ``[start, start + frames)`` in
    file frames; floor placement from the kept frames (:func:`floor_height`); resampling to ``target_fps``
    by linear interpolation of joint positions (adequate for positions, see :func:`resample_linear`).

    Args:
        clip: from :func:`read_bvh`.
        rig: force a rig instead of detecting it.
        fps: the true frame rate, overriding the header (e.g. from the manifest).
        start: first frame kept (in file frames).
        frames: number of file frames kept from ``start`` (None: to the end).
        target_fps: resample to this rate (None: keep the clip's rate).
        label: action label stored on the Motion.
        canonical: ``canonical_positions(clip, rig=rig)`` when the caller already has it (skips the
            forward kinematics).
        rig_map: body point -> joint name for a rig the names do not tell (:func:`read_rig_map`).
    """
    rate = clip.header_fps if fps is None else float(fps)
    if start < 0 or start >= clip.num_frames:
        raise InputError(f"start frame {start} is outside the clip (0..{clip.num_frames - 1})", clip.path)
    if canonical is None:
        canonical = canonical_positions(clip, rig=rig, rig_map=rig_map)
    elif canonical.joints.shape[0] != clip.num_frames or (rig is not None and canonical.rig != rig):
        raise ValueError("canonical= does not belong to this clip / rig")
    return canonical_motion(canonical.joints, fps=rate, source=clip.path, start=start, frames=frames,
                            target_fps=target_fps, label=label, place_floor=canonical.rig not in BODY_POINT_RIGS)




def load_bvh(
    path: str | Path,
    *,
    fps: float | None = None,
    target_fps: float | None = None,
    trim_start: int | None = None,
    frames: int | None = None,
    manifest: str | Path | ManifestEntry | bool | None = None,
    label: str | None = None,
    rig_map: dict[str, str] | None = None,
) -> Motion:
    """Load a BVH file as a canonical ``h36m-17`` Motion (metres, z up, floor at z = 0).

    Args:
        path: the .bvh file.
        fps: true frame rate; wins over the manifest and the header.
        target_fps: resample to this rate by linear interpolation of positions.
        trim_start: frames dropped at the start. None: 0, or with a manifest :func:`default_trim` of the
            detected rig (5 for ``cmu-daz``).
        frames: keep this many file frames after the trim (None: all).
        manifest: where fps and label come from when not given: a ``manifest.csv`` path, a
            :class:`ManifestEntry`, ``True`` to look for a manifest.csv listing this file in its folder or
            the folders above (:func:`find_manifest_entry`), or None / False for none.
        label: action label (wins over the manifest's).
        rig_map: body point -> joint name for a rig the names do not tell (:func:`read_rig_map`).
    """
    clip = read_bvh(path)
    entry = resolve_manifest(path, manifest)
    canonical = canonical_positions(clip, rig_map=rig_map)
    if entry is not None:
        fps = entry.fps if fps is None else fps
        label = entry.label if label is None else label
        if trim_start is None:
            trim_start = default_trim(canonical.rig)
    return bvh_to_canonical(clip, rig=canonical.rig, fps=fps, start=trim_start or 0, frames=frames,
                            target_fps=target_fps, label=label, canonical=canonical)
