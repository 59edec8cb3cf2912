"""Retargeting a motion onto another body and posture (:mod:`motion2video.core.retarget`) on real clips: a
held-out CMU jump onto another subject's walking posture, and a Bandai-Namco wave onto a CMU walker."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.core.retarget import BONES, blend_weights, retarget_motion
from motion2video.core.rotations import heading_of, rotation_z
from motion2video.core.skeletons import PELVIS, bone_lengths, leg_length
from motion2video.data.windows import resample
from motion2video.evaluation import signatures as S
from motion2video.formats.mocap import load_mocap

BLEND = 10


def _clip(path, start: int, frames: int) -> np.ndarray:
    m = load_mocap(path)
    return resample(np.asarray(m.joints, np.float64), m.fps, 25.0)[start:start + frames]


@pytest.fixture(scope="module")
def bandai_dir(shared_dir):
    return shared_dir / "data" / "bandai"


@pytest.fixture(scope="module")
def jump(mocap_dir):
    return _clip(mocap_dir / "cmu/02_04.bvh", 0, 49)


@pytest.fixture(scope="module")
def walker(mocap_dir):
    return _clip(mocap_dir / "cmu/07_03.bvh", 30, 1)[0]


def _directions(joints: np.ndarray) -> np.ndarray:
    child, parent = np.array([b[0] for b in BONES]), np.array([b[1] for b in BONES])
    d = joints[..., child, :] - joints[..., parent, :]
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def test_it_starts_at_the_target_with_its_bones_and_then_moves_its_limbs_as_the_source(jump, walker):
    out = retarget_motion(jump, walker, blend_frames=BLEND)
    assert out.shape == jump.shape
    np.testing.assert_array_equal(out[0], walker)
    np.testing.assert_allclose(bone_lengths(out), np.repeat(bone_lengths(walker)[None], len(out), 0), atol=1e-9)
    turn = rotation_z(heading_of(walker) - heading_of(jump[0]))
    np.testing.assert_allclose(_directions(out[BLEND:]), _directions(jump[BLEND:]) @ turn.T, atol=1e-9)
    assert np.abs(_directions(out[1]) - _directions(jump[1]) @ turn.T).max() > 0.1  # still blending in
    # the root path: the source's, turned and scaled by the legs; heights above the floor after the blend
    scale = leg_length(walker[None]) / leg_length(jump)
    np.testing.assert_allclose(out[BLEND:, PELVIS, 2], scale * jump[BLEND:, PELVIS, 2], atol=1e-9)
    moved = (jump[-1, PELVIS, :2] - jump[0, PELVIS, :2]) @ turn[:2, :2].T * scale
    np.testing.assert_allclose(out[-1, PELVIS, :2] - walker[PELVIS, :2], moved, atol=1e-9)
    # the jump's root-relative signatures come across (within the ratio of the bodies' sizes)
    for name in S.ROOT_RELATIVE_SIGNATURES:
        assert 0.9 * scale <= S.signature(name, out, 25.0) / S.signature(name, jump, 25.0) <= 1.1 * scale, name


def test_turning_and_moving_the_target_turns_and_moves_the_result(jump, walker):
    turn = rotation_z(np.float64(2.0))
    moved = walker @ turn.T + np.array([1.5, -0.5, 0.0])
    a = retarget_motion(jump, walker, blend_frames=BLEND)
    b = retarget_motion(jump, moved, blend_frames=BLEND)
    np.testing.assert_allclose(b, a @ turn.T + np.array([1.5, -0.5, 0.0]), atol=1e-9)


def test_a_bandai_wave_onto_a_cmu_walker(bandai_dir, walker):
    """Another rig and another performer's body: the wave's arm swing comes across, the walker's bones stay."""
    wave = _clip(bandai_dir / "bvh" / "dataset-2_wave-both-hands_feminine_001.bvh.xz", 0, 120)
    out = retarget_motion(wave, walker, blend_frames=BLEND)
    np.testing.assert_allclose(bone_lengths(out[-1]), bone_lengths(walker), atol=1e-9)
    assert S.arm_swing(wave) > 0.3
    assert S.arm_swing(out) / S.arm_swing(wave) >= 0.8


def test_blend_weights_rise_smoothly_from_zero_to_one():
    w = blend_weights(20, 10)
    assert w[0] == 0.0 and np.all(w[10:] == 1.0) and np.all(np.diff(w) >= 0)
    assert np.all(blend_weights(3, 0)[1:] == 1.0)


def test_bad_shapes_are_refused(jump, walker):
    with pytest.raises(ValueError, match="17, 3"):
        retarget_motion(jump[:, :16], walker, blend_frames=BLEND)
