"""Excel workbooks (.xlsx) people upload instead of CSV: a sheet's rows as text.

The file is untrusted: its unpacked size, each worksheet's XML elements and all its parts'
together (shared strings, styles) are bounded before any XML is parsed (openpyxl parses a
sheet twice, ≈ 6 µs an element, empty or not: 10 MB of "<row/>" is a 20 kB upload of 1.6
million; 1.5 million shared strings, a 67 kB upload, took 12 s), and openpyxl parses through
defusedxml (no entity expansion, no external entities).  An Excel 97-2003 file (.xls),
as a school's records system still exports a class roster, is read with xlrd (its BIFF
records, no compression to unpack: bounded by the upload's own size and its sheets'
declared cells); one xlrd cannot read either is named as an old workbook, with the fix.
The callers -- a class roster
(:mod:`app.accounts.roster_workbook`), a student's readings (:mod:`app.core.workbook_text`)
-- set the bounds and say each problem in their own words.
"""

from __future__ import annotations

import io
import math
import zipfile
import zlib
from dataclasses import dataclass
from datetime import date, datetime, time

from app.core.exceptions import UserError

ZIP_MAGIC = b"PK\x03\x04"
OLE_MAGIC = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1"  # Excel 97-2003 (.xls), and other OLE files
EXACT_WHOLE = 2**53  # floats hold every whole number below this exactly

Row = tuple[int, list[str]]  # the row's number in the sheet, its cells as text


@dataclass(frozen=True)
class SheetLimits:
    """How much of an untrusted workbook is read, and the message key for each problem."""

    max_unpacked_bytes: int
    max_sheet_elements: int
    max_columns: int
    old_excel: str  # an .xls
    unreadable: str  # not a readable .xlsx
    too_large: str  # unpacks past max_unpacked_bytes (``limit_mb``)
    too_many_elements: str  # a worksheet past max_sheet_elements (``limit``)


def is_workbook(data: bytes) -> bool:
    """Whether an upload is a workbook, not text.

    Parameters
    ----------
    data : bytes
        The file's bytes.

    Returns
    -------
    bool
        True for a zip (such as .xlsx: "PK\\x03\\x04") or an OLE file (an old .xls).
    """
    return data.startswith((ZIP_MAGIC, OLE_MAGIC))


def cell_text(value: object) -> str:
    """A workbook cell's value as text.

    Parameters
    ----------
    value : object
        What openpyxl reads from the cell: None, a bool, a number, a date or time, text.

    Returns
    -------
    str
        A whole number without ".0" (2023010101, not 2023010101.0), other numbers as
        Python writes them (the shortest text that reads back as the same float), a date
        or time as ISO 8601, text as it is, an empty cell as "".
    """
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


