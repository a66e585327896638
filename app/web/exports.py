"""Downloads made safe: every cell a spreadsheet would run as a formula -- text starting
with ``= + - @``, a tab or a carriage return, and not a plain number -- gets a leading
apostrophe (OWASP "CSV injection"); comment lines never carry a raw line break; file names
are safe on every system and keep their UTF-8 (RFC 6266).  The lab's own files are
``app.lab.exports``, the class's ``app.review.exports``.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterable, Iterator
from urllib.parse import quote

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


def credentials_data_url(credentials) -> str:
    """A ``data:`` URL holding one-time passwords as CSV, so they are downloaded without
    being stored anywhere (``credentials``: items with username, display_name, password)."""
    rows = [["username", "display_name", "initial_password"]]
    rows += [[item.username, item.display_name, item.password] for item in credentials]
    return "data:text/csv;charset=utf-8," + quote("".join(csv_table(rows)))


FILENAME_UNSAFE = re.compile(r'[\x00-\x1f\x7f/\\:*?"<>|;,%]+')


def attachment(parts: list[str], extension: str) -> str:
    """A Content-Disposition naming the download after its contents (course, assignment,
    student…): an ASCII ``filename`` for old clients and the UTF-8 ``filename*`` (RFC 6266
    / 5987) that browsers use, so "惯导实验_寻北_s1.csv" survives."""
    cleaned = [
        re.sub(r"\s+", "-", FILENAME_UNSAFE.sub("-", part).strip()).strip("-.") for part in parts
    ]
    stem = "_".join(part for part in cleaned if part)[:120] or "gyrolab"
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
