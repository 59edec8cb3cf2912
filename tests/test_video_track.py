"""The video track: every frame's BlazePose landmarks and person segmentation of a video, cached by the
file's sha256 and shared by evaluate-frames --video, train-frames --video and the pose of `pose` / synthesize; the
frames the reconstruction protocol scores, over the whole video or its tail."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2video.evaluation.reconstruction import protocol_frames, tail_start
from motion2video.pose.estimate import estimate_video, iter_video_frames, track_frames
from motion2video.stages.people import track_cache_path, video_pose, video_track
from tests.test_pose import _cut_video


@pytest.fixture(autouse=True)
def private_cache(tmp_path_factory, monkeypatch):
    """Track and pose caches go to a temporary folder, not the user's ~/.cache."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.fixture(scope="module")
def dancer30(dancer_video, tmp_path_factory) -> Path:
    return _cut_video(dancer_video, tmp_path_factory.mktemp("clip") / "dancer30.avi", 30)


def test_protocol_frames_of_the_whole_video_and_of_its_tail():
    # the whole video: frame 0 then targets spread over it (the protocol as it was)
    assert protocol_frames(1571, targets=64) == list(range(0, 1571, 24))[:65]
    # the tail: frame 0 (the reference) then targets from round(0.8 * 1571) = 1257 on, spread over the tail
    assert tail_start(1571, 0.8) == 1257
    frames = protocol_frames(1571, targets=64, start_fraction=0.8)
    assert frames == [0] + list(range(1257, 1571, 4))[:64]
    assert protocol_frames(30, targets=3, start_fraction=0.8) == [0, 24, 26, 28]
    assert protocol_frames(30, targets=3, stride=1, start_fraction=0.8) == [0, 24, 25, 26]
    with pytest.raises(Exception, match="start fraction"):
        tail_start(30, 1.0)


@pytest.mark.slow
def test_video_track_is_cached_and_is_the_trackers_result(dancer30, tmp_path, capsys):
    notes: list[str] = []
    track = video_track(dancer30, cache=tmp_path, note=notes.append)
    assert track.num_frames == 30 and track.found.all() and track.segmentation.dtype == np.uint8
    assert "tracked dancer30.avi" in notes[-1] and track_cache_path(dancer30, "largest", tmp_path).is_file()
    again = video_track(dancer30, cache=tmp_path, note=notes.append)
    assert "read from the cache" in notes[-1]
    np.testing.assert_array_equal(again.xy, track.xy)
    np.testing.assert_array_equal(again.segmentation, track.segmentation)
    # the landmarks are the tracker's, bit for bit; the mask its segmentation within 8-bit rounding
    first = next(iter(track_frames(iter_video_frames(dancer30)))).landmarks
    np.testing.assert_array_equal(track.xy[0], first.xy)
    exact = first.person_mask(track.width, track.height)
    assert np.abs(track.person_mask(0) - exact).max() <= 1.0 / 255 + 1e-6
    # `pose` / synthesize derive their (smoothed) pose from the cached track instead of tracking again
    pose = video_pose(dancer30, cache=tmp_path, note=notes.append)
    assert "from its cached track" in notes[-1]
    np.testing.assert_array_equal(pose.points2d, estimate_video(dancer30).points2d)
