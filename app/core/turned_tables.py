"""The handout's table turned on its side: one row per position, its name first ("位置1,
10.74, 10.65, …"), as a student types it line by line or writes notes ("位置1：10.74 …",
"P2 = 2.88, 2.69"), perhaps under a header that numbers the readings ("位置 | 1 | … | 10 |
平均值"), with a summary column or each row's mean at its end left out and said.  The
other layouts: :mod:`app.core.readings`.
"""

from __future__ import annotations

import re

import numpy as np

from app.core.exceptions import UserError
from app.core.means_row import is_row_of_means, written_decimals
from app.core.readings_data import (
    MAX_POSITION_NUMBER,
    WIDE_COLUMN,
    Readings,
    cell_number,
    symmetric_numbers,
)
from app.core.table_headers import column_name, summary_label
from app.core.typed_numbers import is_number

LABEL_MARK = re.compile(r"\s*[:=]\s*")  # "位置1：10.74", "P1 = 10.74" (full width made plain)


def label_apart(row: list[str]) -> list[str]:
    """A row of notes with its position's name apart.

    Parameters
    ----------
    row : list of str
        A row's cells ("位置1：10.74 10.65 …", "P1 = 10.74, 10.65", "Position 1: 10.74 …"
        split at its spaces).

    Returns
    -------
    list of str
        Where the position's name ends in a colon or an equals sign, the name and the
        readings in cells of their own; any other row as it is.
    """
    for end, cell in enumerate(row[:3]):
        name, mark, first = _split_label(cell)
        if mark:
            label = " ".join([*row[:end], name]).strip()
            if not WIDE_COLUMN.match(column_name(label)):
                return row
            return [label, *([first] if first else []), *row[end + 1 :]]
    return row


def _split_label(cell: str) -> tuple[str, str, str]:
    """A cell split at its first colon or equals sign: (before, the mark, after)."""
    match = LABEL_MARK.search(cell)
    if match is None:
        return cell, "", ""
    return cell[: match.start()], match.group(), cell[match.end() :]


def names_its_position(row: list[str]) -> bool:
    """Whether a row is one of the table turned on its side.

    Parameters
    ----------
    row : list of str
        A row's cells.

    Returns
    -------
    bool
        True for a position's name, then readings (or empty cells).
    """
    return bool(WIDE_COLUMN.match(column_name(row[0]))) and all(
        is_number(c) for c in row[1:] if c.strip()
    )


def parse_rows_of_positions(rows, header: list[str] | None = None) -> Readings:
    """The readings of a wide table turned on its side.

    Parameters
    ----------
    rows : list of (int, list of str)
        One row per position, its name first ("位置1, 10.74, 10.65, …"), with its line
        number; the symmetric order's 1-2-3-4-4-3-2-1 names read as positions 1-8.
    header : list of str, optional
        A header above them that numbers the readings ("位置 | 1 | … | 10 | 平均值").

    Returns
    -------
    Readings
        The positions' readings (layout "wide"); a column the header names a summary
        ("平均值", "mean"), or a last column of each row's mean written to more decimals
        than its readings (a spreadsheet's =AVERAGE), left out and said
        (``layout_notes``), as such a row under a table is.

    Raises
    ------
    UserError
        A position named twice, past ``MAX_POSITION_NUMBER``, or without readings; a cell
        that is no number.
    """
    notes: list[tuple[str, dict]] = []
    summaries = [k for k, cell in enumerate(header or []) if k and summary_label([cell])]
    for k in summaries:
        notes.append(("csv.summary_column_skipped", {"label": summary_label([header[k]])}))
    cells = {
        line: [c.strip() for k, c in enumerate(row) if k and k not in summaries and c.strip()]
        for line, row in rows
    }
    if _last_column_of_means(list(cells.values())):
        cells = {line: row[:-1] for line, row in cells.items()}
        notes.append(("csv.means_column_skipped", {}))
    named = [int(WIDE_COLUMN.match(column_name(row[0])).group(1)) for _, row in rows]
    if max(named) > MAX_POSITION_NUMBER:
        raise UserError("csv.position_number", position=max(named), limit=MAX_POSITION_NUMBER)
    order = symmetric_numbers(named) or named  # 1-2-3-4-4-3-2-1: the second visits 5 … 8
    columns = {}
    for (line, _row), number in zip(rows, order, strict=True):
        if number in columns:
            raise UserError("csv.position_twice", line=line, position=number)
        columns[number] = [cell_number(c, line, f"position_{number}") for c in cells[line]]
    numbers = sorted(columns)
    for number in numbers:
        if not columns[number]:
            raise UserError("readings.empty_position", position=number)
    given = None if numbers == list(range(1, len(numbers) + 1)) else numbers
    readings = Readings([np.array(columns[k]) for k in numbers], None, None, "wide", numbers=given)
    readings.layout_notes = notes
    return readings


def _last_column_of_means(rows: list[list[str]]) -> bool:
    """Whether each row's last cell is the mean of the readings before it, written to more
    decimals than they are (:func:`app.core.means_row.is_row_of_means`, turned)."""
    if not rows or any(len(row) < 2 for row in rows):
        return False
    try:
        above = [[float(c) for c in row[:-1]] for row in rows]
    except ValueError:
        return False
    decimals = [max(written_decimals(c, significant=True) or 0 for c in row[:-1]) for row in rows]
    return is_row_of_means([row[-1] for row in rows], above, decimals)
