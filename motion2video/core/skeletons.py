"""Joint sets as data.

Every skeleton is a :class:`Skeleton`: joint names, the parent of each joint (-1 for the root) and the
left/right pairs used for mirroring. The canonical body skeleton of the project is ``h36m-17`` in the
VideoPose3D / DLow order (index 1 is the RIGHT hip)::

    0 pelvis  1 right_hip  2 right_knee  3 right_ankle  4 left_hip  5 left_knee  6 left_ankle
    7 spine   8 thorax     9 neck (nose) 10 head
    11 left_shoulder 12 left_elbow 13 left_wrist 14 right_shoulder 15 right_elbow 16 right_wrist

World coordinates are metres, right-handed, z up. The BVH rig maps (:data:`RIG_JOINT_MAPS`) say which BVH
joint's origin sits at each canonical joint; ``None`` entries are derived by :func:`rig_target` rules
(a midpoint of two joints or an end site).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2video.core.errors import InputError


# Named joint indices of the canonical H36M-17 skeleton (checked against :data:`H36M_17`'s names below).
PELVIS, R_HIP, R_KNEE, R_ANKLE, L_HIP, L_KNEE, L_ANKLE = 0, 1, 2, 3, 4, 5, 6
SPINE, THORAX, NECK, HEAD = 7, 8, 9, 10
L_SHOULDER, L_ELBOW, L_WRIST, R_SHOULDER, R_ELBOW, R_WRIST = 11, 12, 13, 14, 15, 16


@dataclass(frozen=True)
class Skeleton:
    """A joint topology.

    Attributes:
        name: registry name, e.g. ``"h36m-17"``.
        joints: joint names, in array order.
        parents: parent index per joint, -1 for the root.
        mirror_pairs: (left, right) index pairs swapped by left/right mirroring.
    """

    name: str
    joints: tuple[str, ...]
    parents: tuple[int, ...]
    mirror_pairs: tuple[tuple[int, int], ...] = ()

    def __post_init__(self) -> None:
        if len(self.joints) != len(self.parents):
            raise ValueError(f"skeleton {self.name}: {len(self.joints)} names but {len(self.parents)} parents")
        for j, p in enumerate(self.parents):
            if p >= j:
                raise ValueError(f"skeleton {self.name}: parent of joint {j} must come before it, got {p}")

    @property
    def num_joints(self) -> int:
        return len(self.joints)

    def index(self, joint: str) -> int:
        return self.joints.index(joint)

    @property
    def bones(self) -> list[tuple[int, int]]:
        """(parent, child) index pairs, one per non-root joint."""
        return [(p, j) for j, p in enumerate(self.parents) if p >= 0]

    def mirror_permutation(self) -> np.ndarray:
        """Index array that swaps left and right joints: ``joints[..., perm, :]`` mirrors names."""
        perm = np.arange(self.num_joints)
        for a, b in self.mirror_pairs:
            perm[a], perm[b] = b, a
        return perm

    def side(self, j: int) -> str:
        """``"left"``, ``"right"`` or ``"center"`` for joint ``j``, from its name."""
        name = self.joints[j].lower()
        if name.startswith("left") or name.startswith("l_"):
            return "left"
        if name.startswith("right") or name.startswith("r_"):
            return "right"
        return "center"


H36M_17 = Skeleton(
    name="h36m-17",
    joints=(
        "pelvis", "right_hip", "right_knee", "right_ankle", "left_hip", "left_knee", "left_ankle",
        "spine", "thorax", "neck", "head",
        "left_shoulder", "left_elbow", "left_wrist", "right_shoulder", "right_elbow", "right_wrist",
    ),
    parents=(-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 9, 8, 11, 12, 8, 14, 15),
    mirror_pairs=((1, 4), (2, 5), (3, 6), (11, 14), (12, 15), (13, 16)),
)

# Human3.6M's full 32-joint layout as stored by VideoPose3D (data_3d_h36m.npz).
H36M_32 = Skeleton(
    name="h36m-32",
    joints=(
        "pelvis", "right_hip", "right_knee", "right_ankle", "right_toe", "right_toe_end",
        "left_hip", "left_knee", "left_ankle", "left_toe", "left_toe_end",
        "spine0", "spine", "thorax", "neck", "head",
        "left_collar", "left_shoulder", "left_elbow", "left_wrist", "left_thumb", "left_thumb_end",
        "left_hand", "left_hand_end",
        "right_collar", "right_shoulder", "right_elbow", "right_wrist", "right_thumb", "right_thumb_end",
        "right_hand", "right_hand_end",
    ),
    parents=(-1, 0, 1, 2, 3, 4, 0, 6, 7, 8, 9, 0, 11, 12, 13, 14, 12, 16, 17, 18, 19, 20, 19, 22,
             12, 24, 25, 26, 27, 28, 27, 30),
    mirror_pairs=((1, 6), (2, 7), (3, 8), (4, 9), (5, 10), (16, 24), (17, 25), (18, 26), (19, 27),
                  (20, 28), (21, 29), (22, 30), (23, 31)),
)
# The 17 joints DLow / VideoPose3D keep from the 32 (in canonical order).
H36M_32_TO_17 = (0, 1, 2, 3, 6, 7, 8, 12, 13, 14, 15, 17, 18, 19, 25, 26, 27)

COCO_17 = Skeleton(
    name="coco-17",
    joints=(
        "nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder", "right_shoulder",
        "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip",
        "left_knee", "right_knee", "left_ankle", "right_ankle",
    ),
    # COCO has no kinematic tree; this one hangs everything off the nose for drawing and mirroring.
    parents=(-1, 0, 0, 1, 2, 0, 0, 5, 6, 7, 8, 5, 6, 11, 12, 13, 14),
    mirror_pairs=((1, 2), (3, 4), (5, 6), (7, 8), (9, 10), (11, 12), (13, 14), (15, 16)),
)

OPENPOSE_18 = Skeleton(
    name="openpose-18",
    joints=(
        "nose", "neck", "right_shoulder", "right_elbow", "right_wrist", "left_shoulder", "left_elbow",
        "left_wrist", "right_hip", "right_knee", "right_ankle", "left_hip", "left_knee", "left_ankle",
        "right_eye", "left_eye", "right_ear", "left_ear",
    ),
    # Rooted at the nose so that every parent precedes its child; the drawn limbs are the same.
    parents=(-1, 0, 1, 2, 3, 1, 5, 6, 1, 8, 9, 1, 11, 12, 0, 0, 14, 15),
    mirror_pairs=((2, 5), (3, 6), (4, 7), (8, 11), (9, 12), (10, 13), (14, 15), (16, 17)),
)

BODY_25 = Skeleton(
    name="body-25",
    joints=(
        "nose", "neck", "right_shoulder", "right_elbow", "right_wrist", "left_shoulder", "left_elbow",
        "left_wrist", "mid_hip", "right_hip", "right_knee", "right_ankle", "left_hip", "left_knee",
        "left_ankle", "right_eye", "left_eye", "right_ear", "left_ear", "left_big_toe", "left_small_toe",
        "left_heel", "right_big_toe", "right_small_toe", "right_heel",
    ),
    parents=(-1, 0, 1, 2, 3, 1, 5, 6, 1, 8, 9, 10, 8, 12, 13, 0, 0, 15, 16, 14, 19, 14, 11, 22, 11),
    mirror_pairs=((2, 5), (3, 6), (4, 7), (9, 12), (10, 13), (11, 14), (15, 16), (17, 18), (19, 22),
                  (20, 23), (21, 24)),
)

SKELETONS: dict[str, Skeleton] = {s.name: s for s in (H36M_17, H36M_32, COCO_17, OPENPOSE_18, BODY_25)}


def get_skeleton(name: str) -> Skeleton:
    """Look a skeleton up by registry name; raises ``KeyError`` with the known names."""
    try:
        return SKELETONS[name]
    except KeyError:
        raise KeyError(f"unknown skeleton {name!r}; known: {', '.join(sorted(SKELETONS))}") from None


# OpenPose 18 / BODY_25 -> canonical: canonical joint -> list of source joints averaged.
OPENPOSE_TO_H36M: dict[str, tuple[str, ...]] = {
    "pelvis": ("right_hip", "left_hip"),
    "right_hip": ("right_hip",), "right_knee": ("right_knee",), "right_ankle": ("right_ankle",),
    "left_hip": ("left_hip",), "left_knee": ("left_knee",), "left_ankle": ("left_ankle",),
    "spine": ("right_hip", "left_hip", "neck", "neck"),
    "thorax": ("neck",),
    "neck": ("nose",),
    "head": ("right_eye", "left_eye"),
    "left_shoulder": ("left_shoulder",), "left_elbow": ("left_elbow",), "left_wrist": ("left_wrist",),
    "right_shoulder": ("right_shoulder",), "right_elbow": ("right_elbow",), "right_wrist": ("right_wrist",),
}


def convert_openpose_to_h36m(joints: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Map OpenPose-18 or BODY_25 joints to the canonical H36M-17 order.

    Args:
        joints: (..., J, D) joints in ``skeleton`` order (J = 18 or 25).
        skeleton: ``OPENPOSE_18`` or ``BODY_25``.
    Returns:
        (..., 17, D) joints; each canonical joint is the mean of its sources in :data:`OPENPOSE_TO_H36M`.
    """
    out = []
    for name in H36M_17.joints:
        idx = [skeleton.index(s) for s in OPENPOSE_TO_H36M[name]]
        out.append(joints[..., idx, :].mean(axis=-2))
    return np.stack(out, axis=-2)


