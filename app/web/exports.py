"""Downloads made safe: every cell a spreadsheet would run as a formula -- text starting
with ``= + - @``, a tab or a carriage return, and not a plain number -- gets a leading
apostrophe (OWASP "CSV injection"); comment lines never carry a raw line break; file names
are safe on every system and keep their UTF-8 (RFC 6266).  Excel workbooks are
``app.web.workbooks``, the lab's own files ``app.lab.exports``, the class's
``app.review.exports``.
"""

from __future__ import annotations

import base64
import csv
import io
import re
from collections.abc import Callable, Iterable, Iterator
from urllib.parse import quote

from app.web.workbooks import XLSX_MEDIA_TYPE, xlsx_table

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
