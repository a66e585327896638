"""How spreadsheets and instruments write a table of readings as text: the column separator
(a tab when copied, a semicolon in Europe, named on a first line "sep=;"), decimal commas,
a title line or two above the table, a row of units under its names, and one column of
decimal commas that a comma separator would split in two.  The layouts themselves are
:mod:`app.core.readings`.
"""

from __future__ import annotations

import re
from collections import Counter

from app.core.column_names import RATE_LIKE, is_hash_comment
from app.core.text_files import plain_text
from app.core.typed_numbers import is_number

# Excel's first line naming the separator ("sep=;"), which programs that write for Excel
# put above the table so that any locale's Excel splits it right
SEPARATOR_HINT = re.compile(r'\s*"?sep=([,;\t])"?[,;\t]*\s*', re.IGNORECASE)


def separator_hint(line: str) -> str | None:
    """The separator a file's first line names, as Excel reads it: "sep=;" → ";".

    Parameters
    ----------
    line : str
        The file's first line (a byte-order mark before it allowed).

    Returns
    -------
    str or None
        ``,``, ``;`` or a tab; None for any other line.
    """
    match = SEPARATOR_HINT.fullmatch(line.lstrip("\ufeff"))
    return match.group(1) if match else None


def without_separator_hint(text: str) -> tuple[str | None, str]:
    """A file's text with its "sep=;" first line blanked (the lines keep their numbers).

    Parameters
    ----------
    text : str
        The file's whole text.

    Returns
    -------
    hint : str or None
        The separator the first line names; None where there is no such line.
    text : str
        ``text``, that line empty.
    """
    first, end, rest = text.partition("\n")
    hint = separator_hint(first.rstrip("\r"))
    return (hint, end + rest) if hint is not None else (None, text)


def spreadsheet_delimiter(text: str) -> str:
    """The separator of a readings file's columns.

    Parameters
    ----------
    text : str
        The file's text.

    Returns
    -------
    str
        The one of a tab, ``;`` and ``,`` that the most of the first ``SEPARATOR_LINES``
        lines (not ``#`` comments) hold -- a tab or ``;`` before the comma where they tie
        (what a spreadsheet copies to the clipboard, and what spreadsheets in Europe write,
        with decimal commas); ``,`` where none does.  Lines about the table above it (a
        title, a name) hold none, or fewer than the table's rows do.  The Chinese
        enumeration comma ``、`` ("10.74、2.88、-9.11", as typed with a Chinese input method)
        where it is the only one the most lines hold.
    """
    lines = _first_lines(text)
    counts = {mark: sum(mark in line for line in lines) for mark in ("\t", ";", ",", "、")}
    most = max(counts.values())
    return next((mark for mark, count in counts.items() if count == most and most), ",")


SEPARATOR_LINES = 20  # lines looked at for the separator: a preamble and the table's start


def _first_lines(text: str) -> list[str]:
    """The first ``SEPARATOR_LINES`` lines that are neither empty nor ``#`` comments."""
    head = LINE_END.split(text, maxsplit=4 * SEPARATOR_LINES)[: 4 * SEPARATOR_LINES]
    return [line for line in head if line.strip() and not is_hash_comment(line)][:SEPARATOR_LINES]


def separated_by_spaces(text: str) -> bool:
    """Whether a file's columns are separated by spaces: none of its first
    ``SEPARATOR_LINES`` lines holds a tab, ``;`` or ``,`` and one at least holds two cells
    between spaces ("10.74  2.88  -9.11  -0.96", as MATLAB's ``save -ascii`` or a
    fixed-width export writes a table; the grid splits a paste so too).

    Parameters
    ----------
    text : str
        The file's text.

    Returns
    -------
    bool
        True where the columns can only be split at spaces.
    """
    lines = _first_lines(text)
    return not any(mark in line for line in lines for mark in "\t;,") and any(
        len(line.split()) > 1 for line in lines
    )


def spaced_cells(text: str) -> list[list[str]]:
    """A table separated by spaces, split into cells line by line.

    A line of numbers is split at every run of spaces.  A line of names whose words hold
    single spaces ("Position 1   Position 2", "位置 1  位置 2") is split at runs of two
    or more where that gives as many cells as the most lines of numbers hold.  Where some
    lines start with a label the rows of numbers lack ("位置 1 2 3 4", "平均值 10.71 …"),
    those rows get an empty first cell, as a spreadsheet's label column has.

    Parameters
    ----------
    text : str
        The file's text.

    Returns
    -------
    list of list of str
        Each line's cells (an empty line: no cells).
    """
    lines = LINE_END.split(text)
    split = [line.split() for line in lines]
    widths = [len(cells) for cells in split if cells and all(is_number(c) for c in cells)]
    width = Counter(widths).most_common(1)[0][0] if widths else None
    for index, (line, cells) in enumerate(zip(lines, split, strict=True)):
        if width is not None and len(cells) != width and not all(is_number(c) for c in cells):
            wide = [cell for cell in re.split(r"\s{2,}", line.strip()) if cell]
            if len(wide) == width:
                split[index] = wide
    if width is not None and any(len(c) == width + 1 and not is_number(c[0]) for c in split):
        # a label column, as the handout prints it ("位置 | 1 | 2 | 3 | 4", "平均值 …"): its
        # empty cells are lost between spaces, so the rows of numbers get them back
        split = [[""] + c if len(c) == width and all(map(is_number, c)) else c for c in split]
    return split