# --- BVH rigs -----------------------------------------------------------------------------------------
# For each rig in ../shared/data/mocap (plus cmu-amc, the raw conversions of two CMU clips): canonical joint -> BVH joint whose ORIGIN is that joint.
# A tuple of two names means "midpoint of the two origins"; a name ending in ":end" means "the end site
# of that joint".
RIG_JOINT_MAPS: dict[str, dict[str, str | tuple[str, str]]] = {
    "cmu-mb": {
        "pelvis": "Hips", "right_hip": "RightUpLeg", "right_knee": "RightLeg", "right_ankle": "RightFoot",
        "left_hip": "LeftUpLeg", "left_knee": "LeftLeg", "left_ankle": "LeftFoot",
        "spine": "Spine", "thorax": "Spine1", "neck": "Neck1", "head": "Head",
        "left_shoulder": "LeftArm", "left_elbow": "LeftForeArm", "left_wrist": "LeftHand",
        "right_shoulder": "RightArm", "right_elbow": "RightForeArm", "right_wrist": "RightHand",
    },
    "cmu-daz": {
        "pelvis": "hip", "right_hip": "rThigh", "right_knee": "rShin", "right_ankle": "rFoot",
        "left_hip": "lThigh", "left_knee": "lShin", "left_ankle": "lFoot",
        "spine": "abdomen", "thorax": "chest", "neck": "neck", "head": "head",
        "left_shoulder": "lShldr", "left_elbow": "lForeArm", "left_wrist": "lHand",
        "right_shoulder": "rShldr", "right_elbow": "rForeArm", "right_wrist": "rHand",
    },
    "cmu-3dsmax": {
        "pelvis": "Hips", "right_hip": "RightHip", "right_knee": "RightKnee", "right_ankle": "RightAnkle",
        "left_hip": "LeftHip", "left_knee": "LeftKnee", "left_ankle": "LeftAnkle",
        "spine": "Chest", "thorax": "Chest2", "neck": "Neck", "head": "Head",
        "left_shoulder": "LeftShoulder", "left_elbow": "LeftElbow", "left_wrist": "LeftWrist",
        "right_shoulder": "RightShoulder", "right_elbow": "RightElbow", "right_wrist": "RightWrist",
    },
    "deepmimic-humanoid": {
        "pelvis": "root", "right_hip": "right_hip", "right_knee": "right_knee", "right_ankle": "right_ankle",
        "left_hip": "left_hip", "left_knee": "left_knee", "left_ankle": "left_ankle",
        "spine": ("root", "chest"), "thorax": "chest", "neck": "neck", "head": "neck:end",
        "left_shoulder": "left_shoulder", "left_elbow": "left_elbow", "left_wrist": "left_elbow:end",
        "right_shoulder": "right_shoulder", "right_elbow": "right_elbow", "right_wrist": "right_elbow:end",
    },
    "mass-character1": {
        "pelvis": "Character1_Hips", "right_hip": "Character1_RightUpLeg", "right_knee": "Character1_RightLeg",
        "right_ankle": "Character1_RightFoot", "left_hip": "Character1_LeftUpLeg",
        "left_knee": "Character1_LeftLeg", "left_ankle": "Character1_LeftFoot",
        "spine": "Character1_Spine", "thorax": "Character1_Spine1", "neck": "Character1_Neck",
        "head": "Character1_Head",
        "left_shoulder": "Character1_LeftArm", "left_elbow": "Character1_LeftForeArm",
        "left_wrist": "Character1_LeftHand",
        "right_shoulder": "Character1_RightArm", "right_elbow": "Character1_RightForeArm",
        "right_wrist": "Character1_RightHand",
    },
    # Raw amc2bvh conversions of CMU captures (cmu/16_01.bvh, cmu/16_02.bvh) keep the ASF bone names (the
    # manifest calls them cmu-daz, but their joints say otherwise). The ASF bone named X starts where its parent ends, so each BVH joint's
    # origin is the proximal end of that bone (lfemur = hip, ltibia = knee, lhumerus = shoulder, ...). The
    # correspondence mirrors the MotionBuilder renaming used by ``cmu-mb`` (upperback = Spine, thorax =
    # Spine1, upperneck = Neck1).
    # The BVH files motion2video writes (formats/bvh_write.py, ``--bvh DIR``): joints on Human3.6M's body
    # points already, so h36m_body_points is skipped for them (:data:`BODY_POINT_RIGS`).
    "motion2video-h36m": {
        "pelvis": "Hips", "right_hip": "RightUpLeg", "right_knee": "RightLeg", "right_ankle": "RightFoot",
        "left_hip": "LeftUpLeg", "left_knee": "LeftLeg", "left_ankle": "LeftFoot",
        "spine": "Spine", "thorax": "Thorax", "neck": "Neck", "head": "Head",
        "left_shoulder": "LeftArm", "left_elbow": "LeftForeArm", "left_wrist": "LeftHand",
        "right_shoulder": "RightArm", "right_elbow": "RightForeArm", "right_wrist": "RightHand",
    },
    "cmu-amc": {
        "pelvis": "hip", "right_hip": "rfemur", "right_knee": "rtibia", "right_ankle": "rfoot",
        "left_hip": "lfemur", "left_knee": "ltibia", "left_ankle": "lfoot",
        "spine": "upperback", "thorax": "thorax", "neck": "upperneck", "head": "head",
        "left_shoulder": "lhumerus", "left_elbow": "lradius", "left_wrist": "lwrist",
        "right_shoulder": "rhumerus", "right_elbow": "rradius", "right_wrist": "rwrist",
    },
}
# Rigs whose mapped joints already are Human3.6M's body points (the canonical joints a reader would build):
# readers take them as they are instead of rebuilding them with :func:`h36m_body_points`, whose spine split
# and head lengths depend on whole-clip statistics (the longest pelvis-thorax distance, the median leg) that
# a window of a clip need not share with the clip it was cut from (on a 5 s window of CMU 13_10 it moves
# the spine by 1.2 cm). Their floor is at height 0 already, so readers keep it (no floor placement).
BODY_POINT_RIGS = frozenset({"motion2video-h36m"})


