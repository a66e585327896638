"""What a readings file gives -- each position's readings, and where the file says them,
their angles, times and temperatures -- and the reader of one cell's number, shared by
the wide and long layouts (:mod:`app.core.readings`, :mod:`app.core.long_readings`) and
the one-position records (:mod:`app.core.position_records`)."""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from app.core.column_names import is_spreadsheet_error
from app.core.exceptions import UserError
from app.core.typed_numbers import NumberOutOfRange, parse_decimal

WIDE_COLUMN = re.compile(r"^position_(\d+)$")
SYMMETRIC_HALF = 4  # the symmetric order visits 1-2-3-4, then 4-3-2-1 as positions 5-8
MAX_POSITION_NUMBER = 360  # one position per degree of the turntable at most


@dataclass
class Readings:
    """Each position's readings (°/h as written) and what the file says beside them."""

    positions: list[np.ndarray]
    angles_deg: list[float] | None  # given by the long layout, else None
    times_s: list[np.ndarray] | None = None
    layout: str = "wide"
    temperatures_c: list[np.ndarray] | None = None  # long layout's optional temperature_c
    skipped: list[tuple[int, str]] = field(default_factory=list)  # summary rows: line, label
    numbers: list[int] | None = None  # the positions' numbers as the file gives, not 1…N
    means_row: int | None = None  # the line of an unlabelled row of means, left out
    header_angles: list[float] | None = None  # a wide header's angles ("0° | 90° …")
    named_unit: str | None = None  # the rate unit the header or a row of units names
    # how the time column was read, where not as written (a coarse clock's ticks spread)
    time_notes: list[tuple[str, dict]] = field(default_factory=list)
    # columns of a table turned on its side left out: a summary, each row's mean
    layout_notes: list[tuple[str, dict]] = field(default_factory=list)

    def left_out(self) -> list[tuple[str, dict]]:
        """What the reader passed over, as message keys and their values: each summary
        row, an unlabelled row of means, a turned table's summary or means column, and a
        time column not read as written."""
        notes = [
            ("csv.summary_skipped", {"line": line, "label": label}) for line, label in self.skipped
        ]
        if self.means_row is not None:
            notes.append(("csv.means_row_skipped", {"line": self.means_row}))
        return notes + self.layout_notes + self.time_notes


def symmetric_numbers(numbers: list[int]) -> list[int] | None:
    """The positions 1 … 8 that 1, 2, 3, 4, 4, 3, 2, 1 in order mean: the symmetric
    recording order with each position named again on its second visit, as a student heads
    the columns or rows of it -- positions 5 … 8 revisit 4 … 1 (lab-reference §3).

    Parameters
    ----------
    numbers : list of int
        The positions' numbers as a header or the rows give them, in order.

    Returns
    -------
    list of int or None
        1, 2, …, 8; None for any other sequence.
    """
    there_and_back = [*range(1, SYMMETRIC_HALF + 1), *range(SYMMETRIC_HALF, 0, -1)]
    return list(range(1, 2 * SYMMETRIC_HALF + 1)) if numbers == there_and_back else None


def cell_number(text: str, line: int, column: str) -> float:
    """A cell's number, as :func:`app.core.typed_numbers.parse_decimal` reads it.

    Parameters
    ----------
    text : str
        The cell, stripped (a decimal comma already made a point).
    line : int
        The file's line it is on, for the message.
    column : str
        The column's name, for the message.

    Returns
    -------
    float
        The number written.

    Raises
    ------
    UserError
        ``csv.not_a_number`` where it is no number; ``csv.out_of_range`` where it is
        beyond the range a reading may take (both with its line, column and first 40
        characters).
    """
    if text.startswith("#") and is_spreadsheet_error(text):  # "#DIV/0!": a failed formula
        raise UserError("csv.spreadsheet_error", line=line, column=column, value=text[:40])
    try:
        return parse_decimal(text)
    except NumberOutOfRange as error:
        raise UserError(
            "csv.out_of_range",
            line=line,
            column=column,
            value=text[:40],
        ) from error
    except ValueError as error:
        raise UserError(
            "csv.not_a_number",
            line=line,
            column=column,
            value=text[:40],
        ) from error
