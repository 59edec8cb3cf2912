"""Long captures: the BVH reader streams the motion lines and poses frames in chunks, with results
identical to reading and posing the whole clip at once."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.formats import bvh
from motion2video.formats.io import load_motion
from motion2video.testing.golden import repeated_bvh


def test_chunked_read_and_pose_equal_the_whole_clip(mocap_dir, tmp_path):
    """CMU 13_10 twice (4794 frames, three chunks of 2048): streamed values, chunked forward kinematics and
    the canonical joints (whole-clip medians in h36m_body_points) equal the all-at-once path exactly."""
    path = tmp_path / "long.bvh"
    frames = repeated_bvh(mocap_dir / "cmu" / "13_10.bvh", path, 2)
    assert frames > 2 * bvh.CHUNK_FRAMES
    streamed = bvh.read_bvh(path)
    whole = bvh.parse_bvh(path.read_text(), str(path))
    np.testing.assert_array_equal(streamed.values, whole.values)
    np.testing.assert_array_equal(bvh.bvh_world_positions(streamed), bvh._world_positions(whole))
    chunked = bvh.canonical_positions(streamed)
    at_once = bvh.canonical_positions(whole, chunk=frames)
    np.testing.assert_array_equal(chunked.nodes, at_once.nodes)
    np.testing.assert_array_equal(chunked.joints, at_once.joints)
    assert load_motion(path).num_frames == frames


@pytest.mark.parametrize("declared, message", [(5000, "file ends after 4794 of 5000 frames"),
                                               (4100, "more frame lines than the declared 4100")])
def test_frame_count_errors_across_chunks(mocap_dir, tmp_path, declared, message):
    path = tmp_path / "bad.bvh"
    repeated_bvh(mocap_dir / "cmu" / "13_10.bvh", path, 2, declared=declared)
    with pytest.raises(InputError, match=message) as err:
        bvh.read_bvh(path)
    assert str(path) in str(err.value)