def bone_lengths(joints: np.ndarray, parents: tuple[int, ...] = H36M_17.parents) -> np.ndarray:
    """(..., J) length of the bone from each joint to its parent over (..., J, D) joints (0 at the root)."""
    j = np.asarray(joints, np.float64)
    par = np.array([p if p >= 0 else i for i, p in enumerate(parents)])
    return np.linalg.norm(j - j[..., par, :], axis=-1)


def with_bone_lengths(joints: np.ndarray, lengths: np.ndarray,
                      parents: tuple[int, ...] = H36M_17.parents) -> np.ndarray:
    """Rigid bones: (..., J, D) joints with every bone rescaled along its own direction to ``lengths`` (J,), or
    lengths per sequence that broadcast against the joints' (..., J) (from :func:`bone_lengths`; the root's entry
    is ignored), walking down the tree from the root, which stays where it is. A bone of zero length keeps its
    parent's position."""
    j = np.asarray(joints, np.float64)
    lengths = np.asarray(lengths, np.float64)
    out = j.copy()
    for i, p in enumerate(parents):  # parents come before their children in every skeleton here
        if p < 0:
            continue
        d = j[..., i, :] - j[..., p, :]
        norm = np.linalg.norm(d, axis=-1, keepdims=True)
        unit = np.divide(d, norm, out=np.zeros_like(d), where=norm > 1e-12)
        out[..., i, :] = out[..., p, :] + unit * lengths[..., i, None]
    return out


