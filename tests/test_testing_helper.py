"""The golden-frame helper itself (real PNG files in tmp_path) and the synthetic test motion."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.testing import assert_frames_match, frame_error, synthetic_walk
from motion2video.video import read_image


@pytest.fixture(autouse=True)
def _clean_env(monkeypatch):
    monkeypatch.delenv("UPDATE_GOLDEN", raising=False)
    monkeypatch.delenv("MOTION2VIDEO_TEST_OUTPUT", raising=False)


def _frames(n: int = 3) -> np.ndarray:
    rng = np.random.default_rng(7)
    return rng.integers(20, 230, size=(n, 12, 16, 3), dtype=np.uint8)


def _write_goldens(monkeypatch, frames, golden):
    monkeypatch.setenv("UPDATE_GOLDEN", "1")
    result = assert_frames_match(frames, golden, tolerance=0)
    monkeypatch.delenv("UPDATE_GOLDEN")
    return result


def test_update_mode_writes_and_prunes(tmp_path, monkeypatch):
    golden = tmp_path / "golden" / "clip"
    frames = _frames(3)
    result = _write_goldens(monkeypatch, frames, golden)
    assert result.updated and result.errors == ()
    assert sorted(p.name for p in golden.iterdir()) == ["frame_000.png", "frame_001.png", "frame_002.png"]
    np.testing.assert_array_equal(read_image(golden / "frame_001.png"), frames[1])
    _write_goldens(monkeypatch, frames[:1], golden)  # fewer frames: stale goldens go
    assert sorted(p.name for p in golden.iterdir()) == ["frame_000.png"]


def test_matching_frames_pass(tmp_path, monkeypatch):
    golden = tmp_path / "golden"
    frames = _frames(2)
    _write_goldens(monkeypatch, frames, golden)
    result = assert_frames_match(frames, golden, tolerance=0, out_dir=tmp_path / "out")
    assert not result.updated and result.errors == (0.0, 0.0)
    assert not (tmp_path / "out").exists()
    # A single (H, W, 3) image is a one-frame clip.
    _write_goldens(monkeypatch, frames[0], tmp_path / "single")
    assert assert_frames_match(frames[:1], tmp_path / "single", tolerance=0).errors == (0.0,)
    nudged = frames.copy()
    nudged[1, 5, 5, 0] += 1
    assert assert_frames_match(nudged, golden, tolerance=1, out_dir=tmp_path / "out").errors == (0.0, 1.0)
    rel = assert_frames_match(nudged, golden, tolerance=1e-3, metric="rel_l1", out_dir=tmp_path / "out")
    assert rel.errors[1] == pytest.approx(1.0 / frames[1].astype(float).sum())


def test_mismatch_writes_actual_and_diff(tmp_path, monkeypatch):
    golden = tmp_path / "golden"
    frames = _frames(3)
    _write_goldens(monkeypatch, frames, golden)
    bad = frames.copy()
    bad[2, 3:6, 4:8] = 255 - bad[2, 3:6, 4:8]
    out = tmp_path / "out"
    with pytest.raises(AssertionError) as info:
        assert_frames_match(bad, golden, tolerance=1, out_dir=out, name="clip")
    message = str(info.value)
    assert "frame 2: max" in message and str(out) in message and "UPDATE_GOLDEN=1" in message
    assert sorted(p.name for p in out.iterdir()) == ["actual_002.png", "diff_002.png"]
    np.testing.assert_array_equal(read_image(out / "actual_002.png"), bad[2])
    diff = read_image(out / "diff_002.png")
    assert diff[3:6, 4:8].max() == 255  # stretched: the largest difference is white
    assert not diff[:3].any() and not diff[6:].any()  # only the changed block shows


def test_default_output_dir_from_env(tmp_path, monkeypatch):
    golden = tmp_path / "golden"
    frames = _frames(1)
    _write_goldens(monkeypatch, frames, golden)
    monkeypatch.setenv("MOTION2VIDEO_TEST_OUTPUT", str(tmp_path / "outputs"))
    with pytest.raises(AssertionError):
        assert_frames_match(frames // 2, golden, tolerance=0.01, metric="rel_l1", name="half")
    assert (tmp_path / "outputs" / "half" / "actual_000.png").is_file()
    assert (tmp_path / "outputs" / "half" / "diff_000.png").is_file()


def test_missing_goldens_fail_never_skip(tmp_path, monkeypatch):
    frames = _frames(2)
    with pytest.raises(AssertionError, match="does not exist.*UPDATE_GOLDEN=1"):
        assert_frames_match(frames, tmp_path / "nowhere", tolerance=1)
    golden = tmp_path / "golden"
    _write_goldens(monkeypatch, frames[:1], golden)
    with pytest.raises(AssertionError, match=r"missing \[1\]"):
        assert_frames_match(frames, golden, tolerance=1, out_dir=tmp_path / "out")
    _write_goldens(monkeypatch, frames, golden)
    with pytest.raises(AssertionError, match=r"extra \[1\]"):
        assert_frames_match(frames[:1], golden, tolerance=1, out_dir=tmp_path / "out")
    with pytest.raises(AssertionError, match="size"):
        assert_frames_match(np.zeros((2, 6, 6, 3), np.uint8), golden, tolerance=1, out_dir=tmp_path / "out")


def test_frame_error_metrics():
    a = np.zeros((2, 2, 3), np.uint8)
    b = np.full((2, 2, 3), 10, np.uint8)
    assert frame_error(a, b, "max") == 10.0
    assert frame_error(a, b, "rel_l1") == 1.0
    assert frame_error(a, a, "rel_l1") == 0.0
    assert frame_error(b, a, "rel_l1") == float("inf")
    with pytest.raises(ValueError, match="metric"):
        frame_error(a, b, "l2")


def test_synthetic_walk_is_human_like_and_seeded():
    a = synthetic_walk(40, fps=25.0, seed=1)
    assert a.joints.shape == (40, 17, 3) and a.fps == 25.0 and a.skeleton == "h36m-17"
    np.testing.assert_array_equal(a.joints, synthetic_walk(40, fps=25.0, seed=1).joints)
    assert not np.array_equal(a.joints, synthetic_walk(40, fps=25.0, seed=2).joints)
    j = a.joints
    height = j[:, 10, 2] - j[:, [3, 6], 2].min(axis=1)
    assert np.all((1.5 < height) & (height < 1.8))
    thigh = np.linalg.norm(j[:, 2] - j[:, 1], axis=-1)
    np.testing.assert_allclose(thigh, thigh[0], atol=1e-5)  # rigid bones
    # Right joints are on the body's right (-x in the body frame, facing -y): check at zero yaw-ish frames
    # through the hip axis pointing from right hip to left hip roughly along +x.
    hip_axis = j[:, 4] - j[:, 1]
    assert np.all(hip_axis[:, 0] > 0.1)