LINE_END = re.compile(r"\r\n|\r|\n")


DECIMAL_COMMA = re.compile(r"([+-]?\d*),(\d+(?:[eE][+-]?\d+)?)")


def decimal_point(cell: str) -> str:
    """A cell's decimal comma as a decimal point, for files whose separator is not the comma.

    Parameters
    ----------
    cell : str
        One cell, e.g. ``"10,74"`` or ``"-1,5e-3"``.

    Returns
    -------
    str
        ``"10.74"``, ``"-1.5e-3"``; any other cell unchanged.
    """
    match = DECIMAL_COMMA.fullmatch(cell.strip())
    return f"{match.group(1)}.{match.group(2)}" if match else cell


TITLE_LINES = 2  # at most this many title lines above a table are passed over


def title_lines_blanked(text: str) -> str:
    """A spreadsheet's title above the table blanked, its line kept.

    A title ("陀螺寻北实验数据", a merged cell saved as a line of its own) is a line of one
    cell that is not a number; up to ``TITLE_LINES`` of them before a header (the first
    line with a tab, semicolon or comma, one of its cells not a number) are blanked, so
    that later lines keep their numbers.  A file of one column (its lines without a
    separator, or numbers with a decimal comma) is left as it is.

    Parameters
    ----------
    text : str
        The file's text.

    Returns
    -------
    str
        The text with its title lines empty.
    """
    head = text.split("\n", TITLE_LINES + 2)  # the lines looked at, then the rest
    titles = []
    for index, line in enumerate(head[: TITLE_LINES + 2]):
        cell = line.strip()
        if not cell or is_hash_comment(cell):
            continue
        separator = next((mark for mark in "\t;," if mark in cell), None)
        if separator is not None:
            if all(is_number(c.strip()) for c in cell.split(separator) if c.strip()):
                return text  # numbers ("10,74" under a one-column header): no header here
            break
        if is_number(cell) or len(titles) == TITLE_LINES or index == len(head) - 1:
            return text  # data of one column, too many lines, or no table after them
        titles.append(index)
    else:
        return text
    for index in titles:
        head[index] = ""
    return "\n".join(head)


WHOLE_COMMA_DIGITS = re.compile(r"[+-]?\d+,\d+")  # "11,5", "-0,0045"


def one_column_of_decimal_commas(header: list[str] | None, lines: list[str]) -> bool:
    """Whether a comma-separated record is one column of numbers with decimal commas
    ("11,5" per line, as a European logger or spreadsheet writes them) rather than
    ``time_s,value`` pairs.

    It is one column when every line is a whole number, a comma and digits (a fraction),
    and a one-name header stands above ("value") or, with no header, the first numbers do
    not increase as times must.  "10,74" / "11,75" stays a time and a value; so does
    anything under a two-name header ("time_s,value").

    Parameters
    ----------
    header : list of str or None
        The header's names, if the record has one.
    lines : list of str
        The data lines, comments and a units row left out.

    Returns
    -------
    bool
        True when each line is one number with a decimal comma.
    """
    if header is not None and len(header) != 1:
        return False
    if not lines or not all(WHOLE_COMMA_DIGITS.fullmatch(line) for line in lines):
        return False
    if header is not None:
        return True
    firsts = [float(line.split(",", 1)[0]) for line in lines]  # float: any length of digits
    return any(later <= earlier for earlier, later in zip(firsts, firsts[1:], strict=False))


UNIT_NAME = re.compile(
    r"(?:°|deg|rad|mrad|dph|dps|s|ms|h|hr|min|hz|°c|℃|c|k|v|mv|lsb|度|秒|小时|摄氏度)"
    r"(?:\s*/\s*(?:s|h|hr|min|秒|小时))?"
)


UNITS_LABELS = frozenset({"unit", "units", "单位"})  # a row's label: "单位 | °/h | °/h…"


def is_units_row(cells: list[str]) -> bool:
    """Whether a row under a header only names units ("s, °/h, °/h", "(deg/h)", "度/小时"),
    as an instrument's or a spreadsheet's export writes them: every cell empty or a unit
    (the first may name the row, "单位" or "unit"), and at least one a rate ("/", dph or
    dps).  Like a unit after a column name, it is a
    note: the unit of the readings is the one the student or the script chose.

    Parameters
    ----------
    cells : list of str
        The row's cells.

    Returns
    -------
    bool
        True for a row of units only.
    """
    names = [re.sub(r"[\s()\[\]]", "", plain_text(cell)).lower() for cell in cells]
    names = [name for name in names if name]
    if names and names[0].rstrip(":：") in UNITS_LABELS:
        names = names[1:]  # "单位 | °/h | °/h…": the row named as the units' in its first cell
    return (
        bool(names)
        and all(UNIT_NAME.fullmatch(name) or RATE_LIKE.fullmatch(name) for name in names)
        and any("/" in name or name in ("dph", "dps") for name in names)
    )
