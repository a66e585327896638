"""Excel workbooks a teacher downloads (the class table, one-time passwords): text stored
as text, so it is never a formula and a student number such as 202301010101 or 007 opens
as typed; the numeric columns as numbers.
"""

from __future__ import annotations

import io
import math
import re
import unicodedata
from collections.abc import Iterable

import xlsxwriter

XLSX_MEDIA_TYPE = "application/vnd.openxmlformats-officedocument.spreadsheetml.sheet"
XLSX_CELL_LIMIT = 32_767  # the most characters Excel keeps in one cell
XLSX_WIDEST_COLUMN = 60  # characters; longer text wraps at this width
_XLSX_UNSAFE = re.compile(r"[\x00-\x08\x0b-\x1f\x7f\ud800-\udfff]")


def xlsx_text(text: str) -> str:
    """A text cell as a workbook can hold it: control characters other than a tab or a line
    break become spaces (as in :func:`one_line`), a lone surrogate the replacement
    character, and text over Excel's 32,767 characters a cell is cut with an ellipsis."""
    text = _XLSX_UNSAFE.sub(
        lambda match: "\ufffd" if "\ud800" <= match.group() <= "\udfff" else " ", text
    )
    if len(text) > XLSX_CELL_LIMIT:
        text = text[: XLSX_CELL_LIMIT - 1] + "…"
    return text


def _shown_width(text: str) -> int:
    """Characters as a spreadsheet's column shows them: CJK and full-width ones count two."""
    line = max(text.split("\n"), key=len) if text else ""
    return sum(2 if unicodedata.east_asian_width(ch) in "WF" else 1 for ch in line)


def xlsx_table(rows: list[list], numeric: Iterable[int], sheet: str) -> bytes:
    """A whole table (header row first) as one Excel worksheet named ``sheet``.

    Text is stored as text -- never read as a formula, a number or a date, so
    "=HYPERLINK(…)" stays those characters and "202301010101" is not 2.02301E+11 -- and the
    cells of the ``numeric`` columns (indices) as numbers, so a teacher can sort and
    average them; an empty cell stays empty, a non-numeric or non-finite one text.  The
    header row is bold, frozen and filtered, each column as wide as its longest cell (at
    most ``XLSX_WIDEST_COLUMN``, longer text wrapping).
    """
    numeric = set(numeric)
    buffer = io.BytesIO()
    workbook = xlsxwriter.Workbook(
        buffer,
        {
            "in_memory": True,
            "strings_to_formulas": False,
            "strings_to_numbers": False,
            "strings_to_urls": False,
        },
    )
    header_format = workbook.add_format({"bold": True, "text_wrap": True, "valign": "top"})
    wrap_format = workbook.add_format({"text_wrap": True, "valign": "top"})
    sheet_ = workbook.add_worksheet(sheet)
    widths: dict[int, int] = {}
    for r, row in enumerate(rows):
        for c, cell in enumerate(row):
            if cell is None or cell == "":
                continue
            if r and c in numeric and not isinstance(cell, bool):
                try:
                    number = float(cell)
                except (TypeError, ValueError):
                    number = math.nan
                if math.isfinite(number):  # else kept as the text it is (Excel has no ∞)
                    sheet_.write_number(r, c, number)
                    widths[c] = max(widths.get(c, 0), len(str(cell)))
                    continue
            text = xlsx_text(str(cell))
            width = _shown_width(text)
            if r == 0:
                sheet_.write_string(r, c, text, header_format)
                width = min(width, 24)  # a long header wraps instead of widening its column
            elif width > XLSX_WIDEST_COLUMN or "\n" in text:
                sheet_.write_string(r, c, text, wrap_format)
            else:
                sheet_.write_string(r, c, text)
            widths[c] = max(widths.get(c, 0), width)
    for c, width in widths.items():
        sheet_.set_column(c, c, min(max(width, 6), XLSX_WIDEST_COLUMN) + 2)
    if rows:
        sheet_.freeze_panes(1, 0)
        sheet_.autofilter(0, 0, max(len(rows) - 1, 0), max(len(rows[0]) - 1, 0))
    workbook.close()
    return buffer.getvalue()
