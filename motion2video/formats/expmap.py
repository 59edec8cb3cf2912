"""Exponential-map motion text files (one frame of comma-separated numbers per line), as the motion-
prediction benchmarks store them (CMU: Li et al. 2018; Human3.6M: Martinez et al. 2017), converted to the
canonical H36M-17 body.

The skeleton and the column layout are data, a JSON layout file (:class:`ExpmapLayout`, e.g.
``cmu-bench/skeleton.json``): parents, offsets (file units), which columns hold the root position and each
joint's exponential map, metres per unit, the file's up / forward / left axes, the frame rate, a rest-pose
line to skip and which skeleton joints are the canonical H36M-17 ones. Another layout (Human3.6M's 99
numbers, 32 joints) is another such file.

Forward kinematics, with row vectors as the benchmark's code writes it: ``R_i = E(e_i) R_parent``,
``p_i = o_i R_parent + p_parent``, the root at its position column plus its offset with ``R_0 = E(e_0)``,
where ``E`` is Rodrigues' formula. A joint whose exp-map columns are ``null`` does not rotate.

The layout file: ``layout=`` when given; otherwise ``skeleton.json`` in the motion file's folder or up to
three folders above (:func:`find_layout`), which covers ``cmu-bench/{train,test}/<action>/`` in the shared
data.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from motion2video.errors import InputError
from motion2video.formats.canonical import CanonicalClip, canonical_motion, to_project_frame
from motion2video.formats.manifest import ManifestEntry, resolve_manifest
from motion2video.formats.numbers import parse_number_rows
from motion2video.motion import Motion
from motion2video.core.skeletons import H36M_17, h36m_body_points

LAYOUT_FILE = "skeleton.json"


@dataclass(frozen=True)
class ExpmapLayout:
    """The skeleton and column layout of an exp-map text format.

    Attributes:
        path: the layout file.
        name: the rig name results carry (``"<folder>-expmap"``, e.g. ``"cmu-bench-expmap"``).
        values_per_frame: numbers per line.
        root_position_columns: (3,) columns of the root position.
        expmap_columns: (N,) per joint its three exp-map columns, or None (no rotation).
        parents: (N,) parent index, -1 for the root; parents precede children.
        offsets: (N, 3) offsets in the parent's frame, file units.
        unit: metres per file unit.
        axes: (3, 3) file axes -> project axes (left -> +x, forward -> -y, up -> +z).
        fps: the rate the files are captured at.
        rest_pose_lines: lines at the start of every file that are not motion.
        canonical: (17,) skeleton joint index of each H36M-17 joint, in canonical order.
        toe_ends: (left, right) joint indices of the toe ends, or None.
    """

    path: str
    name: str
    values_per_frame: int
    root_position_columns: tuple[int, int, int]
    expmap_columns: tuple[tuple[int, int, int] | None, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray
    unit: float
    axes: np.ndarray
    fps: float
    rest_pose_lines: int
    canonical: tuple[int, ...]
    toe_ends: tuple[int, int] | None

    @property
    def num_joints(self) -> int:
        return len(self.parents)

    @property
    def node_names(self) -> tuple[str, ...]:
        """Node names: ``joint<i>``, with the canonical and toe joints named after their role."""
        names = [f"joint{i}" for i in range(self.num_joints)]
        for joint, i in zip(H36M_17.joints, self.canonical):
            names[i] = joint
        if self.toe_ends is not None:
            names[self.toe_ends[0]], names[self.toe_ends[1]] = "left_toe_end", "right_toe_end"
        return tuple(names)


def _axes_matrix(up: int, forward: int, left: int) -> np.ndarray:
    """(3, 3) matrix taking file coordinates to project ones: left -> +x, forward -> -y, up -> +z."""
    if sorted((up, forward, left)) != [0, 1, 2]:
        raise ValueError("up, forward and left must be three different axes 0, 1, 2")
    m = np.zeros((3, 3))
    m[0, left], m[1, forward], m[2, up] = 1.0, -1.0, 1.0
    return m


def read_expmap_layout(path: str | Path) -> ExpmapLayout:
    """Read an exp-map layout file (JSON). Raises InputError when a field is missing or inconsistent."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
        parents = tuple(int(p) for p in d["parents"])
        n = len(parents)
        cols = tuple(None if c is None else tuple(int(x) for x in c) for c in d["expmap_columns"])
        index = d["h36m17_joint_index"]
        toes = d.get("toe_end_index")
        layout = ExpmapLayout(
            path=str(path),
            name=f"{path.resolve().parent.name}-expmap",
            values_per_frame=int(d["values_per_frame"]),
            root_position_columns=tuple(int(c) for c in d["root_position_columns"]),
            expmap_columns=cols,
            parents=parents,
            offsets=np.array(d["offsets"], dtype=np.float64).reshape(n, 3),
            unit=float(d["metres_per_unit"]),
            axes=_axes_matrix(int(d["up_axis"]), int(d["forward_axis"]), int(d["left_axis"])),
            fps=float(d["fps"]),
            rest_pose_lines=0 if d.get("rest_pose_line") is None else int(d["rest_pose_line"]) + 1,
            canonical=tuple(int(index[j]) for j in H36M_17.joints),
            toe_ends=None if toes is None else (int(toes["left"]), int(toes["right"])),
        )
    except (KeyError, TypeError, ValueError, json.JSONDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"not an exp-map layout file ({type(err).__name__}: {err})", path) from None
    width = layout.values_per_frame
    used = [c for c in layout.root_position_columns] + [c for cs in cols if cs for c in cs]
    problems = []
    if len(cols) != n or any(c is not None and len(c) != 3 for c in cols):
        problems.append("expmap_columns needs three columns (or null) per joint")
    if len(layout.root_position_columns) != 3 or not all(0 <= c < width for c in used):
        problems.append(f"columns must lie in 0..{width - 1}")
    if parents[0] != -1 or any(not 0 <= p < j for j, p in enumerate(parents) if j):
        problems.append("parents must start with one root (-1) and list parents before children")
    if not all(0 <= i < n for i in layout.canonical) or layout.unit <= 0 or layout.fps <= 0:
        problems.append("joint indices, metres_per_unit and fps must be valid")
    if problems:
        raise InputError(f"bad exp-map layout: {problems[0]}", path)
    return layout


