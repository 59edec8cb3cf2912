"""Every file of ../shared/data/mocap (all manifest rows: BVH, DeepMimic motion files, exp-map text) is a
plausible canonical body, loaded once per session (conftest ``mocap_clips``).

Checks, each with the measure it uses:

- stature: a pose-independent estimate, ankle height + shin + thigh + the most extended pelvis-to-head
  distance (95th percentile over frames) + the skull-base-to-crown distance. It needs no standing frame, so
  crawling and rolling clips are measured too. The canonical ``head`` is the skull base for every rig except
  the DeepMimic humanoid (BVH or motion file), where it is the neck's end site, i.e. the crown (README
  table) - so the crown offset is 0.12 m (adult skull base to vertex; Anny: 0.15 m) there and 0 for
  DeepMimic. For walking clips the standing head height (median head z + crown offset) is checked as well.
- feet on the floor: the lowest toe/foot-end node over the clip is within a few cm of z = 0 (the floor is
  placed from the ankles, so this checks it against the rig's real foot geometry), and in walking clips a
  foot is near the floor in nearly every frame.
- left/right not swapped (per clip, so per rig): the body's forward direction, up x right with up =
  thorax - pelvis and right = right_hip - left_hip, must agree with (a) the direction the knees bend (a
  bent knee lies in front of the hip-ankle line), (b) the direction the feet point (ankle -> toe), and (c)
  the direction of travel in walking clips. A mirror image flips all three (tested).
- limb bone lengths constant over time; the true fps of the manifest (it overrides every file's own rate).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2video.formats.canonical import ANKLE_HEIGHT
from motion2video.formats.manifest import read_manifest
from motion2video.formats.manifest import default_trim
from motion2video.core.skeletons import H36M_17, proportion_ratios

J = {name: i for i, name in enumerate(H36M_17.joints)}
CROWN_ABOVE_HEAD = {"deepmimic-humanoid": 0.0, "deepmimic-humanoid-txt": 0.0}  # others: 0.12 m (docstring)
DEFAULT_CROWN = 0.12
# The node just past each ankle (toe joint, foot end site or toe point), per rig: (left, right).
TOE_NODES = {
    "cmu-mb": ("LeftToeBase", "RightToeBase"),
    "cmu-3dsmax": ("LeftToe", "RightToe"),
    "cmu-amc": ("ltoes", "rtoes"),
    "cmu-daz": ("lFoot:end", "rFoot:end"),
    "deepmimic-humanoid": ("left_ankle:end", "right_ankle:end"),
    "deepmimic-humanoid-txt": ("left_ankle:toe", "right_ankle:toe"),
    "mass-character1": ("Character1_LeftToeBase", "Character1_RightToeBase"),
    "cmu-bench-expmap": ("left_toe_end", "right_toe_end"),
}
LIMBS = [("right_hip", "right_knee"), ("right_knee", "right_ankle"), ("left_hip", "left_knee"),
         ("left_knee", "left_ankle"), ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
         ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist")]
# The manifest's folders and their file counts (README table).
FOLDER_FILES = {"cmu": 50, "deepmimic": 30, "mass": 8, "acrnn": 43, "deepmimic-cmu": 53, "cmu-bench": 91}


def _manifest_at_collection() -> dict:
    """The manifest, read when the module is collected (parametrisation); empty without the shared data
    (the fixtures then fail with a clear message)."""
    path = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "manifest.csv"
    return read_manifest(path) if path.is_file() else {}


CLIP_NAMES = sorted(_manifest_at_collection())
WALK_NAMES = sorted(n for n, e in _manifest_at_collection().items() if e.label.startswith("walk"))
# Walks of the CMU benchmark's walking_extra set that are not plain forward walks (measured, per file):
# they are kept out of the travel-forward / feet-down check, and still pass every other check.
NOT_PLAIN_WALKS = {
    # the pelvis path runs against the facing direction (mean cosine step . forward -0.25 to -0.62 in
    # every quarter of the clip): backwards / sideways walks.
    "cmu-bench/train/walking_extra/walking_25.txt": "walks backwards",
    "cmu-bench/train/walking_extra/walking_26.txt": "walks backwards",
    # forward for half the clip (cosine 0.96, 0.73), then backwards (-0.37, -0.36): 0.26 m net in 11 s.
    "cmu-bench/train/walking_extra/walking_24.txt": "walks forward, then backwards",
    # frames 270-360: the lower ankle rises to 0.19-0.59 m while the pelvis stays at 1.0 m (steps over
    # or onto something); feet down in 84% of frames.
    "cmu-bench/train/walking_extra/walking_48.txt": "steps over something",
}
# Measured per file: in frames 540-660 the toe ends dip 5-8.5 cm below the floor the ankles define while the
# ankles stay 7 cm up (the foot points down, as over a step edge). Their bound is 10 cm instead of 8.
TOE_TOLERANCE = {"cmu-bench/train/walking_extra/walking_23.txt": 0.10}


def test_every_file_of_the_folder_is_in_the_manifest(mocap_dir, mocap_manifest):
    suffixes = (".bvh", ".txt")
    files = sorted(p.relative_to(mocap_dir).as_posix() for p in mocap_dir.rglob("*")
                   if p.suffix in suffixes and not p.name.startswith(("LICENSE", "NOTICE"))
                   and p.name != "humanoid3d_character.txt")
    assert len(files) == len(mocap_manifest) == 275
    assert files == sorted(mocap_manifest)
    folders = {}
    for name in mocap_manifest:
        folders[name.split("/")[0]] = folders.get(name.split("/")[0], 0) + 1
    assert folders == FOLDER_FILES


def stature(joints: np.ndarray, rig: str) -> float:
    """Pose-independent standing-height estimate (see the module docstring), metres."""
    def length(a: str, b: str) -> float:
        return float(np.median(np.linalg.norm(joints[:, J[a]] - joints[:, J[b]], axis=-1)))

    legs = (length("right_hip", "right_knee") + length("right_knee", "right_ankle")
            + length("left_hip", "left_knee") + length("left_knee", "left_ankle")) / 2
    hip_mid = (joints[:, J["right_hip"]] + joints[:, J["left_hip"]]) / 2
    trunk = float(np.percentile(np.linalg.norm(joints[:, J["head"]] - hip_mid, axis=-1), 95))
    return ANKLE_HEIGHT + legs + trunk + CROWN_ABOVE_HEAD.get(rig, DEFAULT_CROWN)


def body_forward(joints: np.ndarray) -> np.ndarray:
    """(T, 3) unit forward direction: up x right, up = thorax - pelvis, right = right_hip - left_hip."""
    up = joints[:, J["thorax"]] - joints[:, J["pelvis"]]
    right = joints[:, J["right_hip"]] - joints[:, J["left_hip"]]
    forward = np.cross(up, right)
    return forward / np.linalg.norm(forward, axis=-1, keepdims=True)


def knee_agreement(joints: np.ndarray, side: str, forward: np.ndarray) -> tuple[float, int]:
    """Fraction of clearly bent frames (knee angle < 150 deg) whose knee lies in front of hip-ankle."""
    hip, knee, ankle = (joints[:, J[f"{side}_{n}"]] for n in ("hip", "knee", "ankle"))
    u, v = hip - knee, ankle - knee
    cos = np.sum(u * v, -1) / (np.linalg.norm(u, axis=-1) * np.linalg.norm(v, axis=-1))
    bent = np.degrees(np.arccos(np.clip(cos, -1, 1))) < 150
    ahead = np.sum((knee - (hip + ankle) / 2) * forward, axis=-1) > 0
    return (float(ahead[bent].mean()) if bent.any() else float("nan")), int(bent.sum())


@pytest.mark.slow
@pytest.mark.parametrize("name", CLIP_NAMES)
def test_real_clip_is_a_plausible_body(mocap_clips, name):
    c = mocap_clips[name]
    m, rig = c.motion, c.canonical.rig
    x = m.joints.astype(np.float64)
    assert m.skeleton == "h36m-17" and x.shape[1:] == (17, 3)
    assert m.label == c.entry.label
    # Frames: the default trim for cmu-daz (cmu/ and acrnn/), none otherwise.
    assert m.num_frames == c.canonical.num_frames - default_trim(rig)
    # fps: the manifest's true rate; the file's own rate where the manifest has none.
    assert m.fps == (c.entry.fps if c.entry.fps is not None else c.canonical.fps)

    h = stature(x, rig)
    assert 1.4 < h < 2.0, f"stature {h:.2f} m"

    # Human3.6M's body points (skeleton version 2): the four proportions within 0.8-1.25 of Human3.6M's.
    for key, value in proportion_ratios(x).items():
        assert 0.8 <= value <= 1.25, f"{key} is {value:.2f} of Human3.6M's"

    # Limbs are rigid: every canonical limb maps to one bone (no joint in between).
    for a, b in LIMBS:
        length = np.linalg.norm(x[:, J[a]] - x[:, J[b]], axis=-1)
        assert length.std() < 1e-3, f"{a}-{b} length varies by {length.std() * 1000:.2f} mm"
        assert 0.15 < length.mean() < 0.6

    # Feet: the rig's toe / foot-end nodes reach the floor the ankles define, within a few cm. Clips whose
    # notes name a pose glitch (a few frames with a joint faster than 12 m/s, where feet may dip below
    # the floor) are measured at their 1st percentile instead of the minimum.
    low = (lambda v: float(np.percentile(v, 1))) if "glitch" in c.entry.notes else (lambda v: float(v.min()))
    toe_ids = [c.canonical.index(n) for n in TOE_NODES[rig]]
    lowest_toe = low(c.nodes[:, toe_ids, 2].min(axis=1))
    assert abs(lowest_toe) < TOE_TOLERANCE.get(name, 0.08), f"lowest toe at {lowest_toe:.3f} m"
    lowest_ankle = low(x[:, [J["right_ankle"], J["left_ankle"]], 2].min(axis=1))
    assert ANKLE_HEIGHT - 0.06 < lowest_ankle <= ANKLE_HEIGHT + 1e-5

    # Chirality (a): knees bend forward.
    forward = body_forward(x)
    for side in ("left", "right"):
        agree, bent = knee_agreement(x, side, forward)
        if bent >= 5:
            assert agree > 0.75, f"{side} knee bends forward in only {agree:.0%} of {bent} bent frames"
    # Chirality (b): feet point forward (median over frames of ankle -> toe along forward).
    for side, toe_id in zip(("left", "right"), toe_ids):
        foot = c.nodes[:, toe_id] - x[:, J[f"{side}_ankle"]]
        assert np.median(np.sum(foot * forward, axis=-1)) > 0, f"{side} foot points backwards"


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in WALK_NAMES if n not in NOT_PLAIN_WALKS])
def test_walking_clips_stand_travel_forward_and_touch_the_floor(mocap_clips, name):
    c = mocap_clips[name]
    x = c.motion.joints.astype(np.float64)
    head = float(np.median(x[:, J["head"], 2])) + CROWN_ABOVE_HEAD.get(c.canonical.rig, DEFAULT_CROWN)
    assert 1.4 < head < 2.0, f"standing head height {head:.2f} m"
    # Chirality (c): the pelvis travels the way the body faces.
    step = np.diff(x[:, J["pelvis"], :2], axis=0)  # (T-1, 2)
    along = np.sum(step * body_forward(x)[1:, :2], axis=-1).sum() / np.linalg.norm(step, axis=-1).sum()
    assert along > 0.5, f"only {along:.0%} of the path goes forward"
    if "uneven" not in c.entry.label:
        lower_ankle = x[:, [J["right_ankle"], J["left_ankle"]], 2].min(axis=1)
        assert np.mean(lower_ankle < ANKLE_HEIGHT + 0.10) > 0.9


@pytest.mark.slow
def test_chirality_checks_detect_a_mirror_image(mocap_clips):
    for name in ("cmu/16_11.bvh", "cmu-bench/test/walking/walking_1.txt", "deepmimic-cmu/07_03.txt"):
        c = mocap_clips[name]  # a walk of each rig family
        mirrored = c.motion.joints.astype(np.float64) * np.array([-1.0, 1.0, 1.0])  # reflect, keep names
        forward = body_forward(mirrored)
        for side in ("left", "right"):
            agree, bent = knee_agreement(mirrored, side, forward)
            assert bent > 10 and agree < 0.1, (name, side)


@pytest.mark.slow
def test_true_rates_per_source(mocap_clips):
    """The manifest's fps is the truth; the files say otherwise for salsa and the subject-88 files."""
    rates = {name: c.motion.fps for name, c in mocap_clips.items()}
    stated = {name: c.canonical.fps for name, c in mocap_clips.items()}
    assert {rates[n] for n in rates if n.startswith("acrnn/salsa")} == {60.0}
    assert {stated[n] for n in rates if n.startswith("acrnn/salsa")} == {120.0}
    assert {rates[n] for n in rates if n.startswith(("acrnn/indian", "acrnn/martial"))} == {120.0}
    for n in ("deepmimic-cmu/88_06.txt", "deepmimic-cmu/88_08.txt", "deepmimic-cmu/88_09.txt"):
        assert stated[n] == 30.0 and rates[n] == 15.0
    assert {rates[n] for n in rates if n.startswith("cmu-bench/")} == {120.0}
    assert rates["deepmimic/txt/humanoid3d_backflip.txt"] == 16.0  # 1 / frame duration
    # The subject-88 files at 15 fps: the pelvis falls at about g in the flight of 88_06's jump, and its
    # ankles stay below 10 m/s (at 30 fps they would peak at 14-18 m/s).
    x = mocap_clips["deepmimic-cmu/88_06.txt"].motion.joints.astype(np.float64)
    ankle_speed = np.linalg.norm(np.diff(x[:, [3, 6]], axis=0), axis=-1) * 15.0
    assert np.percentile(ankle_speed, 99) < 10.0


@pytest.mark.slow
def test_cmu_bench_rest_line_is_dropped_and_matches_its_bvh_twin(mocap_clips):
    """cmu-bench train walking_1 is CMU 02_01: the same trial as cmu/02_01.bvh frame for frame (line 0 of
    the exp-map file is a rest pose, frame 0 of the BVH its T-pose; the BVH drops 5 frames)."""
    bench = mocap_clips["cmu-bench/train/walking/walking_1.txt"]
    twin = mocap_clips["cmu/02_01.bvh"]
    assert bench.canonical.num_frames == 343 and twin.canonical.num_frames == 344
    a = bench.canonical.joints[4:]  # bench line k + 1 = BVH frame k + 1; the BVH keeps frames 5..
    b = twin.canonical.joints[5:]
    pelvis_gap = np.linalg.norm(a[:, 0, :2] - b[:, 0, :2], axis=-1)  # different skeletons, same path
    assert np.median(pelvis_gap) < 0.1