def feet_above(joints: np.ndarray, floor: float, *, legs=((R_HIP, R_KNEE, R_ANKLE), (L_HIP, L_KNEE, L_ANKLE))
               ) -> np.ndarray:
    """Ground contact by leg inverse kinematics: (T, 17, 3) world joints (z up) whose ankles never go below
    height ``floor``. Where an ankle is lower it is lifted straight up to ``floor`` and the knee is placed
    by two-bone IK (hip fixed, thigh and shin lengths kept) in the plane of hip, new ankle and the old knee,
    so the leg bends the way it already bent: a body whose pelvis drops crouches instead of sinking into the
    ground. Frames whose ankles are above ``floor`` are unchanged."""
    j = np.array(joints, np.float64, copy=True)
    for hip, knee, ankle in legs:
        low = j[:, ankle, 2] < floor
        if not low.any():
            continue
        h, k, a = j[low, hip], j[low, knee], j[low, ankle]
        thigh = np.linalg.norm(k - h, axis=-1)
        shin = np.linalg.norm(a - k, axis=-1)
        target = a.copy()
        target[:, 2] = floor
        d_vec = target - h
        dist = np.linalg.norm(d_vec, axis=-1)
        reach = np.clip(dist, np.abs(thigh - shin) + 1e-6, thigh + shin - 1e-6)
        axis = d_vec / np.maximum(dist, 1e-9)[:, None]
        target = h + axis * reach[:, None]  # out of reach: as close as the leg gets
        along = (thigh**2 - shin**2 + reach**2) / (2 * reach)  # hip -> foot of the knee's perpendicular
        height = np.sqrt(np.maximum(thigh**2 - along**2, 0.0))
        pole = k - h - axis * np.sum((k - h) * axis, axis=-1, keepdims=True)  # the old knee's bend direction
        pole_n = np.linalg.norm(pole, axis=-1, keepdims=True)
        fallback = np.cross(axis, np.array([0.0, 0.0, 1.0]))  # a straight leg: bend sideways of the leg axis
        pole = np.where(pole_n > 1e-6, pole / np.maximum(pole_n, 1e-9), fallback / np.maximum(
            np.linalg.norm(fallback, axis=-1, keepdims=True), 1e-9))
        j[low, knee] = h + axis * along[:, None] + pole * height[:, None]
        j[low, ankle] = target
    return j


