"""Streaming: frames go from the renderer to the encoder chunk by chunk, so memory does not grow with length."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.formats.io import load_motion, save_motion
from motion2video.apps.render import CHUNK, iter_frames, render_motion
from motion2video.testing.golden import command_peak_rss_mb, tiled_motion
from motion2video.formats.video import (VideoWriter, grid, iter_grid, iter_observed_future, observed_future_video,
                                read_video, write_video)


def _walk(shared_dir, frames: int | None = None):
    motion = load_motion(shared_dir / "data" / "mocap" / "cmu" / "08_01.bvh")
    return motion if frames is None else motion.slice(0, frames)


def test_iter_frames_yields_chunks_equal_to_render_motion(shared_dir):
    motion = _walk(shared_dir, 70)
    chunks = list(iter_frames(motion, style="skeleton", size=64))
    assert [len(c) for c in chunks] == [CHUNK, CHUNK, 70 - 2 * CHUNK]
    np.testing.assert_array_equal(np.concatenate(chunks), render_motion(motion, style="skeleton", size=64))


def test_iter_frames_is_lazy(shared_dir):
    """Only as many frames are drawn as the consumer has asked for."""
    stream = iter_frames(_walk(shared_dir), style="skeleton", size=64)
    first = next(stream)
    assert first.shape == (CHUNK, 64, 64, 3)
    stream.close()


def test_write_video_from_a_generator_with_and_without_count(shared_dir, tmp_path):
    motion = _walk(shared_dir, 40)
    frames = render_motion(motion, style="skeleton", size=64)
    for name, count in (("known.mp4", 40), ("unknown.mp4", None), ("anim.gif", None)):
        path = write_video(tmp_path / name, iter_frames(motion, style="skeleton", size=64), motion.fps, n_frames=count)
        back, _ = read_video(path)
        assert back.shape == frames.shape
        assert np.abs(back.astype(int) - frames.astype(int)).mean() < 6.0
    with pytest.raises(ValueError, match="expected 41 frames"):
        write_video(tmp_path / "wrong.mp4", iter_frames(motion, style="skeleton", size=64), motion.fps, n_frames=41)
    assert not (tmp_path / "wrong.mp4").exists()
    assert not [p for p in tmp_path.iterdir() if ".tmp" in p.name]


@pytest.mark.parametrize("encoder", ["ffmpeg", "pyav"])
def test_video_writer_removes_its_temp_file_when_interrupted(tmp_path, encoder):
    path = tmp_path / "cut.mp4"
    with pytest.raises(KeyboardInterrupt):
        with VideoWriter(path, 25, encoder=encoder) as writer:
            writer.write(np.zeros((4, 16, 16, 3), np.uint8))
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_iter_grid_equals_grid_and_streams_generators():
    rng = np.random.default_rng(0)
    clips = [rng.integers(0, 255, (n, 12, 10, 3), dtype=np.uint8) for n in (5, 9, 3)]
    expected = grid(clips, ["a", "b", "c"], 2)

    def pairs(clip):
        for i in range(0, len(clip), 2):
            yield clip[i:i + 2]

    gens = [pairs(c) for c in clips]  # chunks of 2 from generators
    streamed = np.concatenate(list(iter_grid(gens, ["a", "b", "c"], 2, chunk=4)))
    np.testing.assert_array_equal(streamed, expected)
    observed = rng.integers(0, 255, (4, 12, 10, 3), dtype=np.uint8)
    futures = [rng.integers(0, 255, (n, 12, 10, 3), dtype=np.uint8) for n in (6, 2)]
    np.testing.assert_array_equal(
        np.concatenate(list(iter_observed_future(observed, [iter(f) for f in futures], ["s1", "s2"]))),
        observed_future_video(observed, futures, ["s1", "s2"]))


@pytest.mark.slow
def test_render_peak_memory_does_not_grow_with_clip_length(shared_dir, tmp_path):
    """A clip 4x longer (the same walk tiled) peaks at about the same resident memory.

    Held in memory, 4x the frames at 384x384 would add ~0.9 GB; streaming keeps the difference near zero.
    """
    motion = _walk(shared_dir)
    short, long = tmp_path / "short.npz", tmp_path / "long.npz"
    save_motion(tiled_motion(motion, 2), short)
    save_motion(tiled_motion(motion, 8), long)
    args = ["--size", "384", "--no-progress"]
    peak_short = command_peak_rss_mb(["render", short, "-o", tmp_path / "short.mp4", *args])
    peak_long = command_peak_rss_mb(["render", long, "-o", tmp_path / "long.mp4", *args])
    frames_long = 8 * motion.num_frames
    held_mb = frames_long * 384 * 384 * 3 / 2**20
    assert held_mb > 800  # the test would see a non-streaming render
    assert peak_long < 1.3 * peak_short, (peak_short, peak_long)
    assert read_video(tmp_path / "long.mp4")[0].shape[0] == frames_long
