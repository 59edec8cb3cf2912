"""Procedural body motion: joint-angle primitives driven through forward kinematics.

A canonical H36M-17 rest skeleton (bone lengths from a body height) is posed by per-joint local rotations
that are functions of time, one set per motion mode (walk, run, jump, wave, squat, punch, turn, stand,
idle). A clip is a list of modes with durations; consecutive modes cross-fade their joint angles, and the
root trajectory is integrated from blended forward speed and yaw rate, so it is always continuous.

Frames and signs (DESIGN.md): world metres, right-handed, z up. At heading 0 the body faces -y and its
left side is +x (index 1, the RIGHT hip, has the smaller x). The floor is z = 0: on the ground, the lowest
ankle sits at the ankle height (~0.08 m for a 1.7 m body).

Local rotations are Euler angles per joint, ``(pitch, roll, yaw)`` about the body's (x, y, z) axes,
composed as ``R = Rz(yaw) @ Ry(roll) @ Rx(pitch)``. The rotation stored at joint ``j`` turns the bones that
leave ``j`` (its children), i.e. ``global[j] = global[parent] @ local[j]`` and
``pos[j] = pos[parent] + global[parent] @ offset[j]``. With these axes, for a limb hanging down a positive
pitch swings it backwards (+y), so hip and shoulder flexion are negative pitches; for the torso a positive
pitch leans it forwards.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from motion2video.errors import InputError
from motion2video.motion import Motion
from motion2video.core.rotations import euler_to_matrix, heading_of  # noqa: F401 (heading_of: old import path)
from motion2video.core.skeletons import (  # noqa: F401 (H36M-17 joint indices, also imported from here)
    PELVIS, R_HIP, R_KNEE, R_ANKLE, L_HIP, L_KNEE, L_ANKLE, SPINE, THORAX, NECK, HEAD,
    L_SHOULDER, L_ELBOW, L_WRIST, R_SHOULDER, R_ELBOW, R_WRIST,
)
from motion2video.skeletons import H36M_17

MODES: tuple[str, ...] = ("stand", "idle", "walk", "run", "jump", "wave", "squat", "punch", "turn")
GAIT_MODES: frozenset[str] = frozenset({"walk", "run", "turn"})  # share one continuous gait phase

# Cycle frequency of each mode at speed 1, Hz (a gait cycle is two steps).
MODE_FREQUENCY: dict[str, float] = {
    "stand": 0.25, "idle": 0.2, "walk": 0.95, "run": 1.4, "jump": 0.8, "wave": 1.6, "squat": 0.45,
    "punch": 0.9, "turn": 0.9,
}
TURN_RATE = 1.6  # rad/s at speed 1 and amplitude 1 (about 90 degrees per second)
GRAVITY = 9.81  # m/s^2, for the jump's flight arc

PITCH, ROLL, YAW = 0, 1, 2
NUM_JOINTS = 17


@dataclass(frozen=True)
class BodyParams:
    """Body proportions.

    Attributes:
        height: standing height in metres (top of the head); bone lengths scale with it.
        hip_width, shoulder_width, leg_length, arm_length: multipliers on the default proportions.
    """

    height: float = 1.7
    hip_width: float = 1.0
    shoulder_width: float = 1.0
    leg_length: float = 1.0
    arm_length: float = 1.0

    def __post_init__(self) -> None:
        if not 0.5 <= self.height <= 2.5:
            raise InputError(f"body height must be in 0.5..2.5 m, got {self.height}")
        for name in ("hip_width", "shoulder_width", "leg_length", "arm_length"):
            value = getattr(self, name)
            if not 0.5 <= value <= 1.5:
                raise InputError(f"body {name} multiplier must be in 0.5..1.5, got {value}")

    @property
    def ankle_height(self) -> float:
        """Height of the ankle joint above the floor when standing, metres (0.08 m at 1.7 m)."""
        return 0.047 * self.height


@dataclass(frozen=True)
class ModeSpec:
    """One segment of a procedural clip.

    Attributes:
        mode: one of :data:`MODES`.
        seconds: duration, > 0.
        speed: time scale of the cycle (and of forward speed and turn rate), > 0.
        amplitude: scale of the joint-angle excursions (and jump height, turn rate), > 0.
        phase: start phase in cycles [0, 1); ``None`` draws it from the seed. walk, run and turn share one
            gait phase, so only the first of them in a clip sets it (later ones continue in step).
        mirror: swap left and right (wave with the left hand, turn clockwise, lead with the right fist).
    """

    mode: str
    seconds: float
    speed: float = 1.0
    amplitude: float = 1.0
    phase: float | None = None
    mirror: bool = False

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise InputError(f"unknown motion mode {self.mode!r}; known: {', '.join(MODES)}")
        if not (np.isfinite(self.seconds) and self.seconds > 0):
            raise InputError(f"mode {self.mode!r}: duration must be a positive number of seconds, got {self.seconds}")
        if not (self.speed > 0 and self.amplitude > 0):
            raise InputError(f"mode {self.mode!r}: speed and amplitude must be positive")


# --- geometry (pure functions) --------------------------------------------------------------------------

def rest_offsets(params: BodyParams = BodyParams()) -> np.ndarray:
    """Bone offsets of the rest pose (standing straight, arms hanging, facing -y, left = +x).

    Args:
        params: body proportions.
    Returns:
        (17, 3) float64: offset of each joint from its parent in the parent's frame (row 0 is zero).
    """
    h = params.height
    leg = 0.245 * h * params.leg_length
    arm = h * params.arm_length
    hip = 0.075 * h * params.hip_width
    shoulder = 0.09 * h * params.shoulder_width
    off = np.zeros((NUM_JOINTS, 3))
    off[R_HIP] = (-hip, 0.0, 0.0)
    off[L_HIP] = (hip, 0.0, 0.0)
    off[R_KNEE] = off[L_KNEE] = (0.0, 0.0, -leg)
    off[R_ANKLE] = off[L_ANKLE] = (0.0, 0.0, -leg)
    off[SPINE] = (0.0, 0.0, 0.135 * h)
    off[THORAX] = (0.0, 0.0, 0.145 * h)
    off[NECK] = (0.0, -0.02 * h, 0.06 * h)
    off[HEAD] = (0.0, 0.0033 * h, 0.0627 * h)  # Human3.6M's nose -> head: 115 / 897 of the leg (0.49 h)
    off[L_SHOULDER] = (shoulder, 0.0, -0.005 * h)
    off[R_SHOULDER] = (-shoulder, 0.0, -0.005 * h)
    off[L_ELBOW] = off[R_ELBOW] = (0.0, 0.0, -0.17 * arm)
    off[L_WRIST] = off[R_WRIST] = (0.0, 0.0, -0.15 * arm)
    return off


def forward_kinematics(local_rot: np.ndarray, offsets: np.ndarray, root: np.ndarray) -> np.ndarray:
    """Joint positions of the H36M-17 tree.

    Args:
        local_rot: (T, 17, 3, 3) local rotation per joint (row 0 is the root's global orientation).
        offsets: (17, 3) bone offsets in the parent's frame (:func:`rest_offsets`).
        root: (T, 3) root (pelvis) positions.
    Returns:
        (T, 17, 3) joint positions.
    """
    T = local_rot.shape[0]
    glob = np.empty((T, NUM_JOINTS, 3, 3))
    pos = np.empty((T, NUM_JOINTS, 3))
    glob[:, 0] = local_rot[:, 0]
    pos[:, 0] = root
    for j in range(1, NUM_JOINTS):
        p = H36M_17.parents[j]
        pos[:, j] = pos[:, p] + glob[:, p] @ offsets[j]  # (T, 3)
        glob[:, j] = glob[:, p] @ local_rot[:, j]  # (T, 3, 3)
    return pos


def mirror_euler(euler: np.ndarray) -> np.ndarray:
    """Left/right mirror of local Euler angles (reflection x -> -x): swap the sides, negate roll and yaw.

    Args:
        euler: (..., 17, 3) local (pitch, roll, yaw).
    Returns:
        (..., 17, 3) mirrored angles; their forward kinematics is the reflection of the original's.
    """
    out = euler[..., H36M_17.mirror_permutation(), :].copy()
    out[..., 1:] *= -1.0
    return out


def smootherstep(x: np.ndarray) -> np.ndarray:
    """C2-smooth ramp from 0 (x <= 0) to 1 (x >= 1): 6x^5 - 15x^4 + 10x^3."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)


def segment_weights(times: np.ndarray, starts: Sequence[float], blend: float) -> np.ndarray:
    """Cross-fade weights of consecutive segments.

    Segment i > 0 fades in over ``[starts[i], starts[i] + blend]`` (never before its start, so a frame
    before a boundary shows nothing of the next segment) while every earlier one fades out in proportion.

    Args:
        times: (T,) frame times, seconds.
        starts: start time of each segment (starts[0] is the clip start).
        blend: fade duration, seconds (0 gives hard cuts).
    Returns:
        (T, S) non-negative weights; each row sums to 1.
    """
    t = np.asarray(times, dtype=np.float64)
    w = np.zeros((t.shape[0], len(starts)))
    w[:, 0] = 1.0
    for i in range(1, len(starts)):
        if blend > 0:
            r = smootherstep((t - starts[i]) / blend)
        else:
            r = (t >= starts[i]).astype(np.float64)
        w *= (1.0 - r)[:, None]
        w[:, i] += r
    return w


# --- gait: foot paths and two-link inverse kinematics -------------------------------------------------------

@dataclass(frozen=True)
class GaitShape:
    """Foot path of a gait, relative to the hip, as fractions of the leg length (thigh + shin).

    Attributes:
        stance: fraction of the cycle each foot is on the ground (> 0.5: double support, < 0.5: flight).
        step: half the distance the planted foot travels under the hip (at amplitude 1).
        extension: hip-to-ankle distance at touchdown and toe-off.
        compress: relative shortening of the leg at mid-stance.
        clearance: lift of the ankle at mid-swing.
        arm_swing, arm_flex, elbow: shoulder swing amplitude, mean shoulder flexion, elbow flexion (rad).
        lean: forward lean of the torso (rad).
    """

    stance: float
    step: float
    extension: float
    compress: float
    clearance: float
    arm_swing: float
    arm_flex: float
    elbow: float
    lean: float


GAIT: dict[str, GaitShape] = {
    "walk": GaitShape(stance=0.6, step=0.38, extension=0.985, compress=0.03, clearance=0.12,
                      arm_swing=0.35, arm_flex=0.0, elbow=0.3, lean=0.04),
    "run": GaitShape(stance=0.35, step=0.38, extension=0.97, compress=0.1, clearance=0.35,
                     arm_swing=0.55, arm_flex=0.2, elbow=1.5, lean=0.18),
    "turn": GaitShape(stance=0.6, step=0.0, extension=0.985, compress=0.0, clearance=0.1,
                      arm_swing=0.0, arm_flex=0.0, elbow=0.15, lean=0.0),
}


def leg_ik(forward: np.ndarray, down: np.ndarray, *, thigh: float, shin: float) -> tuple[np.ndarray, np.ndarray]:
    """Planar two-link inverse kinematics of a leg whose knee bends forwards.

    Args:
        forward: (T,) ankle position in front of the hip, metres.
        down: (T,) ankle position below the hip, metres (> 0).
        thigh, shin: bone lengths, metres.
    Returns:
        hip flexion (T,) (thigh forwards of straight down) and knee flexion (T,) (>= 0), radians.
        Targets out of reach are pulled in to a nearly straight leg.
    """
    dist = np.clip(np.hypot(forward, down), 1e-6, 0.9999 * (thigh + shin))
    knee_inner = np.arccos(np.clip((thigh**2 + shin**2 - dist**2) / (2 * thigh * shin), -1.0, 1.0))
    toward = np.arctan2(forward, down)  # the hip-ankle line, from straight down
    spread = np.arccos(np.clip((thigh**2 + dist**2 - shin**2) / (2 * thigh * dist), -1.0, 1.0))
    return toward + spread, np.pi - knee_inner


def _foot_path(p: np.ndarray, gait: GaitShape, *, leg: float, amp: float) -> tuple[np.ndarray, np.ndarray]:
    """Ankle (forward, down) relative to the hip over one gait cycle.

    Args:
        p: (T,) leg phase in [0, 1): 0 at touchdown, ``gait.stance`` at toe-off.
        gait: the gait.
        leg: leg length (thigh + shin), metres.
        amp: amplitude multiplier (scales the step and the clearance).
    Returns:
        forward (T,) and down (T,) metres. In stance the foot moves backwards at constant speed (it is
        planted while the body moves forward at :func:`gait_speed`).
    """
    half = min(gait.step * amp, 0.6) * leg
    ext = gait.extension * leg
    beta = gait.stance
    stance = p < beta
    ps = np.clip(p / beta, 0.0, 1.0)
    fwd_stance = half * (1.0 - 2.0 * ps)
    len_stance = ext * (1.0 - gait.compress * amp * np.sin(np.pi * ps) ** 2)
    down_stance = np.sqrt(np.maximum(len_stance**2 - fwd_stance**2, 1e-6))
    sw = np.clip((p - beta) / (1.0 - beta), 0.0, 1.0)
    fwd_swing = -half + half * (1.0 - np.cos(np.pi * sw))
    # With a flight phase (stance < 0.5) the foot stays low while both feet are off the ground.
    delay = max(0.0, 0.5 - beta) / (1.0 - beta)
    lift = gait.clearance * leg * min(amp, 1.5) * _bump((sw - delay) / (1.0 - 2.0 * delay))
    down_swing = np.sqrt(np.maximum(ext**2 - fwd_swing**2, 1e-6)) - lift
    return np.where(stance, fwd_stance, fwd_swing), np.where(stance, down_stance, down_swing)


def _flight_lift(u: np.ndarray, gait: GaitShape, *, period: float) -> np.ndarray:
    """Ballistic root lift (metres) while both feet are off the ground (gaits with stance < 0.5)."""
    flight = max(0.0, 0.5 - gait.stance) * period  # seconds per step
    if flight <= 0:
        return np.zeros_like(u)
    t = np.clip(np.mod(u, 0.5) - gait.stance, 0.0, None) * period
    return 0.5 * GRAVITY * t * np.maximum(flight - t, 0.0)


def gait_speed(mode: str, *, amp: float, freq: float, offsets: np.ndarray) -> float:
    """Forward speed (m/s) that keeps the stance foot of ``mode`` planted; 0 for non-travelling modes."""
    if mode not in ("walk", "run"):
        return 0.0
    gait = GAIT[mode]
    leg = float(-offsets[R_KNEE, 2] - offsets[R_ANKLE, 2])
    half = min(gait.step * amp, 0.6) * leg
    return 2.0 * half * freq / gait.stance


# --- mode primitives -------------------------------------------------------------------------------------

def _bump(x: np.ndarray) -> np.ndarray:
    """sin^2 bump: 0 at x = 0 and 1, 1 at x = 0.5, 0 outside [0, 1]."""
    inside = (x >= 0) & (x <= 1)
    return np.where(inside, np.sin(np.pi * np.clip(x, 0, 1)) ** 2, 0.0)


def _set_leg(e: np.ndarray, side: str, *, flex, knee, abduct=0.0) -> None:
    """Hip flexion (thigh forwards), knee flexion (shin backwards), hip abduction (outwards)."""
    hip, kn, s = (R_HIP, R_KNEE, 1.0) if side == "right" else (L_HIP, L_KNEE, -1.0)
    e[:, hip, PITCH] = -np.asarray(flex)
    e[:, hip, ROLL] = s * np.asarray(abduct)
    e[:, kn, PITCH] = knee


def _set_leg_target(e: np.ndarray, side: str, *, forward, down, offsets: np.ndarray) -> None:
    """Place the ankle at (forward, down) metres from the hip with :func:`leg_ik`."""
    T = e.shape[0]
    fwd = np.broadcast_to(np.asarray(forward, dtype=np.float64), (T,))
    dwn = np.broadcast_to(np.asarray(down, dtype=np.float64), (T,))
    flex, knee = leg_ik(fwd, dwn, thigh=float(-offsets[R_KNEE, 2]), shin=float(-offsets[R_ANKLE, 2]))
    _set_leg(e, side, flex=flex, knee=knee)


def _set_arm(e: np.ndarray, side: str, *, flex, abduct, elbow, elbow_roll=0.0, inward=0.0) -> None:
    """Shoulder flexion (arm forwards), abduction (sideways up), inward yaw; elbow flexion and roll."""
    sho, elb, s = (R_SHOULDER, R_ELBOW, 1.0) if side == "right" else (L_SHOULDER, L_ELBOW, -1.0)
    e[:, sho, PITCH] = -np.asarray(flex)
    e[:, sho, ROLL] = s * np.asarray(abduct)
    e[:, sho, YAW] = s * np.asarray(inward)
    e[:, elb, PITCH] = -np.asarray(elbow)
    e[:, elb, ROLL] = s * np.asarray(elbow_roll)


@dataclass(frozen=True)
class _ModeFrames:
    """What one mode contributes per frame: local Euler angles (T, 17, 3) and root lift (T,) metres."""

    euler: np.ndarray
    lift: np.ndarray


def _stand_pose(T: int) -> np.ndarray:
    e = np.zeros((T, NUM_JOINTS, 3))
    for side in ("right", "left"):
        _set_leg(e, side, flex=0.03, knee=0.05)
        _set_arm(e, side, flex=0.05, abduct=0.12, elbow=0.15)
    return e


def _mode_frames(mode: str, phase: np.ndarray, *, amp: float, period: float, offsets: np.ndarray) -> _ModeFrames:
    """Joint angles and root lift of one mode.

    Args:
        mode: one of :data:`MODES`.
        phase: (T,) cycle phase, radians (2 pi per cycle).
        amp: amplitude multiplier.
        period: cycle duration, seconds (for ballistic flight).
        offsets: (17, 3) rest bone offsets (:func:`rest_offsets`).
    """
    T = phase.shape[0]
    leg = float(-offsets[R_KNEE, 2] - offsets[R_ANKLE, 2])
    e = _stand_pose(T)
    lift = np.zeros(T)
    s, c = np.sin(phase), np.cos(phase)
    u = np.mod(phase / (2 * np.pi), 1.0)  # cycle position in [0, 1)
    if mode == "stand":
        e[:, THORAX, PITCH] = 0.015 * amp * s  # breathing
    elif mode == "idle":
        sway = 0.05 * amp * s
        e[:, PELVIS, ROLL] = sway  # weight shift; legs and torso stay upright
        e[:, R_HIP, ROLL] = -sway
        e[:, L_HIP, ROLL] = -sway
        e[:, SPINE, ROLL] = -sway
        e[:, NECK, YAW] = 0.35 * amp * np.sin(0.5 * phase + 0.7)  # looks around
        e[:, NECK, PITCH] = 0.08 * amp * np.sin(1.5 * phase)
        for side, sign in (("right", 1.0), ("left", -1.0)):
            _set_arm(e, side, flex=0.05 + 0.1 * amp * sign * s, abduct=0.12, elbow=0.25 + 0.1 * amp * c)
    elif mode in GAIT_MODES:
        gait = GAIT[mode]
        thigh, shin = float(-offsets[R_KNEE, 2]), float(-offsets[R_ANKLE, 2])
        for side, p in (("right", u), ("left", np.mod(u + 0.5, 1.0))):
            fwd, down = _foot_path(p, gait, leg=thigh + shin, amp=amp)
            flex, knee = leg_ik(fwd, down, thigh=thigh, shin=shin)
            _set_leg(e, side, flex=flex, knee=knee)
            if mode != "turn":  # arms swing against the legs: right arm back when the right foot lands
                arm = gait.arm_swing * amp * -np.cos(2 * np.pi * p)
                _set_arm(e, side, flex=arm + gait.arm_flex, abduct=0.12, elbow=gait.elbow + 0.15 * (arm > 0) * arm,
                         inward=0.15 if mode == "run" else 0.0)
        if mode == "turn":
            e[:, NECK, YAW] = 0.15  # looks into the turn
        else:
            e[:, SPINE, YAW] = 0.12 * amp * -np.cos(2 * np.pi * u)  # shoulders counter-rotate the hips
            e[:, SPINE, PITCH] = gait.lean
        lift = _flight_lift(u, gait, period=period)
    elif mode == "jump":
        prep = 0.8 * _bump(u / 0.35)  # crouch and push off
        fly = (u >= 0.35) & (u < 0.75)
        s_fly = np.clip((u - 0.35) / 0.4, 0.0, 1.0)
        land = _bump((u - 0.75) / 0.25) * 0.7  # absorb the landing
        crouch = amp * (prep + land)
        tuck = 0.12 * _bump(s_fly) * fly
        for side in ("right", "left"):
            _set_leg_target(e, side, forward=0.0, down=leg * (0.985 - 0.4 * crouch - tuck), offsets=offsets)
            arm = np.where(u < 0.35, -0.8 * prep, 0.0) + np.where(fly, 2.0 * np.sin(np.pi * s_fly), 0.0)
            _set_arm(e, side, flex=amp * arm, abduct=0.15, elbow=0.3)
        e[:, SPINE, PITCH] = 0.45 * crouch
        e[:, NECK, PITCH] = -0.3 * crouch
        lift = _jump_lift(u, period=period, amp=amp)
    elif mode == "squat":
        d = amp * (0.5 - 0.5 * c)  # 0 standing .. amp at the bottom
        for side in ("right", "left"):  # ankles stay under the hips: the feet do not slide
            _set_leg_target(e, side, forward=0.0, down=leg * (0.985 - 0.46 * d), offsets=offsets)
            _set_arm(e, side, flex=1.45 * d + 0.05, abduct=0.1, elbow=0.15)
        e[:, SPINE, PITCH] = 0.55 * d
        e[:, NECK, PITCH] = -0.4 * d
    elif mode == "wave":
        _set_arm(e, "right", flex=0.15, abduct=2.25, elbow=0.0, elbow_roll=0.75 + 0.45 * amp * s)
        e[:, NECK, ROLL] = 0.06 * s
        e[:, SPINE, ROLL] = -0.04
    elif mode == "punch":
        ext_l = _bump(u / 0.4) * amp  # left jab, then right cross
        ext_r = _bump((u - 0.5) / 0.4) * amp
        for side, ext in (("left", ext_l), ("right", ext_r)):
            _set_arm(e, side, flex=0.75 + 0.85 * ext, abduct=0.25 - 0.15 * ext, elbow=2.2 - 2.05 * ext,
                     inward=0.3 * ext)
        for side, fwd in (("left", 0.12), ("right", -0.1)):  # staggered stance, left foot forward
            _set_leg_target(e, side, forward=fwd * leg, down=leg * np.sqrt(0.96**2 - fwd**2), offsets=offsets)
        e[:, SPINE, YAW] = 0.4 * (ext_r - ext_l)
        e[:, SPINE, PITCH] = 0.1
    else:  # pragma: no cover - ModeSpec validated the name
        raise ValueError(mode)
    return _ModeFrames(e, lift)


def _jump_lift(u: np.ndarray, *, period: float, amp: float) -> np.ndarray:
    """Ballistic root lift of the jump cycle, metres: flight over u in [0.35, 0.75) of each cycle."""
    flight = 0.4 * period
    t = np.clip(u - 0.35, 0.0, 0.4) * period  # seconds into the flight
    return amp * 0.5 * GRAVITY * t * (flight - t)


# --- clips ------------------------------------------------------------------------------------------------

def _as_spec(item) -> ModeSpec:
    if isinstance(item, ModeSpec):
        return item
    if not (isinstance(item, (tuple, list)) and len(item) == 2):
        raise InputError(f"each mode must be (name, seconds) or a ModeSpec, got {item!r}")
    return ModeSpec(str(item[0]), float(item[1]))


def generate(
    modes: Sequence[tuple[str, float] | ModeSpec],
    *,
    fps: float = 25.0,
    params: BodyParams = BodyParams(),
    seed: int = 0,
    speed: float = 1.0,
    amplitude: float = 1.0,
    blend: float = 0.4,
    variation: float = 0.05,
) -> Motion:
    """A procedural H36M-17 body clip.

    Args:
        modes: segments, each ``(mode, seconds)`` or a :class:`ModeSpec`.
        fps: frame rate; the clip has ``round(total seconds * fps)`` frames.
        params: body proportions.
        seed: draws each segment's start phase (unless given) and a small jitter of amplitude and
            frequency; the same seed gives the same clip.
        speed: global time scale multiplying every segment's speed.
        amplitude: global multiplier of every segment's amplitude.
        blend: cross-fade duration at each segment start, seconds (0.3-0.5 looks natural).
        variation: relative size of the per-segment jitter (0 for exact primitives).
    Returns:
        Motion with joints (T, 17, 3) float32 in world metres (z up, floor z = 0), skeleton ``"h36m-17"``,
        label = the mode names joined by ``">"``. The clip starts at the origin facing -y.
    """
    specs = [_as_spec(m) for m in modes]
    if not specs:
        raise InputError("the mode list is empty")
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be positive, got {fps}")
    if not (speed > 0 and amplitude > 0 and blend >= 0 and variation >= 0):
        raise InputError("speed and amplitude must be positive, blend and variation non-negative")
    durations = np.array([sp.seconds for sp in specs])
    starts = np.concatenate([[0.0], np.cumsum(durations)[:-1]])
    T = int(round(durations.sum() * fps))
    if T < 1:
        raise InputError(f"the clip is shorter than one frame at {fps} fps")
    t = np.arange(T) / fps  # (T,)
    w = segment_weights(t, starts, blend)  # (T, S)
    offsets = rest_offsets(params)

    rng = np.random.default_rng(seed)
    draws = rng.uniform(size=(len(specs), 3))  # phase, amplitude jitter, frequency jitter per segment
    amps = np.array([amplitude * sp.amplitude * (1 + variation * (2 * d[1] - 1)) for sp, d in zip(specs, draws)])
    freqs = np.array([MODE_FREQUENCY[sp.mode] * speed * sp.speed * (1 + variation * (2 * d[2] - 1))
                      for sp, d in zip(specs, draws)])
    phase0 = np.array([d[0] if sp.phase is None else sp.phase for sp, d in zip(specs, draws)])

    # One gait phase shared by walk / run / turn, advancing at their blended frequency, so a walk -> run
    # change keeps the legs in step.
    gait = np.array([sp.mode in GAIT_MODES for sp in specs])
    gait_w = w[:, gait].sum(axis=1) if gait.any() else np.zeros(T)
    gait_f = np.where(gait_w > 1e-9, (w[:, gait] * freqs[gait]).sum(axis=1) / np.maximum(gait_w, 1e-9), 0.0)
    first_gait = int(np.argmax(gait)) if gait.any() else 0
    gait_phase = 2 * np.pi * (phase0[first_gait] + np.concatenate([[0.0], np.cumsum(gait_f[:-1]) / fps]))

    euler = np.zeros((T, NUM_JOINTS, 3))
    lift = np.zeros(T)
    forward = np.zeros(T)  # m/s along the facing direction
    yaw_rate = np.zeros(T)  # rad/s
    for i, sp in enumerate(specs):
        if sp.mode in GAIT_MODES:
            phase = gait_phase
        else:
            phase = 2 * np.pi * (phase0[i] + freqs[i] * (t - starts[i]))
        frames = _mode_frames(sp.mode, phase, amp=amps[i], period=1.0 / freqs[i], offsets=offsets)
        seg_euler, seg_lift = frames.euler, frames.lift
        if sp.mirror:
            seg_euler = mirror_euler(seg_euler)
        wi = w[:, i]
        euler += wi[:, None, None] * seg_euler
        lift += wi * seg_lift
        forward += wi * gait_speed(sp.mode, amp=amps[i], freq=freqs[i], offsets=offsets)
        if sp.mode == "turn":
            yaw_rate += wi * TURN_RATE * amps[i] * speed * sp.speed * (-1.0 if sp.mirror else 1.0)

    heading = np.concatenate([[0.0], np.cumsum(yaw_rate[:-1]) / fps])  # (T,)
    facing = np.stack([np.sin(heading), -np.cos(heading)], axis=1)  # (T, 2): heading 0 faces -y
    xy = np.concatenate([np.zeros((1, 2)), np.cumsum(forward[:-1, None] * facing[:-1], axis=0) / fps])

    local = euler_to_matrix(euler)  # (T, 17, 3, 3)
    local[:, 0] = euler_to_matrix(np.stack([np.zeros(T), np.zeros(T), heading], axis=1)) @ local[:, 0]
    rel = forward_kinematics(local, offsets, np.zeros((T, 3)))  # (T, 17, 3) root at the origin
    lowest = rel[:, [R_ANKLE, L_ANKLE], 2].min(axis=1)  # (T,)
    root = np.concatenate([xy, (params.ankle_height - lowest + lift)[:, None]], axis=1)  # (T, 3)
    joints = rel + root[:, None, :]
    label = ">".join(sp.mode for sp in specs)
    return Motion(joints.astype(np.float32), float(fps), "h36m-17", label=label)