# --- the canonical body points (skeleton definition version 2) ----------------------------------------
# Version of the canonical joint definition. 1: each rig's nearest joints were taken as they are (the
# "thorax" of CMU rigs mid-chest, the "head" at the neck). 2: every source lands on Human3.6M's body points
# (:func:`h36m_body_points`). Checkpoints record it (``skeleton_version`` in their metadata).
SKELETON_VERSION = 2

def check_skeleton_version(skeleton: str | None, version: int | None, path: str | Path) -> None:
    """Refuse a body checkpoint trained on another canonical skeleton definition (one line, InputError).

    Version 1 (checkpoints that record none) took each rig's nearest joints as they were: the thorax of CMU
    rigs mid-chest, their head at the neck. Its models draw bodies that do not fit this version's joints.
    """
    if skeleton is None or version == SKELETON_VERSION:
        return
    raise InputError(f"trained on canonical skeleton version {version or 1}, but this motion2video uses version "
                     f"{SKELETON_VERSION} (every source on Human3.6M's body points, docs/data.md): retrain it "
                     "on the new joints", path)


# Human3.6M's own bone lengths, subject S1, millimetres (the skeleton offsets of its exp-map tools).
H36M_BONES_MM: dict[str, float] = {
    "hip": 133.0, "thigh": 443.0, "shin": 454.0, "pelvis_spine": 233.0, "spine_thorax": 257.0,
    "thorax_nose": 121.0, "nose_head": 115.0, "thorax_shoulder": 151.0, "upper_arm": 279.0, "forearm": 252.0,
}
H36M_LEG_MM = H36M_BONES_MM["thigh"] + H36M_BONES_MM["shin"]  # 897

# The four proportions that tell conventions apart, each as a length over the leg (thigh + shin):
# name -> (joint a, joint b, Human3.6M's value).
PROPORTIONS: dict[str, tuple[int, int, float]] = {
    "pelvis_thorax": (PELVIS, THORAX, (H36M_BONES_MM["pelvis_spine"] + H36M_BONES_MM["spine_thorax"]) / H36M_LEG_MM),
    "thorax_nose": (THORAX, NECK, H36M_BONES_MM["thorax_nose"] / H36M_LEG_MM),
    "nose_head": (NECK, HEAD, H36M_BONES_MM["nose_head"] / H36M_LEG_MM),
    "thorax_shoulder": (THORAX, (L_SHOULDER, R_SHOULDER), H36M_BONES_MM["thorax_shoulder"] / H36M_LEG_MM),
}


# Shoulder half-width kept within this band of Human3.6M's (thorax-shoulder over the leg), see
# :func:`h36m_body_points`.
SHOULDER_BAND = (0.85, 1.2)


