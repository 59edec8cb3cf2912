"""Rows of numbers in text files (BVH motion lines, exp-map text), parsed fast and, when malformed, located."""

from __future__ import annotations

import io

import numpy as np

from motion2video.core.errors import InputError


def parse_number_rows(lines: list[tuple[int, str]], width: int, source: str, *, delimiter: str | None = None,
                      what: str = "value") -> np.ndarray:
    """Parse text rows of ``width`` numbers each.

    Args:
        lines: (line number, text) per row, 1-based numbers for messages.
        width: numbers per row.
        source: the file (messages).
        delimiter: None for whitespace, else the separator (``","``).
        what: the noun in messages (``"motion value"``).
    Returns:
        (len(lines), width) float64, all finite.
    Raises:
        InputError: naming the first line with the wrong count, a non-number, NaN or Inf.
    """
    try:
        # numpy's C text parser; it rejects ragged rows and non-numbers, which are then located below.
        values = np.loadtxt(io.StringIO("\n".join(line for _, line in lines)), dtype=np.float64, ndmin=2,
                            comments=None, delimiter=delimiter)  # (T, width)
    except ValueError:
        values = None
    if values is None or values.shape != (len(lines), width):
        for num, line in lines:
            row = line.split(delimiter)
            if len(row) != width:
                raise InputError(f"line {num}: expected {width} values, got {len(row)}", source)
            try:
                np.array(row, dtype=np.float64)
            except ValueError:
                raise InputError(f"line {num}: a {what} is not a number", source) from None
        raise InputError(f"cannot parse the {what}s", source)
    if not np.all(np.isfinite(values)):
        bad = int(np.argwhere(~np.isfinite(values))[0, 0])
        raise InputError(f"line {lines[bad][0]}: {what}s contain NaN or Inf", source)
    return values
