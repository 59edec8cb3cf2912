"""The generated sections of docs/ (motion2video.core.atomic.write_section): replaced between their markers,
refused where a page lacks them, and never at the cost of hand-written text someone placed between them."""

from __future__ import annotations

import pytest

from motion2video.core.atomic import check_section, write_section
from motion2video.core.errors import InputError

BEGIN, END = "<!-- s:begin -->", "<!-- s:end -->"


def test_the_block_is_replaced_and_the_rest_kept(tmp_path):
    doc = tmp_path / "results.md"
    doc.write_text(f"# Results\n\nbefore\n\n{BEGIN}\n## Generated\n\nold numbers\n{END}\n\nafter\n")
    write_section(doc, BEGIN, END, "## Generated\n\nnew numbers")
    assert doc.read_text() == f"# Results\n\nbefore\n\n{BEGIN}\n## Generated\n\nnew numbers\n{END}\n\nafter\n"
    missing = tmp_path / "new.md"
    write_section(missing, BEGIN, END, "## Generated")
    assert missing.read_text() == f"# Results\n\n{BEGIN}\n## Generated\n{END}\n"


def test_hand_written_sections_inside_the_markers_are_not_lost(tmp_path):
    doc = tmp_path / "results.md"
    text = f"# Results\n\n{BEGIN}\n### Three real photos (by hand)\n\nnotes\n\n## Generated\n\nold\n{END}\n"
    doc.write_text(text)
    with pytest.raises(ValueError, match="Three real photos"):
        write_section(doc, BEGIN, END, "## Generated\n\nnew")
    assert doc.read_text() == text  # nothing written


def test_a_document_without_the_markers_is_refused_and_left_as_it_was(tmp_path):
    doc = tmp_path / "results.md"
    text = f"# Results\n\n## Forecasting\n\nhand-written table\n\n{BEGIN}\nold\n"  # the end marker was removed
    doc.write_text(text)
    with pytest.raises(InputError, match=r"results\.md: no marker line <!-- s:end -->") as refused:
        write_section(doc, BEGIN, END, "new numbers")
    assert refused.value.path == str(doc)
    assert doc.read_text() == text  # nothing appended, nothing written
    doc.write_text("# Results\n\nno markers at all\n")
    with pytest.raises(InputError, match="no marker line <!-- s:begin -->"):
        check_section(doc, BEGIN, END)
    doc.write_text(f"# Results\n\n{END}\n\n{BEGIN}\n")
    with pytest.raises(InputError, match="comes before"):
        write_section(doc, BEGIN, END, "new numbers")
    assert doc.read_text() == f"# Results\n\n{END}\n\n{BEGIN}\n"
    assert check_section(tmp_path / "missing.md", BEGIN, END) == tmp_path / "missing.md"  # a new page is started
