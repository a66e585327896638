"""Single records: one position's readings as a device or a script sends them, and a static
record for an Allan analysis."""

from __future__ import annotations

import csv
import io
import re

import numpy as np

from app.core.column_names import column_name, is_hash_comment, readable_rate_unit
from app.core.exceptions import UserError
from app.core.readings import parse_readings_csv
from app.core.readings_data import cell_number
from app.core.record_columns import header_layout
from app.core.spreadsheet_text import (
    decimal_point,
    is_units_row,
    one_column_of_decimal_commas,
    spreadsheet_delimiter,
)
from app.core.text_files import decode_text, file_text, plain_text
from app.core.typed_numbers import is_number
from app.core.units import check_named_unit


def parse_static_record(text: str) -> np.ndarray:
    """One static record for an Allan analysis.

    Parameters
    ----------
    text : str
        A CSV in either layout with one position, or one value (or ``time_s,value``) per
        line with an optional header.

    Returns
    -------
    numpy.ndarray
        The readings, in the unit the record was written in.

    Raises
    ------
    UserError
        More than one position (``allan.one_position``) or a bad cell.
    """
    try:
        readings = parse_readings_csv(text)
    except UserError as error:
        if error.key != "csv.unknown_layout":
            raise
        return parse_position_csv(text)[0]
    if len(readings.positions) != 1:
        raise UserError(
            "allan.one_position",
            count=len(readings.positions),
        )
    return readings.positions[0]


