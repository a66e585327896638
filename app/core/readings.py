"""Readings files: the two CSV layouts shared by ``gyrolab solve``, uploads and exports.

* wide — like the handout's tables: a header ``position_1,...,position_N`` (or "位置1",
  "Position 1", "P1", the handout's own "位置 | 1 | 2 | 3 | 4", the turntable's angles
  "0° | 90° | …": :mod:`app.core.table_headers`) and one reading per row; other columns
  (``sample``, 序号, ``time``...) are ignored and blank cells allowed; a row of means or
  other summary ("平均值", "mean") is passed over and reported (``Readings.skipped``), as
  is a last row of each column's mean without a label (a spreadsheet's ``=AVERAGE``,
  :mod:`app.core.means_row`; ``Readings.means_row``).
  Turned on its side -- one row per position, its name first -- it is read the same way.

Either may be separated by semicolons or tabs instead of commas, with decimal commas
("10,74"), as spreadsheets in many European locales write them, or by spaces where a file
holds none of those (MATLAB's ``save -ascii``, a fixed-width export:
:func:`app.core.spreadsheet_text.spaced_cells`).
  A table of numbers only (no header) is read the same way when it has three or more
  position columns; a first column counting 1, 2, 3… is taken as row numbers.
* long — one reading per row beside its position: header ``position,angle_deg,value`` with
  optional ``time_s`` and ``temperature_c`` (GyroLab's export), or as students name it --
  "position, rate", "angle, reading (°/h)", "位置, 角速度" (:mod:`app.core.long_headers`),
  read by :mod:`app.core.long_readings`.  The position is keyed by its number ("3", "P3",
  "位置3"; kept, so a file of position 3 alone is position 3), a label, or the turntable's
  angle; the angle of each position is used as given.

Under either header a row naming only units ("s, °/h, °/h") is passed over, as a unit
after a column name is: the readings' unit is the one chosen with the file.
"""

from __future__ import annotations

import csv
import io
import re

import numpy as np

from app.core.column_names import column_name as record_column_name
from app.core.column_names import is_hash_comment, readable_rate_unit
from app.core.column_roles import COUNTER_NAME, names_a_time
from app.core.exceptions import UserError
from app.core.long_headers import long_columns, name_and_unit
from app.core.long_readings import parse_long
from app.core.means_row import is_row_of_means, written_decimals
from app.core.part_names import part_table
from app.core.readings_data import (
    MAX_POSITION_NUMBER,
    WIDE_COLUMN,
    Readings,
    cell_number,
    symmetric_numbers,
)
from app.core.record_columns import names_a_records_times
from app.core.spreadsheet_text import (
    decimal_point,
    is_units_row,
    separated_by_spaces,
    spaced_cells,
    spreadsheet_delimiter,
    title_lines_blanked,
    without_separator_hint,
)
from app.core.table_headers import (
    column_name,
    header_angles,
    numbered_columns,
    summary_label,
)
from app.core.text_files import file_text, plain_text
from app.core.turned_tables import label_apart, names_its_position, parse_rows_of_positions
from app.core.typed_numbers import is_number


def parse_readings_csv(text: str, part: str | None = None) -> Readings:
    """Parse either readings layout (see the module's docstring).

    Lines starting with ``#`` are comments.  A long file with a ``part`` column (GyroLab's
    session export) keeps only the rows of ``part`` when one is given.

    Parameters
    ----------
    text : str
        The file's text.
    part : {"heading", "latitude"}, optional
        Which part's rows to keep from a session export.

    Returns
    -------
    Readings
        Each position's readings, and (long layout) its angle, times and temperatures.

    Raises
    ------
    UserError
        With the line and column of the first problem.
    """
    hint, text = without_separator_hint(plain_text(file_text(text)))
    if part is not None:  # both parts' tables in one file, each under its title: part's
        text = part_table(text, part)
    text = title_lines_blanked(text)
    delimiter = hint or spreadsheet_delimiter(text)
    if hint is None and separated_by_spaces(text):  # "10.74  2.88  -9.11  -0.96"
        rows, delimiter = spaced_cells(text), " "
    else:
        try:  # newline="": lines may end in \n, \r\n or a bare \r (old Mac files)
            rows = list(csv.reader(io.StringIO(text, newline=""), delimiter=delimiter))
        except csv.Error as error:
            raise UserError("csv.unreadable", detail=str(error)) from None
    rows = [  # "10.74, 2.88, -9.11" as typed: each cell without the spaces around it
        (number, [_typed_cell(cell.strip(), delimiter) for cell in row])
        for number, row in enumerate(rows, start=1)
        if any(cell.strip() for cell in row) and not is_hash_comment(row[0])
    ]
    if not rows:
        raise UserError("csv.empty")
    try:
        return _read_table(rows, part)
    except UserError as error:
        if error.key != "csv.unknown_layout":
            raise
        return _below_lines_about_it(rows, part, error)


def _typed_cell(cell: str, delimiter: str) -> str:
    """A cell with its decimal comma read as a point, where the comma does not separate."""
    return decimal_point(cell) if delimiter != "," or "," in cell else cell


