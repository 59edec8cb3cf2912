"""`make demo` and the real photo: with ../shared/data/photos beside the repository the demo draws the
CMU walk's futures as the person of one real photo (pose estimated, cut around the person); without it, one note."""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.formats.video import read_video
from tests.test_pipeline import _demo_module


def test_photo_demo_is_skipped_with_one_line_without_the_photos(tmp_path, capsys):
    demo = _demo_module()
    out = tmp_path / "out"
    assert demo.run_photo_demo(out, photos=tmp_path / "no-photos") == {}
    printed = capsys.readouterr().out.strip()
    assert "\n" not in printed and printed.startswith("photo: skipped") and "skier.jpg" in printed
    assert not out.exists()


@pytest.mark.slow
def test_photo_demo_draws_the_walk_as_the_person_of_a_real_photo(photos_dir, tmp_path, capsys):
    """Not marked slow: 9 s on 2 shared cores beside one training (13-18 s beside two)."""
    demo = _demo_module()
    written = demo.run_photo_demo(tmp_path, photos=photos_dir)
    printed = capsys.readouterr().out
    assert set(written) == {"photo_body", "photo_body_structure", "photo_body_sheet"}
    assert all(path.is_file() for path in written.values())
    assert "estimated the person's pose" in printed and "photo: 2 futures of cmu_walk.npz" in printed
    frames, fps = read_video(written["photo_body"])
    # two cells of 256 px side by side, 16 observed + 48 future frames at the clip's 25 fps
    assert frames.shape[0] == 16 + 48 and frames.shape[1] == 256 and frames.shape[2] >= 2 * 256 and fps == 25
    # the person moves: the cells change over time, not a still of the photo
    first, last = frames[0].astype(int), frames[-1].astype(int)
    assert np.abs(first - last).mean() > 2.0
