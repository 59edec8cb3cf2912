"""The golden-frame helper itself (real PNG files in tmp_path) and the synthetic test motion."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2video.testing.golden import (MANIFEST, assert_frames_match, diff_image, frame_error, golden_clip, panel_layout,
                                  select_indices, ssim, synthetic_walk)
from motion2video.formats.video import read_image, write_image, write_video


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
    assert sorted(p.name for p in golden.iterdir()) == ["frame_000.png", "frame_001.png", "frame_002.png", MANIFEST]
    np.testing.assert_array_equal(read_image(golden / "frame_001.png"), frames[1])
    _write_goldens(monkeypatch, frames[:1], golden)  # fewer frames: stale goldens go
    assert sorted(p.name for p in golden.iterdir()) == ["frame_000.png", MANIFEST]


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


def test_mismatch_writes_actual_and_diff_panel(tmp_path, monkeypatch):
    golden = tmp_path / "golden"
    frames = _frames(3)
    _write_goldens(monkeypatch, frames, golden)
    bad = frames.copy()
    bad[2, 3:6, 4:8] = 255 - bad[2, 3:6, 4:8]
    out = tmp_path / "out"
    (out).mkdir()
    (out / "diff_000.png").write_bytes(b"stale from an earlier run")
    with pytest.raises(AssertionError) as info:
        assert_frames_match(bad, golden, tolerance=1, out_dir=out, name="clip")
    message = str(info.value)
    assert "frame 2: max" in message and str(out / "diff_002.png") in message and "--update-golden" in message
    assert sorted(p.name for p in out.iterdir()) == ["actual_002.png", "diff_002.png"]  # the stale one went
    np.testing.assert_array_equal(read_image(out / "actual_002.png"), bad[2])
    panel = read_image(out / "diff_002.png")
    layout = panel_layout(12, 16, 3)
    assert panel.shape == (layout.height, layout.width, 3) and layout.scale == 10
    s = layout.scale

    def box(name):  # the panel's image back at frame size (each pixel was enlarged s x s)
        rows, cols = layout.boxes[name]
        return panel[rows, cols][::s, ::s]

    np.testing.assert_array_equal(box("golden"), frames[2])
    np.testing.assert_array_equal(box("actual"), bad[2])
    np.testing.assert_array_equal(box("diff"), diff_image(bad[2], frames[2]))
    assert box("diff")[3:6, 4:8].max() == 255  # stretched: the largest difference is white
    assert not box("diff")[:3].any() and not box("diff")[6:].any()  # only the changed block shows
    text = panel[layout.text_top:]
    assert (text > 200).sum() > 200  # the numbers are written under the images
    assert (panel[: layout.boxes["golden"][0].start] > 200).sum() > 50  # and the titles above


def test_ssim_metric_and_selected_frames(tmp_path, monkeypatch):
    frames = _frames(10)
    golden = tmp_path / "golden"
    monkeypatch.setenv("UPDATE_GOLDEN", "1")
    written = assert_frames_match(frames, golden, tolerance=0, every=4, fps=12.5)
    monkeypatch.delenv("UPDATE_GOLDEN")
    assert written.indices == (0, 4, 8)
    assert sorted(p.name for p in golden.iterdir()) == ["frame_000.png", "frame_004.png", "frame_008.png", MANIFEST]
    assert json.loads((golden / MANIFEST).read_text()) == {"frames": 10, "width": 16, "height": 12, "fps": 12.5,
                                                           "indices": [0, 4, 8]}
    noisy = frames.copy()
    noisy[4] = np.clip(noisy[4].astype(int) + 3, 0, 255).astype(np.uint8)
    noisy[5] = 0  # not a kept frame: never compared
    result = assert_frames_match(noisy, golden, tolerance=0.05, metric="ssim", every=4, fps=12.5)
    assert result.errors[0] == 0.0 and result.errors[2] == 0.0 and 0 < result.errors[1] < 0.05
    assert result.errors[1] == pytest.approx(1 - ssim(noisy[4], frames[4]))
    with pytest.raises(AssertionError, match=r"frame 4: ssim 0\.\d+ \(1-ssim"):
        assert_frames_match(noisy, golden, tolerance=1e-6, metric="ssim", every=4, out_dir=tmp_path / "out")
    # The same frames chosen by explicit indices compare the same way; other indices are refused.
    assert assert_frames_match(frames, golden, tolerance=0, indices=[8, 0, 4]).indices == (0, 4, 8)
    with pytest.raises(AssertionError, match=r"compares frames \[0, 5\] but the golden .* keeps frames \[0, 4, 8\]"):
        assert_frames_match(frames, golden, tolerance=0, indices=[0, 5])
    with pytest.raises(ValueError, match="out of range"):
        assert_frames_match(frames, golden, tolerance=0, indices=[10])
    assert select_indices(5) == (0, 1, 2, 3, 4) and select_indices(5, every=2) == (0, 2, 4)


def test_count_size_and_fps_checked_first(tmp_path, monkeypatch):
    frames = _frames(6)
    golden = tmp_path / "golden"
    monkeypatch.setenv("UPDATE_GOLDEN", "1")
    assert_frames_match(frames, golden, tolerance=0, indices=[0, 3], fps=25)
    monkeypatch.delenv("UPDATE_GOLDEN")
    with pytest.raises(AssertionError) as info:  # every difference named in one message, before any pixel
        assert_frames_match(np.zeros((7, 10, 16, 3), np.uint8), golden, tolerance=0, indices=[0, 3], fps=30)
    message = str(info.value)
    assert "(7 frames of 16x10 at 30 fps) does not match the golden" in message
    assert "frame count 7 vs 6; size 16x10 vs 16x12; fps 30 vs 25" in message
    with pytest.raises(AssertionError, match=r"fps 24 vs 25"):
        assert_frames_match(frames, golden, tolerance=0, indices=[0, 3], fps=24)
    assert assert_frames_match(frames, golden, tolerance=0, indices=[0, 3]).errors == (0.0, 0.0)  # fps unknown


def test_bad_goldens_fail_clearly(tmp_path, monkeypatch):
    frames = _frames(2)
    # A golden "directory" that is a file: compared and in update mode.
    as_file = tmp_path / "clip"
    as_file.write_text("not a folder")
    with pytest.raises(AssertionError, match=r"clip: golden path .*clip is a file, not a directory"):
        assert_frames_match(frames, as_file, tolerance=0)
    with pytest.raises(AssertionError, match=r"is a file, not a directory"):
        assert_frames_match(frames, as_file, tolerance=0, update=True)
    assert as_file.read_text() == "not a folder"
    # A corrupt golden PNG, and a golden of another size.
    golden = tmp_path / "golden"
    _write_goldens(monkeypatch, frames, golden)
    (golden / "frame_001.png").write_bytes(b"\x89PNG\r\n\x1a\n truncated")
    with pytest.raises(AssertionError, match=r"cannot decode frame_001\.png \(corrupt PNG\)"):
        assert_frames_match(frames, golden, tolerance=0)
    write_image(golden / "frame_001.png", np.zeros((8, 8, 3), np.uint8))
    with pytest.raises(AssertionError, match=r"size: frame_001\.png is 8x8, not 16x12"):
        assert_frames_match(frames, golden, tolerance=0)
    (golden / MANIFEST).write_text("{ not json")
    with pytest.raises(AssertionError, match=r"cannot read the golden manifest"):
        assert_frames_match(frames, golden, tolerance=0)
    # Update mode repairs all of it.
    assert assert_frames_match(frames, golden, tolerance=0, update=True).updated
    assert assert_frames_match(frames, golden, tolerance=0).errors == (0.0, 0.0)


def test_update_keeps_unchanged_pngs_byte_identical(tmp_path, monkeypatch):
    frames = _frames(2)
    golden = tmp_path / "golden"
    _write_goldens(monkeypatch, frames, golden)
    # Same pixels, other bytes (another PNG compression level): an update must not rewrite the file.
    import cv2

    ok, data = cv2.imencode(".png", np.ascontiguousarray(frames[0][..., ::-1]), [cv2.IMWRITE_PNG_COMPRESSION, 0])
    (golden / "frame_000.png").write_bytes(data.tobytes())
    before = (golden / "frame_000.png").read_bytes()
    changed = frames.copy()
    changed[1, 0, 0] ^= 1
    assert assert_frames_match(changed, golden, tolerance=0, update=True).updated
    assert (golden / "frame_000.png").read_bytes() == before
    np.testing.assert_array_equal(read_image(golden / "frame_001.png"), changed[1])


def test_golden_clip_sources(tmp_path, mocap_dir):
    from motion2video.formats.io import load_motion, resample_motion
    from motion2video.apps.render import render_motion

    motion = resample_motion(load_motion(mocap_dir / "cmu" / "08_01.bvh"), 25.0).slice(0, 10)
    clip = golden_clip(motion, style="skeleton", size=64)
    np.testing.assert_array_equal(clip.frames, render_motion(motion, style="skeleton", size=64))
    assert clip.fps == 25.0 and "skeleton" in clip.what
    video = write_video(tmp_path / "walk.mp4", clip.frames, 25.0)
    from_video = golden_clip(video)
    assert from_video.frames.shape == (10, 64, 64, 3) and from_video.fps == 25.0
    gif = golden_clip(write_video(tmp_path / "walk.gif", clip.frames, 25.0))
    assert gif.frames.shape == (10, 64, 64, 3) and gif.fps == pytest.approx(25.0)
    assert golden_clip(clip.frames[0]).frames.shape == (1, 64, 64, 3)
    with pytest.raises(ValueError, match="style= and size="):
        golden_clip(motion)
    with pytest.raises(ValueError, match="Motion only"):
        golden_clip(clip.frames, style="skeleton")
    with pytest.raises(ValueError, match=".mp4"):
        golden_clip(tmp_path / "walk.avi")


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
    with pytest.raises(AssertionError, match="does not exist.*--update-golden.*UPDATE_GOLDEN=1"):
        assert_frames_match(frames, tmp_path / "nowhere", tolerance=1)
    golden = tmp_path / "golden"
    _write_goldens(monkeypatch, frames[:1], golden)
    with pytest.raises(AssertionError, match=r"frame count 2 vs 1"):
        assert_frames_match(frames, golden, tolerance=1, out_dir=tmp_path / "out")
    _write_goldens(monkeypatch, frames, golden)
    with pytest.raises(AssertionError, match=r"frame count 1 vs 2"):
        assert_frames_match(frames[:1], golden, tolerance=1, out_dir=tmp_path / "out")
    with pytest.raises(AssertionError, match="size 6x6 vs 16x12"):
        assert_frames_match(np.zeros((2, 6, 6, 3), np.uint8), golden, tolerance=1, out_dir=tmp_path / "out")


def test_goldens_without_manifest_still_compare(tmp_path, monkeypatch):
    """Goldens written before golden.json existed (PNGs only): the PNG set is the frame list."""
    frames = _frames(2)
    golden = tmp_path / "golden"
    _write_goldens(monkeypatch, frames, golden)
    (golden / MANIFEST).unlink()
    assert assert_frames_match(frames, golden, tolerance=0, fps=30).errors == (0.0, 0.0)
    with pytest.raises(AssertionError, match=r"missing \[2\], extra \[\]"):
        assert_frames_match(_frames(3), golden, tolerance=1)
    with pytest.raises(AssertionError, match=r"missing \[\], extra \[1\]"):
        assert_frames_match(frames[:1], golden, tolerance=1)
    with pytest.raises(AssertionError, match=r"size: frame_000\.png is 16x12, not 6x6"):
        assert_frames_match(np.zeros((2, 6, 6, 3), np.uint8), golden, tolerance=1)


def test_h264_noise_within_the_documented_tolerance(tmp_path, mocap_dir):
    """The README's numbers: a real render against its mp4 stays within SSIM 0.05 but not within 1 grey level;
    an mp4 against its own golden (same encoder) matches exactly."""
    from motion2video.formats.io import load_motion, resample_motion
    from motion2video.apps.render import render_motion

    motion = resample_motion(load_motion(mocap_dir / "mass" / "mass_run.bvh"), 25.0).slice(0, 25)
    raw = render_motion(motion, style="heatmap", size=96)
    golden = tmp_path / "raw"
    assert_frames_match(raw, golden, tolerance=0, every=6, fps=25.0, update=True)
    video = golden_clip(write_video(tmp_path / "run.mp4", raw, 25.0))
    noise = assert_frames_match(video.frames, golden, tolerance=0.05, metric="ssim", every=6, fps=video.fps)
    assert 0.005 < max(noise.errors) < 0.05
    with pytest.raises(AssertionError, match="max tolerance 1"):
        assert_frames_match(video.frames, golden, tolerance=1, every=6, fps=video.fps, out_dir=tmp_path / "out")
    assert_frames_match(video.frames, tmp_path / "from_video", tolerance=0, every=6, fps=video.fps, update=True)
    again = golden_clip(write_video(tmp_path / "again.mp4", raw, 25.0))
    exact = assert_frames_match(again.frames, tmp_path / "from_video", tolerance=0, every=6, fps=again.fps)
    assert len(exact.indices) >= 3 and exact.errors == (0.0,) * len(exact.indices)


def test_frame_error_metrics():
    a = np.zeros((8, 8, 3), np.uint8)
    b = np.full((8, 8, 3), 10, np.uint8)
    assert frame_error(a, b, "max") == 10.0
    assert frame_error(a, b, "rel_l1") == 1.0
    assert frame_error(a, a, "rel_l1") == 0.0
    assert frame_error(b, a, "rel_l1") == float("inf")
    assert frame_error(a, a, "ssim") == 0.0 and frame_error(a, b, "ssim") > 0.5
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