PREAMBLE_ROWS = 10  # lines about the table above it, at most: a title, a name, a date…


def _below_lines_about_it(rows, part: str | None, unknown: UserError) -> Readings:
    """A table under lines about it -- a title, the student's name and number in cells of
    their own, the date, the gyro's serial number -- more than the title lines
    :func:`app.core.spreadsheet_text.title_lines_blanked` passes over: read from the first
    row (within ``PREAMBLE_ROWS``) that heads a table in a layout this module reads, as
    long as no line above it holds two numbers (a row of readings is no line about them).
    Where none does, the first row's ``unknown`` layout is said -- at once where the first
    row is a record's header, naming its times (``time,gx,gy,gz``): the numbers under it
    are one position's record, never a table of positions with the times for position 1."""
    first = rows[0][1]
    if len(rows) > 1 and len(first) == len(rows[1][1]) and names_a_records_times(first):
        raise unknown
    for start in range(1, min(PREAMBLE_ROWS, len(rows) - 1) + 1):
        if sum(is_number(cell.strip()) for cell in rows[start - 1][1]) >= 2:
            break  # readings above: no table starts below them
        try:
            return _read_table(rows[start:], part)
        except UserError as error:
            if error.key != "csv.unknown_layout":
                raise  # a table known from this row on, with a problem in it
    raise unknown


def _read_table(rows, part: str | None) -> Readings:
    """The readings of a table whose first row is its header (or its first row of numbers,
    where it has no header): a row of units under the header passed over, and rows of
    means or other summaries left out and said, in any layout."""
    header_line, header = rows[0]
    names = [column_name(cell) for cell in header]
    written = _cells(header)
    if len(written) > 1 and not all(is_number(cell) for cell in written):  # a table's header
        again = next((line for line, row in rows[1:] if _cells(row) == written), None)
        if again is not None:  # a second table under the first ("位置 | 1 | 2 | 3 | 4" again)
            raise UserError("csv.header_again", line=again, header=header_line)
    units = rows[1][1] if len(rows) > 1 and is_units_row(rows[1][1]) else []
    if units:
        rows = [rows[0], *rows[2:]]  # "s, °/h, °/h…" under the names: a unit after a name
    # a row of means or other summary ("平均值 | 10.71 …", "mean" under a position's
    # column, a long table's "mean" row): left out and said, as the lab page's grid leaves
    # a pasted one out
    skipped = [(line, label) for line, row in rows[1:] if (label := summary_label(row))]
    if skipped:
        rows = rows[:1] + [(line, row) for line, row in rows[1:] if not summary_label(row)]
    readings = _parse_layout(rows, header_line, header, names, part)
    readings.skipped = skipped
    readings.named_unit = _named_rate_unit(header, units)
    return readings


def _named_rate_unit(header: list[str], units: list[str]) -> str | None:
    """The one rate unit a table's header ("位置1 (°/s)", "rate [rad/s]") and its row of
    units ("°/s | °/s …") name, canonical; None where they name none, or several; a rate
    in a unit GyroLab does not read ("mdeg/s") refused."""
    named = {readable_rate_unit(name_and_unit(cell)[1]) for cell in header}
    named |= {
        readable_rate_unit(re.sub(r"[\s()\[\]]", "", plain_text(cell)).lower()) for cell in units
    }
    named.discard(None)
    return named.pop() if len(named) == 1 else None


def _cells(row: list[str]) -> list[str]:
    """A row's cells as written, without the empty ones at its end."""
    cells = [cell.strip() for cell in row]
    while cells and not cells[-1]:
        cells.pop()
    return cells


def _parse_layout(rows, header_line: int, header: list[str], names, part: str | None) -> Readings:
    """The readings of a table whose first row is ``header`` (which may be numbers: no
    header), in the layout it is in."""
    long = long_columns(header)
    if long is not None:
        body = rows[1:]
        if part is not None and "part" in long:
            column = long["part"]
            body = [(n, r) for n, r in body if column < len(r) and r[column].strip() == part]
        return parse_long(long, body)
    turned = [(line, label_apart(row)) for line, row in rows]
    if len(turned) > 1 and all(names_its_position(row) for _, row in turned):
        return parse_rows_of_positions(turned)  # one row per position, its name first
    if len(turned) > 2 and all(names_its_position(row) for _, row in turned[1:]):
        # the same under a header that numbers the readings ("位置 | 1 | 2 | … | 平均值"):
        # not the handout's "位置 | 1 | 2 | 3 | 4", whose rows name no position
        return parse_rows_of_positions(turned[1:], header=turned[0][1])
    wide = {
        index: int(m.group(1)) for index, name in enumerate(names) if (m := WIDE_COLUMN.match(name))
    }
    if wide:
        readings = _parse_wide(wide, rows[1:])
        readings.layout_notes = _columns_left_out(header, wide, rows[1:])
        return readings
    numbered = numbered_columns(header, more_rows=len(rows) > 1)
    if numbered is not None:  # "位置 | 1 | 2 | 3 | 4" as the handout's tables, "0° | 90° …"
        readings = _parse_wide(numbered, rows[1:])
        readings.header_angles = header_angles(header, more_rows=len(rows) > 1)
        readings.layout_notes = _columns_left_out(header, numbered, rows[1:])
        return readings
    headerless = _headerless_columns(rows)
    if headerless is not None:
        return _parse_wide(headerless, rows)
    found = " | ".join(cell.strip() for cell in header)[:80]
    raise UserError(
        "csv.unknown_layout",
        line=header_line,
        found=found,
    )


