"""A student's readings saved as an Excel workbook (.xlsx), read as the text of a CSV file.

Students type their readings into Excel or WPS and save the workbook as it is.  Its sheet
of readings -- the first sheet with two rows that hold a number, so a cover sheet of
notes before it is passed over -- becomes tab-separated text, one line per row of the
sheet (empty rows as empty lines, so a line the readers name is the sheet's own row), and
is then read as a pasted table or a file is (:mod:`app.core.readings`,
:mod:`app.core.static_record`).  A number is the value the cell holds, written as the
shortest text that reads back as the same float: a typed 10.74 is "10.74"; a formula's
value as last calculated (an ``=AVERAGE`` row, which the readers then leave out); a date
and time as ISO 8601, which a logger's clock column is read from.
"""

from __future__ import annotations

from app.core.exceptions import UserError
from app.core.typed_numbers import is_number
from app.core.workbook_sheets import Row, SheetLimits, sheet_rows

READINGS_LIMITS = SheetLimits(
    max_unpacked_bytes=30_000_000,
    # ≈ 3.6 s of parsing at most; a 10 Hz record of an hour in two columns has ≈ 250,000
    max_sheet_elements=600_000,
    max_columns=40,  # eight positions and their labels, an IMU's axes
    old_excel="workbook.old_excel",
    unreadable="workbook.unreadable",
    too_large="workbook.too_large",
    too_many_elements="workbook.too_many_cells",
)
MAX_ROWS = 200_000


def _holds_readings(rows: list[Row]) -> bool:
    """Whether a sheet holds readings: two rows at least with a number in them."""
    return sum(any(is_number(cell) for cell in cells) for _, cells in rows[:50]) >= 2


def workbook_text(data: bytes) -> str:
    """The sheet of readings of a workbook as tab-separated text.

    Parameters
    ----------
    data : bytes
        The uploaded .xlsx.

    Returns
    -------
    str
        One line per row of the sheet, up to its last non-empty one, cells separated by
        tabs (a tab or a line break inside a cell's text is a space).

    Raises
    ------
    UserError
        ``workbook.old_excel`` (an .xls), ``workbook.unreadable``, ``workbook.too_large``,
        ``workbook.too_many_cells``, ``workbook.too_many_rows``.
    """
    rows = sheet_rows(data, READINGS_LIMITS, MAX_ROWS, chosen=_holds_readings)
    if len(rows) > MAX_ROWS:
        raise UserError("workbook.too_many_rows", limit=MAX_ROWS)
    lines: list[str] = []
    for number, cells in rows:
        lines.extend([""] * (number - 1 - len(lines)))
        while cells and not cells[-1]:
            cells.pop()
        lines.append("\t".join(" ".join(cell.split()) for cell in cells))
    return "\n".join(lines) + "\n"
