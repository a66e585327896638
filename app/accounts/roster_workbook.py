"""A class roster saved as an Excel workbook (.xlsx): its first sheet's rows as text.

A university's student system hands rosters out as workbooks, and student numbers there are
often numbers -- saved as CSV they become "2.0230101E+09" or lose a leading zero, which
:mod:`app.accounts.roster_csv` refuses.  Read from the workbook itself, a whole number is
the student number as the cell holds it (:func:`app.core.workbook_sheets.cell_text`).  The
file is untrusted and bounded as :mod:`app.core.workbook_sheets` says; an Excel 97-2003
file (.xls) is named as such, with the fix.
"""

from __future__ import annotations

from app.core.workbook_sheets import OLE_MAGIC, SheetLimits, cell_text, is_workbook, sheet_rows

__all__ = ["OLE_MAGIC", "cell_text", "is_workbook", "workbook_rows"]

MAX_UNPACKED_BYTES = 10_000_000  # the whole unpacked workbook; a roster of 2,000 is ~0.5 MB
# XML elements in one worksheet at most: a roster of 2,000 students in three columns has
# ≈ 28,000
MAX_SHEET_ELEMENTS = 200_000
MAX_COLUMNS = 26  # A-Z: a roster's columns are the first few
ROSTER_LIMITS = SheetLimits(
    max_unpacked_bytes=MAX_UNPACKED_BYTES,
    max_sheet_elements=MAX_SHEET_ELEMENTS,
    max_columns=MAX_COLUMNS,
    old_excel="roster.old_excel",
    unreadable="roster.bad_workbook",
    too_large="roster.workbook_too_large",
    too_many_elements="roster.workbook_rows",
)


def workbook_rows(data: bytes, max_rows: int) -> list[tuple[int, list[str]]]:
    """The first worksheet's non-empty rows as (row number in the sheet, cells as text),
    at most ``max_rows`` + 1 of them (one more says "too many").

    Raises
    ------
    UserError
        ``roster.old_excel`` for an .xls, ``roster.bad_workbook`` for anything that is not
        a readable .xlsx, ``roster.workbook_too_large`` when it unpacks past
        ``MAX_UNPACKED_BYTES``, ``roster.workbook_rows`` when a worksheet holds more than
        ``MAX_SHEET_ELEMENTS`` XML elements (empty rows and cells too: each costs time).
    """
    return sheet_rows(data, ROSTER_LIMITS, max_rows)