def _checked(data: bytes, limits: SheetLimits) -> None:
    """Refuse a file that is no zip, one that unpacks too large, or a worksheet of too many
    elements -- before openpyxl parses any XML."""
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            unpacked = sum(member.file_size for member in archive.infolist())
            if unpacked > limits.max_unpacked_bytes:
                raise UserError(limits.too_large, limit_mb=limits.max_unpacked_bytes // 1_000_000)
            total = 0  # every part's: openpyxl reads the shared strings and styles whole
            for member in archive.infolist():
                elements = _elements(archive, member)
                total += elements
                if (
                    member.filename.startswith("xl/worksheets/")
                    and elements > limits.max_sheet_elements
                ) or total > 2 * limits.max_sheet_elements:
                    raise UserError(limits.too_many_elements, limit=limits.max_sheet_elements)
    except UserError:
        raise
    # NotImplementedError: a zip version or compression method the module does not read
    # (Deflate64, as 7-Zip and Windows write it); RuntimeError: a member behind a password
    except (
        zipfile.BadZipFile,
        OSError,
        ValueError,
        EOFError,
        zlib.error,
        NotImplementedError,
        RuntimeError,
    ):
        raise UserError(limits.unreadable) from None


def sheet_rows(data: bytes, limits: SheetLimits, max_rows: int) -> list[Row]:
    """The non-empty rows of a workbook's first worksheet, at most ``max_rows`` + 1 of them
    (one more says "too many").

    Parameters
    ----------
    data : bytes
        The uploaded file.
    limits : SheetLimits
        The bounds, and the keys of the problems.
    max_rows : int
        The most rows wanted.

    Returns
    -------
    list of (int, list of str)
        Each non-empty row's number in the sheet and its first ``max_columns`` cells
        (:func:`cell_text`, stripped).

    Raises
    ------
    UserError
        With ``limits``' keys: an .xls, anything that is not a readable .xlsx, a workbook
        that unpacks too large, a worksheet of too many XML elements.
    """
    return all_sheets(data, limits, max_rows, first_only=True)[0][1]


def all_sheets(
    data: bytes, limits: SheetLimits, max_rows: int, *, first_only: bool = False
) -> list[tuple[str, list[Row]]]:
    """Each worksheet's name and non-empty rows, in the workbook's order, at most
    ``max_rows`` + 1 rows of each (:func:`sheet_rows`; ``first_only``: the first sheet
    alone, the others not parsed).

    Parameters
    ----------
    data : bytes
        The uploaded file.
    limits : SheetLimits
        The bounds, and the keys of the problems (every part's XML elements together are
        bounded, so reading every sheet is bounded too).
    max_rows : int
        The most rows wanted of a sheet.
    first_only : bool
        Read the first sheet only.

    Returns
    -------
    list of (str, list of (int, list of str))
        Each sheet's name and rows; at least one.

    Raises
    ------
    UserError
        As :func:`sheet_rows`.
    """
    if data.startswith(OLE_MAGIC):
        return _old_excel_sheets(data, limits, max_rows, first_only)
    _checked(data, limits)
    import openpyxl  # only when a workbook is uploaded (0.2 s to import)

    sheets: list[tuple[str, list[Row]]] = []
    try:
        workbook = openpyxl.load_workbook(
            io.BytesIO(data), read_only=True, data_only=True, keep_links=False
        )
        try:
            for sheet in workbook.worksheets:
                rows: list[Row] = []
                read = sheet.iter_rows(max_col=limits.max_columns, values_only=True)
                for number, values in enumerate(read, start=1):
                    cells = [cell_text(value).strip() for value in values]
                    if any(cells):
                        rows.append((number, cells))
                        if len(rows) > max_rows:
                            break
                sheets.append((str(sheet.title), rows))
                if first_only:
                    break
        finally:
            workbook.close()
    except UserError:
        raise
    except Exception:  # an untrusted file through a third-party parser: any failure is
        # the file's (a broken zip member, forbidden XML, a missing part, a bad value)
        raise UserError(limits.unreadable) from None
    if not sheets:
        raise UserError(limits.unreadable)
    return sheets


def _old_excel_sheets(
    data: bytes, limits: SheetLimits, max_rows: int, first_only: bool
) -> list[tuple[str, list[Row]]]:
    """:func:`all_sheets` of an Excel 97-2003 workbook (.xls), read with xlrd: dates as
    dates (the workbook's 1900 or 1904 system), whole numbers without ".0", text as it is;
    a sheet that declares more cells than ``limits.max_sheet_elements`` refused."""
    import xlrd  # only when an .xls is uploaded

    if len(data) > limits.max_unpacked_bytes:
        raise UserError(limits.too_large, limit_mb=limits.max_unpacked_bytes // 1_000_000)
    sheets: list[tuple[str, list[Row]]] = []
    try:
        # xlrd writes its warnings about a damaged file to stdout by default: kept, not
        # printed (they would land in a command's JSON output, or the server's log)
        book = xlrd.open_workbook(file_contents=data, on_demand=True, logfile=io.StringIO())
        try:
            for index in range(1 if first_only else book.nsheets):
                sheet = book.sheet_by_index(index)
                if sheet.nrows * max(sheet.ncols, 1) > limits.max_sheet_elements:
                    raise UserError(limits.too_many_elements, limit=limits.max_sheet_elements)
                rows: list[Row] = []
                width = min(sheet.ncols, limits.max_columns)
                for number in range(sheet.nrows):
                    values = [_old_excel_value(sheet.cell(number, k), book.datemode)
                              for k in range(width)]  # fmt: skip
                    cells = [cell_text(value).strip() for value in values]
                    if any(cells):
                        rows.append((number + 1, cells))
                        if len(rows) > max_rows:
                            break
                sheets.append((str(sheet.name), rows))
        finally:
            book.release_resources()
    except UserError:
        raise
    except Exception:  # an untrusted file through a third-party parser: an OLE file that
        # is no workbook xlrd reads (encrypted, Excel 95's BIFF5 damaged, a Word file)
        raise UserError(limits.old_excel) from None
    if not sheets:
        raise UserError(limits.unreadable)
    return sheets


def _old_excel_value(cell, datemode: int) -> object:
    """An .xls cell's value as openpyxl would give it: None, bool, float, datetime, str."""
    import xlrd

    kind = cell.ctype
    if kind in (xlrd.XL_CELL_EMPTY, xlrd.XL_CELL_BLANK, xlrd.XL_CELL_ERROR):
        return None
    if kind == xlrd.XL_CELL_BOOLEAN:
        return bool(cell.value)
    if kind == xlrd.XL_CELL_DATE:
        try:
            return xlrd.xldate_as_datetime(cell.value, datemode)
        except (ValueError, OverflowError, xlrd.xldate.XLDateError):
            return float(cell.value)
    return cell.value