def find_layout(motion_path: str | Path, *, levels: int = 4) -> Path:
    """The layout file for a motion file (see the module docstring). Raises InputError when none."""
    folder = Path(motion_path).resolve().parent
    for parent in [folder, *list(folder.parents)[:levels - 1]]:
        if (parent / LAYOUT_FILE).is_file():
            return parent / LAYOUT_FILE
    raise InputError(f"no exp-map layout file ({LAYOUT_FILE}) in the motion file's folder or above it; "
                     "pass layout=", motion_path)


def read_expmap_values(path: str | Path, layout: ExpmapLayout) -> np.ndarray:
    """The motion lines of an exp-map text file (rest-pose lines dropped).

    Returns:
        (T, values_per_frame) float64.
    Raises:
        InputError: a missing, non-text or ragged file, a non-number, or no motion lines.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError("not a text file (exp-map motion is comma-separated text)", path) from None
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()]
    values = parse_number_rows(lines, layout.values_per_frame, str(path), delimiter=",")  # (T + rest, V)
    values = values[layout.rest_pose_lines:]
    if values.shape[0] == 0:
        raise InputError(f"no motion lines after the {layout.rest_pose_lines} rest-pose line(s)", path)
    return values


def expmap_world_positions(values: np.ndarray, layout: ExpmapLayout) -> np.ndarray:
    """Forward kinematics of every joint (module docstring).

    Args:
        values: (T, values_per_frame) motion lines.
    Returns:
        (T, N, 3) positions in file units and axes.
    """
    num = values.shape[0]
    pos = np.empty((num, layout.num_joints, 3))
    rot = np.empty((num, layout.num_joints, 3, 3))
    for j, (p, cols) in enumerate(zip(layout.parents, layout.expmap_columns)):
        local = (np.broadcast_to(np.eye(3), (num, 3, 3)) if cols is None
                 else Rotation.from_rotvec(values[:, list(cols)]).as_matrix())  # (T, 3, 3), E(e_j)
        if p < 0:
            rot[:, j] = local
            pos[:, j] = values[:, list(layout.root_position_columns)] + layout.offsets[j]
        else:
            rot[:, j] = local @ rot[:, p]
            pos[:, j] = layout.offsets[j] @ rot[:, p] + pos[:, p]  # row vector times (T, 3, 3)
    return pos


def expmap_canonical(values: np.ndarray, layout: ExpmapLayout) -> CanonicalClip:
    """A whole clip in the project frame (metres, z up), before trimming and floor placement."""
    nodes = to_project_frame(expmap_world_positions(values, layout), layout.unit, layout.axes)  # (T, N, 3)
    joints = h36m_body_points(nodes[:, list(layout.canonical)])  # (T, 17, 3) on Human3.6M's body points
    return CanonicalClip(joints=joints, nodes=nodes, names=layout.node_names, rig=layout.name,
                         unit=layout.unit, fps=layout.fps)


def load_expmap(
    path: str | Path,
    *,
    layout: str | Path | ExpmapLayout | None = None,
    fps: float | None = None,
    target_fps: float | None = None,
    frames: int | None = None,
    manifest: str | Path | ManifestEntry | bool | None = None,
    label: str | None = None,
) -> Motion:
    """Load an exp-map text file as a canonical ``h36m-17`` Motion (metres, z up, floor at z = 0).

    Args:
        path: the motion file.
        layout: the layout file or an :class:`ExpmapLayout` (None: :func:`find_layout`).
        fps: the true frame rate; wins over the manifest and the layout.
        target_fps: resample to this rate (linear interpolation of positions).
        frames: keep this many motion frames (None: all).
        manifest: as in :func:`motion2video.formats.bvh.load_bvh` (fps and label).
        label: action label (wins over the manifest's).
    """
    if not isinstance(layout, ExpmapLayout):
        layout = read_expmap_layout(find_layout(path) if layout is None else layout)
    values = read_expmap_values(path, layout)
    entry = resolve_manifest(path, manifest)
    if entry is not None:
        fps = entry.fps if fps is None else fps
        label = entry.label if label is None else label
    canon = expmap_canonical(values, layout)
    return canonical_motion(canon.joints, fps=layout.fps if fps is None else float(fps), source=str(path),
                            frames=frames, target_fps=target_fps, label=label)
