"""Behaviour signatures on real clips, and the known-answer transfer benchmark's parts."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.core.rotations import rotation_z
from motion2video.evaluation import signatures as S
from motion2video.evaluation import transfer_benchmark as B


@pytest.fixture(scope="module")
def clip(mocap_dir):
    cache = {}

    def get(name: str) -> np.ndarray:
        if name not in cache:
            cache[name] = B.load_clip_25(str(mocap_dir), name)
        return cache[name]

    return get


def moved(joints: np.ndarray, angle: float, shift) -> np.ndarray:
    return joints @ rotation_z(np.asarray(angle)).T + np.asarray(shift)


def test_a_jump_raises_the_pelvis_and_a_walk_does_not(clip):
    jump = clip("cmu/02_04.bvh")[0:49]
    walk = clip("cmu/07_01.bvh")[8:57]
    assert S.pelvis_excursion(jump) > 0.5
    assert S.pelvis_excursion(walk) < 0.15


def test_running_is_faster_than_walking(clip):
    run = S.root_speed(clip("cmu/02_03.bvh")[0:33], 25.0)
    walk = S.root_speed(clip("cmu/07_01.bvh")[8:57], 25.0)
    assert 2.0 < run < 3.5 and 0.9 < walk < 1.7


def test_an_arabesque_lifts_the_ankle_higher_than_walking(clip):
    dance = S.kick_height(clip("cmu/05_14.bvh")[64:113])
    walk = S.kick_height(clip("cmu/07_01.bvh")[8:57])
    assert dance > 0.55 and walk < 0.3 and dance > 2 * walk


def test_a_spin_turns_a_full_circle_and_a_straight_walk_does_not(clip):
    assert S.heading_change(clip("acrnn/indian_04.bvh")[432:481]) > 5.0
    assert S.heading_change(clip("cmu/07_01.bvh")[8:57]) < 0.4


def test_dance_moves_the_limbs_faster_than_standing(clip):
    assert S.limb_speed(clip("cmu/05_14.bvh")[72:121], 25.0) > 2.0
    assert S.limb_speed(clip("cmu/16_01.bvh")[8:57], 25.0) < 0.6


def test_signatures_ignore_where_the_body_stands_and_faces(clip):
    x = clip("cmu/131_03.bvh")[124:173]
    y = moved(x, 1.1, (3.0, -2.0, 0.0))
    for name in S.SIGNATURES:
        assert S.signature(name, y, 25.0) == pytest.approx(S.signature(name, x, 25.0), rel=1e-9, abs=1e-9)
    assert S.posture_error(y[:1], x[0]) < 1e-9
    assert S.posture_error(x[20:21], x[0]) > 0.02


def test_real_bones_keep_their_length_and_stretched_ones_do_not(clip):
    x = clip("cmu/02_04.bvh")[0:49]
    assert S.bone_length_spread(x) < 0.01
    stretched = x.copy()
    stretched[:, S.L_WRIST] += np.linspace(0, 0.1, len(x))[:, None]
    assert S.bone_length_spread(stretched) > 0.05


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="17, 3"):
        S.pelvis_excursion(np.zeros((5, 16, 3)))
    with pytest.raises(ValueError, match="unknown signature"):
        S.signature("wobble", np.zeros((5, 17, 3)), 25.0)


def test_every_case_holds_its_behaviour_and_is_reenacted_from_other_subjects(clip):
    for case in B.CASES:
        data = clip(case.clip)
        assert case.start + 1 + case.horizon <= len(data), case
        targets = B.targets_for(case)
        assert len(targets) >= 2 and all(t[2] != B.SUBJECT_OF[case.clip] for t in targets)
    jumps = [c for c in B.CASES if c.behaviour == "jump"]
    for case in jumps:
        src = clip(case.clip)[case.start:case.start + 1 + case.horizon]
        assert S.pelvis_excursion(src) > 0.25, case


def test_copying_the_source_carries_every_signature_but_not_the_start_posture(mocap_dir):
    case = B.CASES[0]
    results = B.run_benchmark(str(mocap_dir), cases=(case,))
    assert {r.method for r in results} == {"copy"}
    for r in results:
        assert r.ratio == pytest.approx(1.0, abs=1e-9)
        assert r.start_error > 0.05 and r.bone_spread < 0.01



def test_posture_kept_is_one_for_a_held_posture_and_zero_for_a_copy_of_the_source(clip):
    """posture_kept: a re-enactment that holds the target's posture throughout keeps all of it (1, up to the
    source's own motion), one that turns into the source's poses (moved onto the target) keeps none (0), and one
    half way between keeps half; the same posture as the source's start gives NaN."""
    source = clip("cmu/05_14.bvh")[64:64 + 49]  # the arabesque: a moving body
    posture = clip("cmu/07_03.bvh")[30]  # a walker
    copy = B.copy_reenactment(source, posture)
    held = np.repeat(copy[:1], len(copy), axis=0) - copy[:1, :1] + copy[:, :1]  # the posture carried along the root
    held[0] = posture - posture[:1] + copy[:1, :1]
    becomes = held.copy()
    becomes[len(becomes) // 2:] = copy[len(copy) // 2:]
    assert B.posture_kept(source, posture, becomes) == pytest.approx(0.0, abs=1e-9)
    halfway = held.copy()
    halfway[1:] = 0.5 * (held[1:] + copy[1:])
    kept = B.posture_kept(source, posture, halfway)
    assert 0.2 < kept < 0.8
    whole = B.posture_kept(source, posture, held)
    assert whole == pytest.approx(2 * kept, rel=1e-6) and whole > 0.5
    assert np.isnan(B.posture_kept(source, source[0], source))


def test_feet_above_bends_the_knees_of_a_sinking_body_and_keeps_its_bones(clip):
    """A real standing posture pushed 0.25 m down: leg IK puts the ankles back on the floor, the knees bend
    (the pelvis comes closer to the ankles by the drop), every bone keeps its length; a walk whose ankles
    stay above the floor is unchanged."""
    from motion2video.core.skeletons import L_ANKLE, R_ANKLE, feet_above

    walk = clip("cmu/07_01.bvh")[8:57]
    floor = float(walk[:, [R_ANKLE, L_ANKLE], 2].min())
    np.testing.assert_array_equal(feet_above(walk, floor), walk)
    stand = clip("cmu/02_04.bvh")[:1]
    sunk = stand - np.array([0.0, 0.0, 0.25])
    fixed = feet_above(sunk, float(stand[0, [R_ANKLE, L_ANKLE], 2].min()))
    assert fixed[0, [R_ANKLE, L_ANKLE], 2].min() >= stand[0, [R_ANKLE, L_ANKLE], 2].min() - 1e-9
    np.testing.assert_allclose(S.bone_lengths(fixed), S.bone_lengths(stand), atol=1e-9)
    np.testing.assert_array_equal(fixed[0, 0], sunk[0, 0])  # the pelvis stays where it was put
    drop = (stand[0, 0, 2] - stand[0, R_ANKLE, 2]) - (fixed[0, 0, 2] - fixed[0, R_ANKLE, 2])
    assert drop == pytest.approx(0.25, abs=0.03)


# --- root-relative signatures: hand-made bodies whose answer is known ---------------------------


def standing(frames: int) -> np.ndarray:
    """(T, 17, 3) a still, upright H36M-17 body facing -y: pelvis 0.9 m up, ankles 0.1 m, thorax 1.4 m, the
    wrists hanging 0.5 m below the thorax."""
    pose = np.array([
        [0.0, 0.0, 0.9],  # pelvis
        [-0.1, 0.0, 0.9], [-0.1, 0.0, 0.5], [-0.1, 0.0, 0.1],  # right hip, knee, ankle
        [0.1, 0.0, 0.9], [0.1, 0.0, 0.5], [0.1, 0.0, 0.1],  # left hip, knee, ankle
        [0.0, 0.0, 1.15], [0.0, 0.0, 1.4], [0.0, 0.0, 1.52], [0.0, 0.0, 1.65],  # spine, thorax, neck, head
        [0.15, 0.0, 1.4], [0.2, 0.0, 1.15], [0.2, 0.0, 0.9],  # left shoulder, elbow, wrist
        [-0.15, 0.0, 1.4], [-0.2, 0.0, 1.15], [-0.2, 0.0, 0.9],  # right shoulder, elbow, wrist
    ])
    return np.repeat(pose[None], frames, axis=0)


def crouch(depth: float, frames: int = 9) -> np.ndarray:
    """The standing body lowering everything above the knees by up to ``depth`` metres (mid-sequence), feet
    on the ground: pelvis above the ankles changes by ``depth``."""
    j = standing(frames)
    drop = depth * np.sin(np.linspace(0.0, np.pi, frames))  # 0 -> depth -> 0
    upper = [0, 1, 4, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]
    j[:, upper, 2] -= drop[:, None]
    return j


def test_leg_extension_of_a_crouch_is_its_depth_and_the_ratio_follows():
    assert S.leg_extension(standing(5)) == 0.0
    assert S.leg_extension(crouch(0.3)) == pytest.approx(0.3)
    assert S.leg_extension(crouch(0.15)) / S.leg_extension(crouch(0.3)) == pytest.approx(0.5)


def test_a_stiff_body_lifted_along_the_root_path_keeps_the_pelvis_excursion_not_the_legs():
    """Why root-relative signatures exist: following the source's root path carries the pelvis's range exactly
    while the legs do nothing; only the root-relative signature tells."""
    source = crouch(0.3)
    stiff = standing(9)
    stiff[..., 2] -= 0.3 * np.sin(np.linspace(0.0, np.pi, 9))[:, None]  # the whole body sinks and rises
    assert S.pelvis_excursion(stiff) / S.pelvis_excursion(source) == pytest.approx(1.0)
    assert S.leg_extension(stiff) == pytest.approx(0.0, abs=1e-12)
    assert S.knee_bend(stiff) == pytest.approx(0.0, abs=1e-12) and S.arm_swing(stiff) == pytest.approx(0.0, abs=1e-12)


def test_arm_swing_is_the_wrist_range_relative_to_the_thorax():
    j = standing(11)
    j[:, S.R_WRIST, 2] = 1.4 + np.linspace(-0.5, 0.5, 11)  # right wrist from 0.5 below to 0.5 above the thorax
    j[:, S.L_WRIST, 2] = 1.4 + np.linspace(-0.5, -0.23, 11)  # the left one rises 0.27 m
    assert S.arm_swing(j) == pytest.approx(1.0)  # the larger of the two wrists
    lifted = j.copy()
    lifted[..., 2] += np.linspace(0.0, 0.7, 11)[:, None]  # rising with the whole body changes nothing
    assert S.arm_swing(lifted) == pytest.approx(1.0)
    half = standing(11)
    half[:, S.L_WRIST, 2] = 1.4 + np.linspace(-0.5, -0.23, 11)
    assert S.arm_swing(half) / S.arm_swing(j) == pytest.approx(0.27)


def test_knee_bend_is_the_range_of_the_hip_to_ankle_distance():
    j = standing(3)
    j[1, S.L_ANKLE] = [0.1, 0.3, 0.5]  # shin swung back: hip-ankle distance sqrt(0.3^2 + 0.4^2) = 0.5 (from 0.8)
    assert S.knee_bend(j) == pytest.approx(0.3)
    j[2, S.R_ANKLE] = [-0.1, 0.4, 0.6]  # the right leg bends further: distance sqrt(0.4^2 + 0.3^2) = 0.5 -> 0.3 too
    assert S.knee_bend(j) == pytest.approx(0.3)


def test_ankle_lift_of_a_kick_to_hip_height():
    j = standing(5)
    j[:, S.R_ANKLE, 2] = [0.1, 0.4, 0.9, 0.4, 0.1]  # up to the pelvis's height: 0.8 m relative to it
    j[:, S.R_ANKLE, 1] = [0.0, -0.4, -0.8, -0.4, 0.0]
    assert S.ankle_lift(j) == pytest.approx(0.8)
    low = standing(5)
    low[:, S.L_ANKLE, 2] = [0.1, 0.2, 0.3, 0.2, 0.1]
    assert S.ankle_lift(low) / S.ankle_lift(j) == pytest.approx(0.25)


def test_benchmark_scores_root_relative_ratios_beside_the_root_path_one(clip):
    """On a real held-out jump: the copy baseline carries every root-relative signature exactly (ratio 1), a
    stiff copy of the start posture carried along the root path keeps the pelvis excursion and none of them."""
    case = next(c for c in B.CASES if c.clip == "cmu/02_04.bvh")
    source = clip(case.clip)[case.start:case.start + 1 + case.horizon]
    posture = clip("cmu/07_03.bvh")[30]
    copy = B.score("copy", case, ("cmu/07_03.bvh", 30), source, posture, B.copy_reenactment(source, posture))
    assert copy.ratio == pytest.approx(1.0)
    assert set(copy.relative) == set(S.ROOT_RELATIVE_SIGNATURES)
    for name in S.ROOT_RELATIVE_SIGNATURES:
        src, _ = copy.relative[name]
        if src >= B.MIN_RELATIVE_AMPLITUDE:
            assert copy.relative_ratio(name) == pytest.approx(1.0)
        else:
            assert np.isnan(copy.relative_ratio(name))
    assert copy.relative["leg_extension"][0] > 0.2  # the jump's legs extend and crouch
    stiff = source[:1] + (source[:, :1] - source[:1, :1])  # the first posture, carried along the pelvis path
    rigid = B.score("stiff", case, ("cmu/07_03.bvh", 30), source, source[0], stiff)
    assert rigid.ratio == pytest.approx(1.0)
    assert rigid.relative_ratio("leg_extension") == pytest.approx(0.0, abs=1e-9)
    rows = B.summarise([copy, rigid])
    assert {r["method"] for r in rows} == {"copy", "stiff"}
    assert next(r for r in rows if r["method"] == "stiff")["relative"]["knee_bend"] == pytest.approx(0.0, abs=1e-9)