def leg_length(joints: np.ndarray) -> float:
    """Median over frames of thigh + shin, averaged over both legs, of (T, 17, 3) canonical joints."""
    j = np.asarray(joints, np.float64)
    seg = lambda a, b: np.linalg.norm(j[:, a] - j[:, b], axis=-1)  # noqa: E731  (T,)
    legs = 0.5 * (seg(R_HIP, R_KNEE) + seg(R_KNEE, R_ANKLE) + seg(L_HIP, L_KNEE) + seg(L_KNEE, L_ANKLE))
    return float(np.median(legs))


def proportion_ratios(joints: np.ndarray) -> dict[str, float]:
    """How a clip's skeleton compares with Human3.6M's: 1.00 means "as in Human3.6M".

    For each of :data:`PROPORTIONS` (pelvis-thorax, thorax-neck/nose, neck/nose-head, thorax-shoulder, the
    last averaged over both shoulders): the median length over frames, divided by :func:`leg_length`, divided
    by Human3.6M's own ratio (subject S1).

    Args:
        joints: (T, 17, 3) canonical joints, any unit.
    Returns:
        proportion name -> ratio.
    """
    j = np.asarray(joints, np.float64)
    leg = leg_length(j)
    out = {}
    for name, (a, b, h36m) in PROPORTIONS.items():
        bs = b if isinstance(b, tuple) else (b,)
        lengths = np.mean([np.linalg.norm(j[:, a] - j[:, i], axis=-1) for i in bs], axis=0)  # (T,)
        out[name] = float(np.median(lengths)) / leg / h36m
    return out


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """(..., 3) unit vectors of v; where v is (near) zero, the unit vector of ``fallback``."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    f = fallback / np.maximum(np.linalg.norm(fallback, axis=-1, keepdims=True), 1e-12)
    return np.where(n > 1e-9, v / np.maximum(n, 1e-12), f)


def h36m_body_points(raw: np.ndarray, *, head_direction: np.ndarray | None = None,
                     leg: float | None = None,
                     shoulder_band: tuple[float, float] | None = SHOULDER_BAND) -> np.ndarray:
    """Put the torso and head joints of a rig's nearest joints on Human3.6M's body points (version 2).

    Rigs disagree on where "thorax", "neck/nose" and "head" are (a CMU rig's chest joint sits mid-chest,
    its head joint at the top of the neck), so these four joints are rebuilt from points every rig agrees on:

    - thorax (8): the midpoint of the two shoulders (Human3.6M's thorax is the base of the neck between them);
    - pelvis (0): the midpoint of the hips (Human3.6M's hips are level with its pelvis);
    - spine (7): a chain pelvis -> spine -> thorax with two fixed lengths in Human3.6M's 233 : 257 mm split of
      the clip's longest pelvis-thorax distance, bent towards the side the rig's own spine joint bends;
    - neck/nose (9) and head (10): up from the thorax along the head's direction, at Human3.6M's lengths
      (121 and 115 mm) scaled by this clip's leg (thigh + shin, :func:`leg_length`; 897 mm in Human3.6M).

    Hips, legs, shoulders and arms are the rig's own joints, except that a rig whose shoulders are wider
    (or narrower) than ``shoulder_band`` times Human3.6M's has each whole arm moved towards (or away from)
    the midline by one constant fraction of its shoulder's offset (rigid bones, the same joint angles).
    Every bone this function builds has a constant length over the clip.

    Args:
        raw: (T, 17, 3) the rig's nearest joints in canonical order (metres, z up).
        head_direction: (T, 3) the direction the head points (neck base -> top of head); default the raw
            neck -> head direction. A degenerate direction falls back to pelvis -> thorax.
        leg: the leg length to scale with (default :func:`leg_length` of ``raw``).
        shoulder_band: (low, high) thorax-shoulder ratio to Human3.6M's kept; None keeps the rig's shoulders.
    Returns:
        (T, 17, 3) float64 joints on Human3.6M's body points.
    """
    j = np.array(raw, dtype=np.float64, copy=True)
    leg = leg_length(j) if leg is None else float(leg)
    j[:, PELVIS] = 0.5 * (j[:, L_HIP] + j[:, R_HIP])  # Human3.6M's hips are level with its pelvis
    thorax = 0.5 * (j[:, L_SHOULDER] + j[:, R_SHOULDER])  # (T, 3)
    # Shoulder width: a rig whose shoulder joints sit wider (or narrower) than SHOULDER_BAND times
    # Human3.6M's has each whole arm moved towards (or away from) the midline by one constant fraction of
    # its shoulder's offset: bones stay rigid and joint angles are kept, only the build changes.
    half = np.linalg.norm(j[:, L_SHOULDER] - thorax, axis=-1)  # (T,)
    ratio = float(np.median(half)) / leg / PROPORTIONS["thorax_shoulder"][2] if leg > 0 else 1.0
    if shoulder_band is not None and ratio > 0 and not shoulder_band[0] <= ratio <= shoulder_band[1]:
        scale = float(np.clip(ratio, *shoulder_band)) / ratio
        for shoulder, arm in ((L_SHOULDER, (L_SHOULDER, L_ELBOW, L_WRIST)),
                              (R_SHOULDER, (R_SHOULDER, R_ELBOW, R_WRIST))):
            shift = (scale - 1.0) * (j[:, shoulder] - thorax)  # (T, 3)
            j[:, list(arm)] += shift[:, None]
    up = thorax - j[:, PELVIS]  # (T, 3)
    direction = j[:, HEAD] - j[:, NECK] if head_direction is None else np.asarray(head_direction, np.float64)
    u = _unit(direction, up)  # (T, 3)
    # spine: a two-bone chain pelvis -> spine -> thorax of fixed lengths (Human3.6M's 233 : 257 split of the
    # clip's longest pelvis-thorax distance), bent the way the rig's own spine bends
    chord = thorax - j[:, PELVIS]  # (T, 3)
    dist = np.linalg.norm(chord, axis=-1)  # (T,)
    total = float(dist.max()) if len(dist) else 0.0
    a = total * H36M_BONES_MM["pelvis_spine"] / (H36M_BONES_MM["pelvis_spine"] + H36M_BONES_MM["spine_thorax"])
    b = total - a
    axis = _unit(chord, np.array([0.0, 0.0, 1.0]))  # (T, 3)
    safe = np.maximum(dist, 1e-9)
    along = np.clip((a**2 - b**2 + dist**2) / (2 * safe), 0.0, a)  # (T,) pelvis -> foot of the perpendicular
    height = np.sqrt(np.maximum(a**2 - along**2, 0.0))  # (T,)
    bend = j[:, SPINE] - j[:, PELVIS]
    bend = bend - axis * np.sum(bend * axis, axis=-1, keepdims=True)  # the rig's spine offset from the chord
    backward = np.cross(axis, j[:, L_HIP] - j[:, R_HIP])  # (T, 3) bodies face -y, left is +x: this is +y
    spine = j[:, PELVIS] + axis * along[:, None] + _unit(bend, backward) * height[:, None]
    j[:, SPINE] = spine
    j[:, THORAX] = thorax
    j[:, NECK] = thorax + u * (leg * H36M_BONES_MM["thorax_nose"] / H36M_LEG_MM)
    j[:, HEAD] = j[:, NECK] + u * (leg * H36M_BONES_MM["nose_head"] / H36M_LEG_MM)
    return j


# --- any humanoid rig, from its joint names ------------------------------------------------------------
# A rig outside RIG_JOINT_MAPS is mapped by the names its joints carry in the common conventions
# (``LeftUpLeg``, ``mixamorig:LeftUpLeg``, ``UpperLeg_L``, ``thigh_l``, ``L_Hip``, ``Bip01 L Thigh``, ``lThigh``):
# a name splits into a side (left / right / none) and a part; each body point takes the first part of its
# list that a joint of that side carries. Earlier parts win: a rig with both ``LeftShoulder`` (the clavicle)
# and ``LeftArm`` (the shoulder joint) maps the shoulder to ``LeftArm``.
LIMB_PARTS: dict[str, tuple[str, ...]] = {
    "hip": ("upleg", "upperleg", "thigh", "femur", "hip"),
    "knee": ("lowerleg", "lowleg", "shin", "calf", "knee", "tibia", "leg"),
    "ankle": ("foot", "ankle"),
    "shoulder": ("upperarm", "uparm", "arm", "humerus", "shoulder", "shldr"),
    "elbow": ("forearm", "lowerarm", "lowarm", "elbow", "radius"),
    "wrist": ("hand", "wrist"),
}
PELVIS_PARTS = ("hips", "pelvis", "hip")
NECK_PARTS = ("neck", "neck1", "neck0", "neck01", "lowerneck")
HEAD_PARTS = ("head",)
HEAD_TOP_PARTS = ("headtop", "headend", "headtopend", "headnub")  # a child joint of the head at its top

# Prefixes that say nothing about the body part: a namespace (``mixamorig:``), 3ds Max's ``Bip01 `` and
# MotionBuilder's ``Character1_``.
_NAME_PREFIX = re.compile(r"^(?:.*:)?(?:bip0*1[ _]*|character\d*_)?", re.IGNORECASE)
_NAME_TOKEN = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|\d+")


def joint_name_parts(name: str) -> tuple[str, str]:
    """(side, part) of a joint name: side ``"left"``, ``"right"`` or ``""``; part the rest in lower case
    without separators. ``"mixamorig:LeftUpLeg"`` -> ``("left", "upleg")``, ``"UpperLeg_L"`` -> ``("left",
    "upperleg")``, ``"Bip01 R Forearm"`` -> ``("right", "forearm")``, ``"lThigh"`` -> ``("left", "thigh")``,
    ``"Spine1"`` -> ``("", "spine1")``."""
    tokens = [t.lower() for t in _NAME_TOKEN.findall(_NAME_PREFIX.sub("", name))]
    side = ""
    for word, which in (("left", "left"), ("right", "right")):
        if word in tokens:
            side = which
            tokens.remove(word)
    if not side and len(tokens) > 1:
        for at in (0, -1):  # a one-letter side first or last: L_Hip, thigh_l, lThigh
            if tokens[at] in ("l", "r"):
                side = "left" if tokens[at] == "l" else "right"
                del tokens[at]
                break
    return side, "".join(tokens)


def _first_with_part(candidates: list[int], parts_of: list[tuple[str, str]], side: str,
                     wanted: tuple[str, ...]) -> int | None:
    for part in wanted:
        for i in candidates:
            if parts_of[i] == (side, part):
                return i
    return None


def _path_up(node: int, parents: tuple[int, ...] | list[int]) -> list[int]:
    """``node`` and its ancestors, nearest first."""
    out = []
    while node >= 0:
        out.append(node)
        node = parents[node]
    return out


def map_joint_names(names: tuple[str, ...] | list[str], parents: tuple[int, ...] | list[int]
                    ) -> tuple[dict[str, str | tuple[str, str]], list[str]]:
    """The canonical body points of a rig guessed from its joint names and its hierarchy.

    Limbs and hips come from the names (:data:`LIMB_PARTS`, :func:`joint_name_parts`). ``spine`` is the first
    joint above the pelvis on the way to the neck and ``thorax`` the last one below the neck (the midpoint of
    pelvis and neck when none lies between); :func:`h36m_body_points` rebuilds both, using only the spine's
    bend. ``neck`` -> ``head`` carries the head's direction: the head joint and the point past its top (a
    ``HeadTop_End``-like joint or the head's end site) when the rig has one, else the neck and the head.

    Args:
        names: (N,) node names, end sites as ``"<joint>:end"``.
        parents: (N,) parent index per node.
    Returns:
        (mapping body point -> node name or pair of node names, body points not found).
    """
    joints = [i for i, n in enumerate(names) if not n.endswith(":end")]
    parts_of = [joint_name_parts(n) if not n.endswith(":end") else ("", "") for n in names]
    found: dict[str, int] = {}
    for side in ("right", "left"):
        for point, parts in LIMB_PARTS.items():
            i = _first_with_part(joints, parts_of, side, parts)
            if i is not None:
                found[f"{side}_{point}"] = i
    for point, parts in (("pelvis", PELVIS_PARTS), ("neck", NECK_PARTS), ("head", HEAD_PARTS)):
        i = _first_with_part(joints, parts_of, "", parts)
        if i is not None:
            found[point] = i
    mapping: dict[str, str | tuple[str, str]] = {k: names[i] for k, i in found.items()}
    if "head" in found and "neck" not in found and parents[found["head"]] >= 0:
        found["neck"] = parents[found["head"]]
        mapping["neck"] = names[found["neck"]]
    if "head" in found:
        head = found["head"]
        tops = [i for i, p in enumerate(parents) if p == head
                and (names[i] == f"{names[head]}:end" or parts_of[i][1] in HEAD_TOP_PARTS)]
        if tops:
            mapping["neck"], mapping["head"] = names[head], names[tops[0]]
    if "pelvis" in found and "neck" in found:
        up = _path_up(found["neck"], parents)
        if found["pelvis"] in up:
            between = up[1:up.index(found["pelvis"])]  # nearest the neck first
            if between:
                mapping["spine"], mapping["thorax"] = names[between[-1]], names[between[0]]
            else:
                mapping["spine"] = mapping["thorax"] = (names[found["pelvis"]], names[found["neck"]])
    missing = [j for j in H36M_17.joints if j not in mapping]
    return mapping, missing