def parse_position_csv(
    data: bytes | str, unit: str | None = None, *, as_named: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    r"""One position's readings: one value per line, or ``time_s,value`` per line.

    What a device or a script sends (``text/csv`` to the API) and the fallback for a static
    record.  Spaces may split the columns ("0.1  10.74", what a script writes).  An optional
    header on line 1 and ``#`` comment lines are skipped; lines may
    end in ``\n``, ``\r\n`` or a bare ``\r``; a row of units under the header is passed
    over.  The columns may be separated by a tab or a
    ``;`` instead of a comma (a spreadsheet's copy, a European export), and then a decimal
    comma is read as a point -- as the lab page reads a pasted or uploaded table.  A
    comma-separated record of one column with decimal commas ("11,5" per line) is read as
    such where it cannot be times and values (:func:`_decimal_comma_column`).  A Chinese
    input method's full-width digits and signs, and the minus sign "−", are read as the
    lab page reads them typed or pasted (:func:`app.core.text_files.plain_text`).

    Parameters
    ----------
    data : bytes or str
        The CSV, as bytes (UTF-8, UTF-16 with or without its mark, GB18030 or
        Windows-1252) or text.
    unit : str, optional
        The unit the readings are said to be in (canonical): a header or a row of units
        naming another rate unit for the readings' column is refused, as a logger's
        record's is (``csv.unit_conflict``).
    as_named : bool
        Refuse (``csv.not_a_record``) a header that names its two columns otherwise than
        a time in seconds and the readings, in that order ("Time (ms), Rate", "Temp (C),
        Rate", "Sample, Rate"): a record for the reader that knows such names
        (:func:`parse_one_position_record`), not times and readings by their place.

    Returns
    -------
    values : numpy.ndarray
        The readings, in the order given (their unit is the caller's to say).
    times : numpy.ndarray or None
        Each reading's time in seconds when every line gives one, else None.

    Raises
    ------
    UserError
        ``csv.encoding``, ``csv.unreadable``, ``csv.not_a_number`` or ``csv.out_of_range``
        (with the line), ``csv.one_or_two_columns``, ``csv.times_on_every_line``,
        ``csv.empty``, ``csv.unit_conflict``.
    """
    if isinstance(data, bytes):
        data = decode_text(data)
    data = plain_text(file_text(data))
    delimiter = spreadsheet_delimiter(data)
    spaced = delimiter == "," and _spaced_columns(data)
    if as_named and not _named_time_and_value(
        _first_line_cells(data, " " if spaced else delimiter)
    ):
        raise UserError("csv.not_a_record")
    if delimiter == "," and not spaced and (fast := _plain_numbers(data, unit)) is not None:
        return fast
    if spaced:  # "0.1  10.74": a script's or logger's
        rows = [line.split() for line in data.splitlines()]
    else:
        try:  # newline="": lines may end in \n, \r\n or a bare \r
            rows = list(csv.reader(io.StringIO(data, newline=""), delimiter=delimiter))
        except csv.Error as error:
            raise UserError("csv.unreadable", detail=str(error)) from None
    # a decimal comma: where the separator is not the comma, or in a cell the writer quoted
    # because it holds one ("11,51" from a European spreadsheet saving with commas)
    rows = [
        [decimal_point(cell) if delimiter != "," or "," in cell else cell for cell in row]
        for row in rows
    ]
    values, times, header = _read_rows(rows, unit)
    if times and delimiter == "," and (one_column := _decimal_comma_column(rows, header, times)):
        return np.array(one_column), None
    if not values:
        raise UserError("csv.empty")
    return np.array(values), (np.array(times) if times else None)


def _first_line_cells(data: str, delimiter: str) -> list[str] | None:
    """The first line's cells where it is a header: not a comment, not numbers."""
    end = data.find("\n")
    line = (data if end < 0 else data[:end]).strip()
    if not line or is_hash_comment(line):
        return None
    parts = line.split() if delimiter == " " else line.split(delimiter)
    cells = [cell.strip().strip('"').strip() for cell in parts]
    return None if all(is_number(cell) for cell in cells if cell) else cells


def _named_time_and_value(header: list[str] | None) -> bool:
    """Whether a header leaves the columns as their places say: none, one name, or a time
    in seconds (or a name that is no time's) then the readings."""
    names = [cell for cell in header or [] if cell]
    if len(names) != 2:
        return True  # no header, one name (perhaps over decimal commas), or not two columns
    try:
        layout = header_layout(names)
    except UserError:
        return True  # names that say nothing: by their places, as before
    return (
        layout.time == 0
        and layout.value == 1
        and layout.temperature is None
        and layout.time_scale in (None, 1.0)
    )


def _read_rows(
    rows: list[list[str]], unit: str | None
) -> tuple[list[float], list[float], list[str] | None]:
    """The readings, the times (where lines give them) and the header of a record's rows,
    line by line: a header's or a units row's unit checked, comments and blank lines
    passed over."""
    values: list[float] = []
    times: list[float] = []
    header: list[str] | None = None
    for number, row in enumerate(rows, start=1):
        cells = [c.strip() for c in row if c.strip()]
        if not cells or is_hash_comment(cells[0]):
            continue
        if number == 1 and not all(is_number(cell) for cell in cells):
            header = cells  # such as "time_s,value"
            check_named_unit(readable_rate_unit(column_name(cells[-1]).unit), unit)
            continue
        if number == 2 and header is not None and is_units_row(cells):
            check_named_unit(readable_rate_unit(cells[-1].lower()), unit)
            continue  # "s, °/h" under the names
        if len(cells) > 2:
            raise UserError(
                "csv.one_or_two_columns",
                line=number,
            )
        numbers = [
            cell_number(cell, number, name)
            for cell, name in zip(cells, ("time_s", "value")[2 - len(cells) :], strict=True)
        ]
        values.append(numbers[-1])
        if len(numbers) == 2:
            times.append(numbers[0])
    if times and len(times) != len(values):
        raise UserError("csv.times_on_every_line")
    return values, times, header


# what the lines after the first two may hold for numpy's reader to read them as
# :func:`_read_rows` would: digits, points, exponents, signs, commas, spaces and line ends
# (no "nan", "inf", "1_000", quotes or comments, which only the loop reads or refuses as it
# should)
_NUMBERS_ONLY = re.compile(r"[0-9.eE+\-, \t\r\n]*")


def _plain_numbers(data: str, unit: str | None) -> tuple[np.ndarray, np.ndarray | None] | None:
    """A comma-separated record of plain numbers read at numpy's speed, as
    :func:`parse_position_csv` reads it line by line; None for anything else, which is read
    line by line.

    The first two lines (a header, a row of units) are read line by line; the rest, where
    it is only "value" or "time_s,value" lines of plain decimals, by
    :func:`numpy.loadtxt`, whose C reader takes exactly the plain decimals
    :func:`app.core.typed_numbers.parse_decimal` takes among these characters and rounds
    them as ``float`` does.  A million lines: 0.6 s, where line by line takes 4 s.
    """
    cut = 0
    for _line in range(2):
        cut = data.find("\n", cut) + 1
        if not cut:
            return None  # a record of a line or two
    head, rest = data[:cut], data[cut:]
    if not rest.strip() or not _NUMBERS_ONLY.fullmatch(rest):
        return None
    try:
        table = np.loadtxt(io.StringIO(rest, newline=None), delimiter=",", comments=None, ndmin=2)
        values, times, header = _read_rows(list(csv.reader(io.StringIO(head, newline=""))), unit)
    except ValueError:  # a UserError too: the loop says it, as it would
        return None  # an empty cell, rows of unlike widths, "1e": the loop says which line
    if table.shape[1] > 2 or not bool(np.all(np.isfinite(table))):
        return None
    if values and bool(times) != (table.shape[1] == 2):
        return None  # times on some lines only
    if table.shape[1] == 1:
        return np.concatenate([values, table[:, 0]]), None
    times_s = np.concatenate([times, table[:, 0]])
    if header is None and not bool(np.all(np.diff(times_s) > 0)):
        return None  # perhaps one column of decimal commas (_decimal_comma_column)
    if header is not None and len(header) == 1:
        return None  # one name over two columns: perhaps decimal commas
    return np.concatenate([values, table[:, 1]]), times_s


def _spaced_columns(text: str) -> bool:
    """Whether a record's columns are split by spaces: its first data line (after any
    header or comment) has no comma and two numbers with spaces between them."""
    for line in text.splitlines()[:3]:
        cells = line.split()
        if not cells or is_hash_comment(cells[0]) or "," in line:
            continue
        if all(is_number(cell) for cell in cells):
            return len(cells) > 1
    return False


def _decimal_comma_column(
    rows: list[list[str]], header: list[str] | None, times: list[float]
) -> list[float] | None:
    """The values of a comma-separated record that is one column of numbers with decimal
    commas (:func:`app.core.readings.one_column_of_decimal_commas`), or None where it is
    ``time_s,value`` pairs as read."""
    if header is None and bool(np.all(np.diff(times) > 0)):
        return None  # rising times, as most records have: decided without a scan
    if header is not None and len(header) != 1:
        return None  # two names ("time_s,value"): pairs, whatever the numbers (no scan)
    lines: list[tuple[int, str]] = []
    for number, row in enumerate(rows, start=1):
        cells = [c.strip() for c in row if c.strip()]
        if not cells or is_hash_comment(cells[0]) or (number == 1 and header is not None):
            continue
        if number == 2 and header is not None and is_units_row(cells):
            continue
        lines.append((number, ",".join(cells)))
    if not one_column_of_decimal_commas(header, [line for _number, line in lines]):
        return None
    return [cell_number(line.replace(",", "."), number, "value") for number, line in lines]
