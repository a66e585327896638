"""A student's readings saved as an Excel workbook (.xlsx), read as the text of a CSV file.

Students type their readings into Excel or WPS and save the workbook as it is.  Its sheet
of readings -- the one the student chooses where several hold readings (one a part, say),
else the one whose name says it holds the part being recorded ("纬度", "Part B"), else the
first sheet with two rows that hold a number, so a cover sheet of notes before it is
passed over -- becomes tab-separated text, one line per row of the sheet (empty rows as
empty lines, so a line the readers name is the sheet's own row), and is then read as a
pasted table or a file is (:mod:`app.core.readings`, :mod:`app.core.static_record`).  A
number is the value the cell holds, written as the shortest text that reads back as the
same float: a typed 10.74 is "10.74"; a formula's value as last calculated (an
``=AVERAGE`` row, which the readers then leave out); a date and time as ISO 8601, which a
logger's clock column is read from.
"""

from __future__ import annotations

from dataclasses import dataclass

from app.core.exceptions import UserError
from app.core.part_names import part_named
from app.core.typed_numbers import is_number
from app.core.workbook_sheets import Row, SheetLimits, all_sheets

READINGS_LIMITS = SheetLimits(
    max_unpacked_bytes=30_000_000,
    # a sheet ≈ 3.6 s of parsing at most, the whole workbook twice that (every sheet is
    # read, to offer those of readings); a 10 Hz record of an hour in two columns: ≈ 250,000
    max_sheet_elements=600_000,
    max_columns=40,  # eight positions and their labels, an IMU's axes
    old_excel="workbook.old_excel",
    unreadable="workbook.unreadable",
    too_large="workbook.too_large",
    too_many_elements="workbook.too_many_cells",
)
MAX_ROWS = 200_000


@dataclass(frozen=True)
class WorkbookReadings:
    """A workbook's sheet of readings as text, the sheet's name, and the names of every
    sheet that holds readings (where several do, the student chooses)."""

    text: str
    sheet: str
    sheets: tuple[str, ...]


def _holds_readings(rows: list[Row]) -> bool:
    """Whether a sheet holds readings: two rows at least with a number in them."""
    return sum(any(is_number(cell) for cell in cells) for _, cells in rows[:50]) >= 2


def _for_part(names: list[str], part: str | None) -> str | None:
    """The one sheet whose name says it holds ``part`` ("纬度", "Part B", "B"), if one does."""
    said = [name for name in names if part is not None and part_named(name) == part]
    return said[0] if len(said) == 1 else None


def workbook_readings(
    data: bytes, sheet: str | None = None, part: str | None = None
) -> WorkbookReadings:
    """A workbook's sheet of readings as tab-separated text.

    Parameters
    ----------
    data : bytes
        The uploaded .xlsx.
    sheet : str, optional
        The sheet chosen (its name); by default the one sheet whose name says it holds
        ``part`` where one does, else the first sheet that holds readings (two rows with
        a number in them; a cover sheet before it is passed over), else the first sheet.
    part : {"heading", "latitude"}, optional
        The part of the lab the readings are for.

    Returns
    -------
    WorkbookReadings
        One line per row of the sheet, up to its last non-empty one, cells separated by
        tabs (a tab or a line break inside a cell's text is a space); the sheet read; the
        sheets that hold readings.

    Raises
    ------
    UserError
        ``workbook.old_excel`` (an .xls), ``workbook.unreadable``, ``workbook.too_large``,
        ``workbook.too_many_cells``, ``workbook.too_many_rows``, ``workbook.no_such_sheet``.
    """
    sheets = all_sheets(data, READINGS_LIMITS, MAX_ROWS)
    names = [name for name, rows in sheets if _holds_readings(rows)]
    if sheet is not None and sheet not in dict(sheets):
        raise UserError("workbook.no_such_sheet", sheet=sheet[:100])
    chosen = sheet or _for_part(names, part) or (names[0] if names else sheets[0][0])
    rows = dict(sheets)[chosen]
    if len(rows) > MAX_ROWS:
        raise UserError("workbook.too_many_rows", limit=MAX_ROWS)
    lines: list[str] = []
    for number, cells in rows:
        lines.extend([""] * (number - 1 - len(lines)))
        while cells and not cells[-1]:
            cells.pop()
        lines.append("\t".join(" ".join(cell.split()) for cell in cells))
    return WorkbookReadings("\n".join(lines) + "\n", chosen, tuple(names))


def workbook_text(data: bytes) -> str:
    """The text of a workbook's first sheet of readings (:func:`workbook_readings`).

    Parameters
    ----------
    data : bytes
        The uploaded .xlsx.

    Returns
    -------
    str
        Its sheet of readings as tab-separated text, a line per row of the sheet.

    Raises
    ------
    UserError
        As :func:`workbook_readings`.
    """
    return workbook_readings(data).text
