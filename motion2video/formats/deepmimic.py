"""DeepMimic motion files (JSON ``{"Loop": ..., "Frames": [[...], ...]}``) with the skeleton read from a
DeepMimic character file, converted to the canonical H36M-17 body.

The skeleton is data: :func:`read_character` reads any DeepMimic character file (``Skeleton.Joints``: name,
parent, type, ``AttachX/Y/Z`` offset in the parent's frame, metres, y up). A frame of a motion file holds
the frame duration (s), the root position (3), the root rotation quaternion (w, x, y, z), then one entry
per non-root joint in character order: a quaternion (w, x, y, z) for ``spherical`` joints, one angle
(radians, about the local z axis) for ``revolute`` joints, nothing for ``fixed`` joints.

Forward kinematics: a joint's world rotation is its parent's world rotation times its own; its position is
the parent's position plus the parent's world rotation applied to the joint's attach offset.

The canonical joints (:data:`DEEPMIMIC_CANONICAL`) are the humanoid's joints by name; the spine is the
midpoint of root and chest, the wrists are the ``fixed`` wrist joints and the head is a point
:data:`HEAD_OFFSET` above the neck joint in the neck's frame (the end site the ``deepmimic-humanoid`` BVH
rig uses, so the BVH twins of ``deepmimic/txt/*.txt`` give the same joints). Each foot gets a toe point,
the front-bottom corner of the foot box in the character's ``BodyDefs``.

The character file: ``character=`` when given; otherwise (:func:`find_character`)

- ``humanoid3d_character.txt`` in the motion file's folder, a ``deepmimic/`` sibling of it, or the same two
  places in up to two folders above (covers ``deepmimic/txt/`` and ``deepmimic-cmu/`` in the shared data);
- the DeepMimic repository's layout: motions in ``data/motions/*.txt``, the character in
  ``data/characters/humanoid3d.txt``, i.e. ``../characters/humanoid3d.txt`` from the motion's folder;
- else the standard DeepMimic ``humanoid3d`` character shipped with the package
  (:data:`DEFAULT_CHARACTER`, zlib licence beside it), with a note on stderr.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from motion2video.core.errors import InputError
from motion2video.formats.canonical import CanonicalClip, canonical_from_map, canonical_motion, to_project_frame
from motion2video.formats.manifest import ManifestEntry, resolve_manifest
from motion2video.formats.resample import round_fps
from motion2video.core.motion import Motion

RIG = "deepmimic-humanoid-txt"
CHARACTER_FILE = "humanoid3d_character.txt"
# The DeepMimic repository keeps motions in data/motions/ and the character in data/characters/.
REPOSITORY_CHARACTER = Path("..") / "characters" / "humanoid3d.txt"
# DeepMimic's standard humanoid3d character (pybullet 3.2.7 wheel, zlib: data/LICENSE-humanoid3d.txt).
DEFAULT_CHARACTER = Path(__file__).resolve().parent / "data" / "humanoid3d.txt"
JOINT_DOFS = {"none": 0, "spherical": 4, "revolute": 1, "fixed": 0}
# The head: this far above the neck joint along the neck's local y, metres (the deepmimic-humanoid BVH
# rig's neck end site).
HEAD_OFFSET = (0.0, 0.20, 0.0)
DEEPMIMIC_CANONICAL: dict[str, str | tuple[str, ...]] = {
    "pelvis": "root", "right_hip": "right_hip", "right_knee": "right_knee", "right_ankle": "right_ankle",
    "left_hip": "left_hip", "left_knee": "left_knee", "left_ankle": "left_ankle",
    "spine": ("root", "chest"), "thorax": "chest", "neck": "neck", "head": "neck:end",
    "left_shoulder": "left_shoulder", "left_elbow": "left_elbow", "left_wrist": "left_wrist",
    "right_shoulder": "right_shoulder", "right_elbow": "right_elbow", "right_wrist": "right_wrist",
}


@dataclass(frozen=True)
class Character:
    """A DeepMimic skeleton.

    Attributes:
        path: the character file.
        names: (N,) joint names in file order (the root first).
        parents: (N,) parent index, -1 for the root; parents precede children.
        types: (N,) joint type: ``none`` (root), ``spherical``, ``revolute`` or ``fixed``.
        offsets: (N, 3) attach offsets in the parent's frame, metres, y up.
        toes: ``{ankle joint name: (3,) toe point in that joint's frame}`` from the foot boxes.
    """

    path: str
    names: tuple[str, ...]
    parents: tuple[int, ...]
    types: tuple[str, ...]
    offsets: np.ndarray
    toes: dict

    @property
    def values_per_frame(self) -> int:
        """Numbers per motion frame: duration, root position and quaternion, then the joints' dofs."""
        return 1 + 3 + 4 + sum(JOINT_DOFS[t] for t in self.types[1:])


@dataclass(frozen=True)
class DeepMimicClip:
    """A motion file as written.

    Attributes:
        path: the file.
        durations: (T,) seconds per frame (the last frame's is often 0: it ends the clip).
        values: (T, V) the rest of each frame (root position, root quaternion, joint rotations).
        loop: the ``Loop`` field.
    """

    path: str
    durations: np.ndarray
    values: np.ndarray
    loop: str

    @property
    def num_frames(self) -> int:
        return int(self.values.shape[0])

    @property
    def file_fps(self) -> float:
        """1 / the first frame's duration (rounded to an integer rate when within 0.1% of one)."""
        return round_fps(1.0 / float(self.durations[0]))


def _load_json(path: Path, what: str):
    if not path.is_file():
        raise InputError("no such file", path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(f"not a text file ({what} is JSON text)", path) from None
    except json.JSONDecodeError as err:
        raise InputError(f"not valid JSON ({what}): line {err.lineno}: {err.msg}", path) from None
    except RecursionError:  # json's decoder recurses once per nesting level
        raise InputError(f"not valid JSON ({what}): nested too deeply", path) from None


def read_character(path: str | Path) -> Character:
    """Read a DeepMimic character file. Raises InputError when it is not one."""
    path = Path(path)
    data = _load_json(path, "a DeepMimic character file")
    try:
        joints = data["Skeleton"]["Joints"]
        names = tuple(str(j["Name"]) for j in joints)
        parents = tuple(int(j["Parent"]) for j in joints)
        types = tuple(str(j["Type"]) for j in joints)
        offsets = np.array([[float(j["AttachX"]), float(j["AttachY"]), float(j["AttachZ"])] for j in joints])
        thetas = np.array([[float(j.get(f"AttachTheta{a}", 0.0)) for a in "XYZ"] for j in joints])
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"not a DeepMimic character file (Skeleton.Joints: {err})", path) from None
    if not names or parents[0] != -1 or any(not -1 <= p < j for j, p in enumerate(parents)) or -1 in parents[1:]:
        raise InputError("character joints must start at one root and list parents before children", path)
    unknown = sorted(set(types[1:]) - set(JOINT_DOFS))
    if unknown:
        raise InputError(f"unsupported joint type(s) {', '.join(unknown)}", path)
    if np.any(thetas != 0):
        raise InputError("joints with a non-zero AttachTheta are not supported", path)
    toes = {}
    for body in data.get("BodyDefs", []):
        if body.get("Shape") == "box" and body.get("Name") in names and "ankle" in str(body.get("Name")):
            size = np.array([float(body["Param0"]), float(body["Param1"]), float(body["Param2"])])
            centre = np.array([float(body["AttachX"]), float(body["AttachY"]), float(body["AttachZ"])])
            toes[body["Name"]] = centre + np.array([size[0] / 2, -size[1] / 2, 0.0])  # front, bottom
    missing = sorted({n for v in DEEPMIMIC_CANONICAL.values() for n in (v if isinstance(v, tuple) else (v,))}
                     - set(names) - {"neck:end"})
    if missing:
        raise InputError(f"character lacks the joint(s) {', '.join(missing)} the canonical body needs", path)
    return Character(path=str(path), names=names, parents=parents, types=types, offsets=offsets, toes=toes)


def read_deepmimic(path: str | Path, character: Character) -> DeepMimicClip:
    """Read a DeepMimic motion file whose frames fit ``character``. Raises InputError when malformed."""
    path = Path(path)
    data = _load_json(path, "a DeepMimic motion file")
    if not isinstance(data, dict) or "Frames" not in data:
        raise InputError("not a DeepMimic motion file (no \"Frames\" list)", path)
    frames = data["Frames"]
    if not isinstance(frames, list) or not frames:
        raise InputError("the motion is empty (no frames)", path)
    width = character.values_per_frame
    for i, row in enumerate(frames):
        if not isinstance(row, list) or len(row) != width:
            got = len(row) if isinstance(row, list) else type(row).__name__
            hint = "; pass --character FILE, the motion's character" if character.path == str(DEFAULT_CHARACTER) else ""
            raise InputError(f"frame {i}: expected {width} numbers for the character "
                             f"{Path(character.path).name}, got {got}{hint}", path)
    try:
        values = np.array(frames, dtype=np.float64)  # (T, width)
    except (TypeError, ValueError):
        raise InputError("a frame value is not a number", path) from None
    if not np.all(np.isfinite(values)):
        bad = int(np.argwhere(~np.isfinite(values))[0, 0])
        raise InputError(f"frame {bad}: values contain NaN or Inf", path)
    if values[0, 0] <= 0:
        raise InputError(f"frame 0: the frame duration must be positive, got {values[0, 0]}", path)
    return DeepMimicClip(path=str(path), durations=values[:, 0], values=values[:, 1:],
                         loop=str(data.get("Loop", "")))


def _quat_matrices(q: np.ndarray, source: str) -> np.ndarray:
    """(..., 4) quaternions (w, x, y, z), normalised -> (..., 3, 3)."""
    norm = np.linalg.norm(q, axis=-1)
    if np.any(norm < 1e-6):
        raise InputError("a rotation quaternion is zero", source)
    flat = q.reshape(-1, 4)
    return Rotation.from_quat(flat, scalar_first=True).as_matrix().reshape(q.shape[:-1] + (3, 3))


def deepmimic_world_positions(clip: DeepMimicClip, character: Character) -> tuple[np.ndarray, tuple[str, ...]]:
    """Forward kinematics of every joint plus the head and toe points.

    Returns:
        (T, N + 1 + toes, 3) positions in metres, y up (the file's frame), and their names (the joints,
        ``"neck:end"``, ``"<ankle>:toe"``).
    """
    num, n = clip.num_frames, len(character.names)
    rot = np.empty((num, n, 3, 3))
    pos = np.empty((num, n, 3))
    pos[:, 0] = clip.values[:, 0:3]
    rot[:, 0] = _quat_matrices(clip.values[:, 3:7], clip.path)
    col = 7
    for j in range(1, n):
        kind = character.types[j]
        if kind == "spherical":
            local = _quat_matrices(clip.values[:, col:col + 4], clip.path)
        elif kind == "revolute":
            local = Rotation.from_rotvec(np.outer(clip.values[:, col], [0.0, 0.0, 1.0])).as_matrix()
        else:
            local = np.broadcast_to(np.eye(3), (num, 3, 3))
        col += JOINT_DOFS[kind]
        p = character.parents[j]
        pos[:, j] = pos[:, p] + rot[:, p] @ character.offsets[j]
        rot[:, j] = rot[:, p] @ local
    neck = character.names.index("neck")
    extra = [pos[:, neck] + rot[:, neck] @ np.array(HEAD_OFFSET)]
    names = list(character.names) + ["neck:end"]
    for ankle, toe in character.toes.items():
        a = character.names.index(ankle)
        extra.append(pos[:, a] + rot[:, a] @ toe)
        names.append(f"{ankle}:toe")
    return np.concatenate([pos, np.stack(extra, axis=1)], axis=1), tuple(names)


def deepmimic_canonical(clip: DeepMimicClip, character: Character) -> CanonicalClip:
    """A whole clip in the project frame (metres, z up), before trimming and floor placement."""
    nodes, names = deepmimic_world_positions(clip, character)
    nodes = to_project_frame(nodes, 1.0)  # (T, N', 3), y up -> z up
    joints = canonical_from_map(nodes, names, DEEPMIMIC_CANONICAL)
    return CanonicalClip(joints=joints, nodes=nodes, names=names, rig=RIG, unit=1.0, fps=clip.file_fps)


def find_character(motion_path: str | Path, *, levels: int = 3) -> Path | None:
    """The character file for a motion file (see the module docstring), or None when there is none."""
    folder = Path(motion_path).resolve().parent
    for parent in [folder, *list(folder.parents)[:levels - 1]]:
        for candidate in (parent / CHARACTER_FILE, parent / "deepmimic" / CHARACTER_FILE):
            if candidate.is_file():
                return candidate
    candidate = (folder / REPOSITORY_CHARACTER).resolve()
    return candidate if candidate.is_file() else None


def resolve_character(motion_path: str | Path, character: str | Path | Character | None = None) -> Character:
    """The character for ``motion_path``: ``character`` when given (a path or a :class:`Character`), else
    :func:`find_character`, else :data:`DEFAULT_CHARACTER` with a note on stderr."""
    if isinstance(character, Character):
        return character
    if character is not None:
        if not Path(character).is_file():
            raise InputError("no such character file", character)
        return read_character(character)
    found = find_character(motion_path)
    if found is not None:
        return read_character(found)
    print(f"note: {motion_path}: no DeepMimic character file beside it ({CHARACTER_FILE}, or "
          f"{REPOSITORY_CHARACTER.as_posix()} as the DeepMimic repository lays it out); using the standard "
          "humanoid3d character (pass --character FILE for another)", file=sys.stderr)
    return read_character(DEFAULT_CHARACTER)


def load_deepmimic(
    path: str | Path,
    *,
    character: str | Path | Character | None = None,
    fps: float | None = None,
    target_fps: float | None = None,
    frames: int | None = None,
    manifest: str | Path | ManifestEntry | bool | None = None,
    label: str | None = None,
) -> Motion:
    """Load a DeepMimic motion file as a canonical ``h36m-17`` Motion (metres, z up, floor at z = 0).

    Args:
        path: the motion file (``.txt``, JSON).
        character: the character file or a :class:`Character` (None: :func:`resolve_character`).
        fps: the true frame rate; wins over the manifest and the file (1 / the frame duration).
        target_fps: resample to this rate (linear interpolation of positions).
        frames: keep this many frames (None: all).
        manifest: as in :func:`motion2video.formats.bvh.load_bvh` (fps and label).
        label: action label (wins over the manifest's).
    """
    character = resolve_character(path, character)
    clip = read_deepmimic(path, character)
    entry = resolve_manifest(path, manifest)
    if entry is not None:
        fps = entry.fps if fps is None else fps
        label = entry.label if label is None else label
    canon = deepmimic_canonical(clip, character)
    return canonical_motion(canon.joints, fps=canon.fps if fps is None else float(fps), source=clip.path,
                            frames=frames, target_fps=target_fps, label=label)
