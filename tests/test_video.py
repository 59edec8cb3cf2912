"""Video / image writing and layouts, with the real ffmpeg encoder and real files in tmp_path."""

from __future__ import annotations

from fractions import Fraction

import imageio_ffmpeg
import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.formats.video import (
    ENCODER_ENV,
    ENCODERS,
    GREEN,
    RED,
    add_border,
    contact_sheet,
    grid,
    label,
    observed_future_video,
    probe_frame_rate,
    read_image,
    read_video,
    video_frame_count,
    write_image,
    write_video,
)


@pytest.fixture(params=ENCODERS)
def encoder(request, monkeypatch):
    """Run an mp4 test once per encoder (a separate ffmpeg process, and PyAV in this process)."""
    monkeypatch.setenv(ENCODER_ENV, request.param)
    return request.param


def _clip(frames: int, height: int, width: int, seed: int = 0) -> np.ndarray:
    """Smooth moving gradients (compress well, so read-back is close to the input)."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    out = np.empty((frames, height, width, 3), np.uint8)
    for t in range(frames):
        out[t, ..., 0] = 128 + 100 * np.sin((x + 3 * t + seed) / 9.0)
        out[t, ..., 1] = 128 + 100 * np.cos((y - 2 * t) / 7.0)
        out[t, ..., 2] = (x + y + 10 * t) % 256 // 2 + 60
    return out


def _no_temp_files(directory) -> bool:
    return not [p for p in directory.iterdir() if ".tmp" in p.name]


@pytest.mark.parametrize("fps", [30000 / 1001, 12.5, 7.3])
def test_mp4_roundtrip_exact_fps(tmp_path, fps, encoder):
    frames = _clip(8, 48, 64)
    path = write_video(tmp_path / "clip.mp4", frames, fps)
    assert path == tmp_path / "clip.mp4" and _no_temp_files(tmp_path)
    rate = probe_frame_rate(path)
    assert rate == Fraction(fps).limit_denominator(100000)
    meta = next(imageio_ffmpeg.read_frames(str(path)))  # ffmpeg's own (rounded) report agrees
    assert abs(meta["fps"] - fps) < 0.01 and tuple(meta["size"]) == (64, 48)
    back, back_fps = read_video(path)
    assert back.shape == frames.shape and back.dtype == np.uint8
    assert back_fps == pytest.approx(fps, abs=1e-9)
    assert np.abs(back.astype(int) - frames.astype(int)).mean() < 4.0


def test_mp4_odd_size_is_padded_not_scaled(tmp_path, encoder):
    frames = _clip(3, 47, 63)
    back, _ = read_video(write_video(tmp_path / "odd.mp4", frames, 25, preset="ultrafast"))
    assert back.shape == (3, 48, 64, 3)
    assert np.abs(back[:, :47, :63].astype(int) - frames.astype(int)).mean() < 4.0


def test_gif_roundtrip(tmp_path):
    frames = _clip(4, 32, 40)
    back, fps = read_video(write_video(tmp_path / "clip.gif", frames, 10.0))
    assert back.shape == frames.shape
    assert fps == pytest.approx(10.0)
    assert np.abs(back.astype(int) - frames.astype(int)).mean() < 12.0  # 256-colour palette
    assert _no_temp_files(tmp_path)


def test_failed_encode_leaves_nothing_and_keeps_old_file(tmp_path, encoder):
    path = tmp_path / "keep.mp4"
    write_video(path, _clip(2, 16, 16), 10)
    before = path.read_bytes()
    # A real encoder failure: libx264 refuses a 40000-pixel-wide frame.
    with pytest.raises(RuntimeError, match="keep.mp4"):
        write_video(path, np.zeros((1, 2, 40000, 3), np.uint8), 10)
    assert path.read_bytes() == before
    assert _no_temp_files(tmp_path)


def test_unwritable_destination_raises_input_error_before_encoding(tmp_path, encoder):
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("x")
    target = blocker / "out.mp4"
    with pytest.raises(InputError) as info:
        write_video(target, _clip(1, 8, 8), 10)
    assert str(target) in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(InputError, match="extension"):
        write_video(tmp_path / "clip.avi", _clip(1, 8, 8), 10)
    with pytest.raises(InputError, match="fps"):
        write_video(tmp_path / "clip.mp4", _clip(1, 8, 8), 0.0)
    with pytest.raises(InputError, match="preset"):
        write_video(tmp_path / "clip.mp4", _clip(1, 8, 8), 10, preset="warp")
    with pytest.raises(InputError, match="encoder"):
        write_video(tmp_path / "clip.mp4", _clip(1, 8, 8), 10, encoder="gstreamer")
    with pytest.raises(InputError):
        write_image(blocker / "x.png", _clip(1, 8, 8)[0])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["not_a_dir"]


def test_both_encoders_write_the_same_video(tmp_path):
    """Same frame count, exact rate and fidelity from either encoder (their pixels differ by compression
    noise: two builds of libx264); a long clip checks that the in-process encoder's timestamps stay right
    after the muxer has started."""
    frames = _clip(120, 48, 64)
    back = {}
    for name in ENCODERS:
        path = write_video(tmp_path / f"{name}.mp4", frames, 30000 / 1001, encoder=name)
        assert video_frame_count(path) == 120 and probe_frame_rate(path) == Fraction(30000, 1001)
        back[name], _ = read_video(path)
    error = {name: np.abs(clip.astype(int) - frames.astype(int)).mean() for name, clip in back.items()}
    assert max(error.values()) < 4.0 and abs(error["pyav"] - error["ffmpeg"]) < 0.3, error


def test_video_frame_count_refuses_what_does_not_read_back(tmp_path, encoder):
    path = write_video(tmp_path / "clip.mp4", _clip(30, 32, 32), 25)
    assert video_frame_count(path) == 30 and video_frame_count(path, decode_first=False) == 30
    data = path.read_bytes()
    for cut in (0, 100, len(data) // 2, len(data) - 50):
        truncated = tmp_path / f"cut{cut}.mp4"
        truncated.write_bytes(data[:cut])
        assert video_frame_count(truncated) is None, cut
    text = tmp_path / "notes.mp4"
    text.write_text("not a video\n" * 50)  # ffmpeg would read this as an ANSI-art "video"
    assert video_frame_count(text) is None
    assert video_frame_count(tmp_path / "missing.mp4") is None
    gif = write_video(tmp_path / "clip.gif", _clip(4, 16, 16), 10)
    assert video_frame_count(gif) == 4


def test_missing_parent_directories_are_created(tmp_path):
    path = write_image(tmp_path / "a" / "b" / "img.png", _clip(1, 10, 12)[0])
    assert path.is_file()


def test_image_roundtrip_is_exact(tmp_path):
    image = _clip(1, 21, 33)[0]
    np.testing.assert_array_equal(read_image(write_image(tmp_path / "img.png", image)), image)
    assert _no_temp_files(tmp_path)


def test_add_border_and_label():
    frames = np.full((2, 40, 50, 3), 100, np.uint8)
    framed = add_border(frames, GREEN, 3)
    assert framed.shape == frames.shape
    assert framed[1, 0, 25].tolist() == list(GREEN) and framed[1, 39, 49].tolist() == list(GREEN)
    assert framed[1, 2, 25].tolist() == list(GREEN) and framed[1, 3, 25].tolist() == [100, 100, 100]
    single = add_border(frames[0], RED, 2)
    assert single.shape == (40, 50, 3) and single[0, 0].tolist() == list(RED)
    texted = label(frames, "sample 1")
    changed = np.argwhere(np.any(texted != frames, axis=-1))
    assert changed.size and changed[:, 1].max() < 20  # only the top strip
    np.testing.assert_array_equal(texted, label(frames, "sample 1"))  # deterministic
    bottom = label(frames, "7", corner="bottom-left")
    assert np.argwhere(np.any(bottom != frames, axis=-1))[:, 1].min() > 20


def test_grid_holds_last_frame_and_checks_inputs():
    a = np.full((3, 10, 12, 3), 50, np.uint8)
    b = np.full((5, 10, 12, 3), 200, np.uint8)
    b[4] = 220
    c = np.full((1, 10, 12, 3), 90, np.uint8)
    out = grid([a, b, c], columns=2, gap=2)
    assert out.shape == (5, 22, 26, 3)
    assert out[4, 0, 0].tolist() == [50] * 3  # a holds its last frame
    assert out[4, 0, 14].tolist() == [220] * 3
    assert out[4, 12, 14].tolist() == [0] * 3  # empty cell
    assert out[0, 10, 0].tolist() == [0] * 3  # gap
    assert grid([a, b, c]).shape == (5, 22, 26, 3)  # default columns = ceil(sqrt(3)) = 2
    with pytest.raises(ValueError, match="labels"):
        grid([a, b], labels=["one"])
    with pytest.raises(ValueError, match="clip 1"):
        grid([a, np.zeros((2, 8, 12, 3), np.uint8)])


def test_observed_future_video_layout():
    observed = np.full((4, 40, 24, 3), 60, np.uint8)
    futures = [np.full((6, 40, 24, 3), 120 + 20 * k, np.uint8) for k in range(3)]
    futures[2] = futures[2][:2]
    video = observed_future_video(observed, futures, [f"sample {k + 1}" for k in range(3)], columns=3)
    assert video.shape == (10, 40, 3 * 24 + 2 * 2, 3)
    for k in range(3):
        x0 = k * 26
        assert video[3, 39, x0 + 12].tolist() == list(GREEN)  # observed frames: green frame
        assert video[4, 39, x0 + 12].tolist() == list(RED)  # predicted frames: red frame
        assert video[3, 30, x0 + 12].tolist() == [60] * 3  # every cell starts with the same observed frames
    assert video[9, 30, 2 * 26 + 12].tolist() == [160] * 3  # the short future holds its last frame
    with pytest.raises(ValueError, match="future 0"):
        observed_future_video(observed, [np.zeros((2, 10, 24, 3), np.uint8)])


def test_contact_sheet():
    frames = _clip(10, 16, 20)
    sheet = contact_sheet(frames, every=2, columns=3, numbered=False, gap=1)
    assert sheet.shape == (2 * 16 + 1, 3 * 20 + 2, 3)
    np.testing.assert_array_equal(sheet[:16, 21:41], frames[2])
    np.testing.assert_array_equal(sheet[17:, 21:41], frames[8])
    numbered = contact_sheet(frames, every=5)
    assert numbered.shape == (16, 2 * 20 + 2, 3)
