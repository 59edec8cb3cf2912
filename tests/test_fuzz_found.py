"""Cases the reader fuzzer (tests/test_fuzz_readers.py, ``make fuzz``) found, kept as regular tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from motion2video.core.errors import InputError
from motion2video.formats.io import load_motion

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"


def test_face_csv_with_a_damaged_frame_number_is_one_line(tmp_path):
    """Found by `make fuzz`: the first frame number of a real LLV capture replaced by -1e308 made the row times
    span 1e306 s, and resampling asked numpy for an array of that many frames (ValueError)."""
    lines = (SHARED / "face" / "llv" / "dao.csv").read_text().splitlines(keepends=True)[:16]
    header, first = lines[0], lines[1]
    cells = first.split(",")
    number = next(i for i, cell in enumerate(cells) if cell.strip().lstrip("-").replace(".", "", 1).isdigit())
    cells[number] = "-1e308"
    path = tmp_path / "capture.csv"
    path.write_text(header + ",".join(cells) + "".join(lines[2:]))
    with pytest.raises(InputError, match="damaged timecode or frame number"):
        load_motion(path)


def test_deeply_nested_json_is_one_line_not_a_recursion_error(tmp_path):
    """Found by test_openpose_reader in a full run: json's decoder recursed past Python's limit."""
    from motion2video.core.errors import InputError
    from motion2video.formats.io import load_motion

    folder = tmp_path / "openpose"
    folder.mkdir()
    (folder / "000000000000_keypoints.json").write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(InputError, match="nested too deeply"):
        load_motion(folder)
