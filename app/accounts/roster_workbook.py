"""A class roster saved as an Excel workbook (.xlsx): its first sheet's rows as text.

A university's student system hands rosters out as workbooks, and student numbers there are
often numbers -- saved as CSV they become "2.0230101E+09" or lose a leading zero, which
:mod:`app.accounts.roster_csv` refuses.  Read from the workbook itself, a whole number is
the student number as the cell holds it.  The file is untrusted: its unpacked size is
bounded before any XML is read, and openpyxl parses through defusedxml (no entity
expansion, no external entities).  An Excel 97-2003 file (.xls) is named as such, with the
fix.
"""

from __future__ import annotations

import io
import math
import zipfile
import zlib
from datetime import date, datetime, time

from app.core.exceptions import UserError

ZIP_MAGIC = b"PK\x03\x04"
OLE_MAGIC = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1"  # Excel 97-2003 (.xls), and other OLE files
MAX_UNPACKED_BYTES = 10_000_000  # the whole unpacked workbook; a roster of 2,000 is ~0.5 MB
# XML elements in one worksheet at most: openpyxl parses a sheet twice (its size, then its
# rows), ≈ 6 µs an element, empty or not, and 10 MB of "<row/>" is a 20 kB upload of 1.6
# million; a roster of 2,000 students in three columns has ≈ 28,000
MAX_SHEET_ELEMENTS = 200_000
MAX_COLUMNS = 26  # A-Z: a roster's columns are the first few
EXACT_WHOLE = 2**53  # floats hold every whole number below this exactly


def is_workbook(data: bytes) -> bool:
    """Whether ``data`` is a workbook (a zip such as .xlsx, or an old .xls), not text."""
    return data.startswith((ZIP_MAGIC, OLE_MAGIC))


def cell_text(value: object) -> str:
    """A cell as the roster reads it: a whole number without ".0" (2023010101, not
    2023010101.0), a date as ISO 8601, text as it is, an empty cell as ""."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, float) and math.isfinite(value):
        if value.is_integer() and abs(value) < EXACT_WHOLE:
            return str(int(value))
        return repr(value)
    if isinstance(value, datetime | date | time):
        return value.isoformat()
    return str(value)


def _elements(archive: zipfile.ZipFile, member: zipfile.ZipInfo) -> int:
    """How many XML elements a member holds (its "<" count, read in blocks: ≈ 5 ms for
    10 MB), without parsing it."""
    count = 0
    with archive.open(member) as stream:
        while block := stream.read(1 << 20):
            count += block.count(b"<")
    return count


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
    if data.startswith(OLE_MAGIC):
        raise UserError("roster.old_excel")
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            unpacked = sum(member.file_size for member in archive.infolist())
            if unpacked > MAX_UNPACKED_BYTES:
                raise UserError(
                    "roster.workbook_too_large", limit_mb=MAX_UNPACKED_BYTES // 1_000_000
                )
            for member in archive.infolist():
                if (
                    member.filename.startswith("xl/worksheets/")
                    and _elements(archive, member) > MAX_SHEET_ELEMENTS
                ):
                    raise UserError("roster.workbook_rows", limit=MAX_SHEET_ELEMENTS)
    except UserError:
        raise
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, zlib.error):
        raise UserError("roster.bad_workbook") from None
    import openpyxl  # only when a workbook is uploaded (0.2 s to import)

    rows: list[tuple[int, list[str]]] = []
    try:
        workbook = openpyxl.load_workbook(
            io.BytesIO(data), read_only=True, data_only=True, keep_links=False
        )
        try:
            sheet = workbook.worksheets[0]
            read = sheet.iter_rows(max_col=MAX_COLUMNS, values_only=True)
            for number, values in enumerate(read, start=1):
                cells = [cell_text(value).strip() for value in values]
                if any(cells):
                    rows.append((number, cells))
                    if len(rows) > max_rows:
                        break
        finally:
            workbook.close()
    except UserError:
        raise
    except Exception:  # an untrusted file through a third-party parser: any failure is
        # the file's (a broken zip member, forbidden XML, a missing part, a bad value)
        raise UserError("roster.bad_workbook") from None
    return rows
