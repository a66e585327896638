"""How a record's lines split into cells: commas (quoted cells allowed), tabs or semicolons
with decimal commas (a spreadsheet's copy, a European spreadsheet), runs of spaces (the plain
text files of instruments and public data sets), a logger's date and time as one cell; and
one column of decimal commas ("0,0123" per line), which is no pair of columns.  Decided by a
record's first lines; the record itself: :mod:`app.core.static_record`.
"""

from __future__ import annotations

import csv
from collections.abc import Callable

from app.core.clock_stamps import DATE_TIME, TIME_OF_DAY
from app.core.column_names import comment_text
from app.core.record_preamble import is_header
from app.core.spreadsheet_text import (
    WHOLE_COMMA_DIGITS,
    decimal_point,
    one_column_of_decimal_commas,
)

LOOK_AHEAD_LINES = 1_000  # lines read before the layout is decided (decimal commas or not)


def quoted_split(text: str, delimiter: str) -> list[str]:
    """A line's cells between ``delimiter``s, a quoted cell unquoted (phyphox quotes its
    header's names whatever the separator, LibreOffice every text cell where asked).

    Parameters
    ----------
    text : str
        One line, without its end.
    delimiter : str
        The separator: a tab or a semicolon.

    Returns
    -------
    list of str
        The cells, unstripped; after semicolons, a spreadsheet's empty last column dropped.
    """
    text = text.rstrip(delimiter) if delimiter != "\t" else text
    if '"' not in text:
        return text.split(delimiter)
    return next(csv.reader([text], delimiter=delimiter))


def line_splitter(first: str) -> Callable[[str], list[str]]:
    """How the record's lines split into cells, decided by its first line.

    Parameters
    ----------
    first : str
        The record's first line (or the separator a spreadsheet's "sep=" line names).

    Returns
    -------
    callable
        Line → cells: commas (quotes allowed), tabs or semicolons with decimal commas (a
        spreadsheet's copy, a European spreadsheet), a logger's date and time as one cell,
        or runs of spaces (the plain text files of instruments and public data sets).
    """
    if "\t" in first:  # a spreadsheet's copy: decimal commas too, as the lab page reads it

        def tabs(text: str) -> list[str]:
            cells = [c.strip() for c in quoted_split(text, "\t")]
            return [decimal_point(c) for c in cells] if "," in text else cells

        return tabs
    if ";" in first:
        return lambda text: [c.strip().replace(",", ".") for c in quoted_split(text, ";")]
    if "," in first:

        def commas(text: str) -> list[str]:  # a spreadsheet's empty last column dropped
            if '"' in text:  # quoted: a cell holding a comma holds a decimal comma
                return [decimal_point(c.strip()) for c in next(csv.reader([text.rstrip(",")]))]
            return [c.strip() for c in text.rstrip(",").split(",")]

        return commas
    words = first.split()
    if len(words) > 2 and DATE_TIME.fullmatch(words[0]) and TIME_OF_DAY.fullmatch(words[1]):

        def stamped(text: str) -> list[str]:  # "2026-11-28 10:00:00.123  10.74"
            cells = text.split()
            return [f"{cells[0]} {cells[1]}", *cells[2:]] if len(cells) > 1 else cells

        return stamped
    return lambda text: text.split()


def one_column_with_decimal_commas(first_lines: list[str]) -> bool:
    """Whether a comma-separated record is one column of numbers with decimal commas.

    Parameters
    ----------
    first_lines : list of str
        The record's first lines, comments among them.

    Returns
    -------
    bool
        True where, header aside, each line is one number written with a decimal comma
        (:func:`app.core.spreadsheet_text.one_column_of_decimal_commas`).
    """
    texts = [line.strip().lstrip("\ufeff") for line in first_lines]
    texts = [text for text in texts if text and comment_text(text) is None]
    if not texts or "\t" in texts[0] or ";" in texts[0]:
        return False
    named = not WHOLE_COMMA_DIGITS.fullmatch(texts[0]) and is_header(texts[0].split(","))
    header = texts[0].split(",") if named else None
    return one_column_of_decimal_commas(header, texts[1:] if named else texts)


def joined_decimal_comma(text: str) -> list[str]:
    """A line of one column of decimal commas as its one cell.

    Parameters
    ----------
    text : str
        One line ("0,0123").

    Returns
    -------
    list of str
        One cell, the decimal comma read as a point ("0.0123").
    """
    return [text.replace(",", ".")]
