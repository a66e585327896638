"""Downloads made safe: every cell a spreadsheet would run as a formula -- text starting
with ``= + - @``, a tab or a carriage return, and not a plain number -- gets a leading
apostrophe (OWASP "CSV injection"); comment lines never carry a raw line break; file names
are safe on every system and keep their UTF-8 (RFC 6266).  An Excel workbook
(:func:`xlsx_table`) stores text as text, so it is never a formula and a student number
such as 202301010101 or 007 opens as typed.  The lab's own files are
``app.lab.exports``, the class's ``app.review.exports``.
"""

from __future__ import annotations

import base64
import csv
import io
import math
import re
import unicodedata
from collections.abc import Callable, Iterable, Iterator
from urllib.parse import quote

import xlsxwriter

FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


ZIP_BLOCK = 64 * 1024


BOM = "\ufeff"


def neutralise(text: str) -> str:
    """A text cell as a spreadsheet will show it, never run it: formulas get an apostrophe."""
    if not text.startswith(FORMULA_STARTS) and not text.lstrip().startswith(FORMULA_STARTS):
        return text
    try:
        float(text)
    except ValueError:
        return "'" + text
    return text  # a plain number such as -10.75 stays a number


def one_line(text: str) -> str:
    """Line breaks (and other control characters) become spaces."""
    return "".join(" " if ord(ch) < 32 or ch in "\u2028\u2029\x85" else ch for ch in text)


def csv_line(cells: Iterable[object]) -> str:
    """One CSV line; text cells neutralised and kept on one line (a name needs no break)."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(
        [one_line(neutralise(cell)) if isinstance(cell, str) else cell for cell in cells]
    )
    return buffer.getvalue()


def comment_line(text: str) -> str:
    """A ``# ...`` line: line breaks and other control characters become spaces."""
    return "# " + one_line(text) + "\n"


def csv_table(rows: Iterable[list]) -> Iterator[str]:
    """A whole table (header row first) as CSV lines, UTF-8 BOM first (Excel and Chinese)."""
    yield BOM
    for row in rows:
        yield csv_line(row)


CREDENTIAL_COLUMNS = ["username", "display_name", "initial_password"]


def _credential_rows(credentials, header: list[str] | None) -> list[list[str]]:
    rows = [header or CREDENTIAL_COLUMNS]
    rows += [[item.username, item.display_name, item.password] for item in credentials]
    return rows


def credentials_data_url(credentials, header: list[str] | None = None) -> str:
    """A ``data:`` URL holding one-time passwords as CSV, so they are downloaded without
    being stored anywhere (``credentials``: items with username, display_name, password;
    ``header``: the column names, by default ``CREDENTIAL_COLUMNS``)."""
    rows = _credential_rows(credentials, header)
    return "data:text/csv;charset=utf-8," + quote("".join(csv_table(rows)))


def credentials_xlsx_data_url(credentials, header: list[str] | None = None) -> str:
    """The same one-time passwords as an Excel workbook in a ``data:`` URL: a student
    number such as 202301010101 or 007 stays the username as typed (Excel opens the CSV's
    as 2.02301E+11 or 7, and a slip printed from it would not log in)."""
    workbook = xlsx_table(_credential_rows(credentials, header), (), "passwords")
    return f"data:{XLSX_MEDIA_TYPE};base64," + base64.b64encode(workbook).decode("ascii")


def credential_downloads(credentials, parts: list[str], _: Callable[..., str]) -> dict[str, str]:
    """The one-time passwords page's two downloads, CSV and Excel, named after ``parts``
    (the course, or the account), their columns named as the page's table names them (a
    roster import reads those names back): a template context's ``csv_href`` /
    ``csv_name`` and ``xlsx_href`` / ``xlsx_name``."""
    header = [_("roster.username"), _("roster.display_name"), _("credentials.password")]
    stem = file_stem([*parts, "initial-passwords"])
    return {
        "csv_href": credentials_data_url(credentials, header),
        "csv_name": f"{stem}.csv",
        "xlsx_href": credentials_xlsx_data_url(credentials, header),
        "xlsx_name": f"{stem}.xlsx",
    }


# path and shell characters, control characters, and the invisible ones that reorder or
# hide what a name shows (a right-to-left override makes "report\u202efdp.csv" read as
# "reportvsc.pdf"): zero-width marks, bidirectional controls, the byte-order mark
FILENAME_UNSAFE = re.compile(
    r'[\x00-\x1f\x7f/\\:*?"<>|;,%\u061c\u200b-\u200f\u202a-\u202e\u2060-\u2069\ufeff]+'
)


def file_stem(parts: list[str]) -> str:
    """A file name's stem from its parts (course, assignment, student…), joined by "_":
    characters unsafe on some system become "-", the UTF-8 kept, at most 120 characters."""
    cleaned = [
        re.sub(r"\s+", "-", FILENAME_UNSAFE.sub("-", part).strip()).strip("-.") for part in parts
    ]
    return "_".join(part for part in cleaned if part)[:120] or "gyrolab"


def attachment(parts: list[str], extension: str) -> str:
    """A Content-Disposition naming the download after its contents (course, assignment,
    student…): an ASCII ``filename`` for old clients and the UTF-8 ``filename*`` (RFC 6266
    / 5987) that browsers use, so "惯导实验_寻北_s1.csv" survives."""
    stem = file_stem(parts)
    ascii_stem = "".join(
        ch if ch.isascii() and (ch.isalnum() or ch in "_.-") else "_" for ch in stem
    )
    ascii_stem = re.sub(r"-*_[-_]*", "_", ascii_stem).strip("_.-") or "gyrolab"
    return (
        f'attachment; filename="{ascii_stem}.{extension}"; '
        f"filename*=UTF-8''{quote(stem)}.{extension}"
    )


def safe_name(text: str) -> str:
    """A file or folder name from a username (which is already [A-Za-z0-9_.-])."""
    cleaned = "".join(ch if ch.isalnum() or ch in "_.-" else "_" for ch in text).lstrip(".")
    return cleaned or "student"


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