def _headerless_columns(rows) -> dict[int, int] | None:
    """Position columns of a wide table without a header: every row numbers only, at least
    three positions (two columns may be ``time_s,value``); a first column counting 1, 2, 3…
    (or 0, 1, 2…) is a row number, not position 1."""
    width = len(rows[0][1])
    if any(len(row) != width or not all(is_number(c) for c in row) for _, row in rows):
        return None
    first = [row[0].strip() for _, row in rows]
    start = first[0]
    counting = (
        len(rows) > 1
        and start in ("0", "1")
        and first == [str(int(start) + k) for k in range(len(rows))]
    )
    skip = 1 if counting and width > 1 else 0
    if width - skip < 3:
        return None
    return {index: index - skip + 1 for index in range(skip, width)}


def _parse_wide(columns: dict[int, int], rows) -> Readings:
    """The readings of a wide table's position columns (column index → position number).
    A table of some positions only ("位置3" alone, a workbook's sheet of one position)
    keeps the numbers its header gives, as a long table does; a position named twice is
    refused."""
    if max(columns.values(), default=0) > MAX_POSITION_NUMBER:
        raise UserError(
            "csv.position_number", position=max(columns.values()), limit=MAX_POSITION_NUMBER
        )
    in_order = sorted(columns)
    revisits = symmetric_numbers([columns[index] for index in in_order])
    if revisits is not None:  # "位置1 … 位置4, 位置4 … 位置1": the symmetric order's 1 … 8
        columns = dict(zip(in_order, revisits, strict=True))
    numbers = sorted(columns.values())
    if len(set(numbers)) != len(numbers):
        raise UserError(
            "csv.position_columns",
        )
    order = sorted(columns, key=columns.get)
    values: list[list[float]] = [[] for _ in order]
    decimals = [0] * len(order)  # the most decimals a reading of each column is written to
    cells: list[str] = []
    above = decimals  # the same, for the rows above the last
    for line, row in rows:
        cells = [row[index].strip() if index < len(row) else "" for index in order]
        above = list(decimals)
        for slot, cell in enumerate(cells):
            if cell:
                values[slot].append(cell_number(cell, line, f"position_{numbers[slot]}"))
                decimals[slot] = max(decimals[slot], written_decimals(cell, significant=True) or 0)
    means_row = None
    if not any(values):  # a header alone: a template not filled in (was a 500)
        raise UserError("csv.empty")
    if all(cells) and is_row_of_means(cells, [v[:-1] for v in values], above):
        means_row = rows[-1][0]  # a spreadsheet's =AVERAGE row, unlabelled: no reading
        values = [v[:-1] for v in values]
    for number, column in zip(numbers, values, strict=True):
        if not column:
            raise UserError("readings.empty_position", position=number)
    given = None if numbers == list(range(1, len(numbers) + 1)) else numbers
    arrays = [np.array(v) for v in values]
    return Readings(arrays, None, None, "wide", numbers=given, means_row=means_row)


def _columns_left_out(header: list[str], taken: dict[int, int], rows) -> list[tuple[str, dict]]:
    """What a wide table's header names beside its positions and the readings leave out,
    said: a summary column ("平均值", "mean"), or a column of numbers whose name is no
    position's ("x", "note" …) -- not a time column, a column numbering the readings
    ("sample", "序号", or 1, 2, 3 … under any name) or a column of words (remarks), which
    hold no readings.

    Parameters
    ----------
    header : list of str
        The header's cells.
    taken : dict
        The position columns read (column index → position number).
    rows : list of (int, list of str)
        The table's rows under the header, with their line numbers.

    Returns
    -------
    list of (str, dict)
        Notes (message key, parameters), in column order.
    """
    notes: list[tuple[str, dict]] = []
    for index, cell in enumerate(header):
        if index in taken or not cell.strip():
            continue
        if not any(index < len(row) and is_number(row[index].strip()) for _, row in rows):
            continue  # remarks, or an empty column: nothing a reading could be
        if _counts([row[index].strip() if index < len(row) else "" for _, row in rows]):
            continue  # "位置 | 1 | 2 | 3 | 4" over the readings' numbers 1, 2, 3 …
        name = record_column_name(cell)
        if label := summary_label([cell]):
            notes.append(("csv.summary_column_skipped", {"label": label}))
        elif not (names_a_time(name) or COUNTER_NAME.fullmatch(name.base)):
            notes.append(("csv.column_left_out", {"column": cell.strip()[:40]}))
    return notes


def _counts(cells: list[str]) -> bool:
    """Whether a column's cells number the rows: 1, 2, 3 … (or 0, 1, 2 …)."""
    start = cells[0] if cells else ""
    return start in ("0", "1") and cells == [str(int(start) + k) for k in range(len(cells))]
