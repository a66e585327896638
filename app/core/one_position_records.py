"""One position's record as a gyro's own logger writes it, read for a position the student
chooses on the lab page (and the API's file upload): one reading per line, ``time,value``,
with or without a header, an IMU's record of several axes (one of its columns, the likeliest
offered), lost readings left out and said.  Records sent by a device or a script:
:mod:`app.core.position_records`; the record itself: :mod:`app.core.static_record`.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from app.core.clock_stamps import spread_within_ticks
from app.core.exceptions import UserError
from app.core.readings_data import Readings
from app.core.record_columns import ColumnChoiceNeeded
from app.core.static_record import LEFT_OUT, read_static_record
from app.core.text_files import file_text, plain_text
from app.core.units import check_named_unit

# what is said of a file read as one position's record (any other problem: it is none)
RECORD_PROBLEMS = (
    "allan.bad_line",
    "readings.not_finite",
    "csv.record_of_angles",
    "csv.unit_conflict",
    "csv.choose_column",
    "allan.no_such_column",
)


@dataclass(frozen=True)
class OnePositionRecord:
    """One position's record as read: its readings, and where the file has several
    columns that may hold the rates (the axes of an IMU), those columns (likeliest
    first) and the one read."""

    readings: Readings
    columns: tuple[str, ...] = ()
    column: str | None = None
    notes: tuple[dict, ...] = ()  # what the reader left out, as the preview says it


def parse_one_position_record(
    text: str, unit: str, column: str | None = None, *, suggest: bool = False
) -> OnePositionRecord:
    """One position's record as a gyro's own logger writes it, for a position the student
    chooses: one reading per line, ``time,value`` (seconds, a logger's clock, ns since
    1970), with or without a header, units in the header, a header behind ``#``
    (:func:`app.core.static_record.read_static_record`, which reads it in blocks); an
    IMU's record of several axes, one of its columns.  Full-width digits and signs, and
    the minus sign "−", as typed or pasted (:func:`app.core.text_files.plain_text`).

    Parameters
    ----------
    text : str
        The file's text.
    unit : str
        The unit chosen for the readings (canonical); a header naming another is refused.
    column : str, optional
        The rates' column where the file has several: a header cell, its name without the
        unit, or a number from 1.
    suggest : bool
        Where the file has several such columns and none is chosen, read the likeliest
        (a preview) rather than refuse (``csv.choose_column``).

    Returns
    -------
    OnePositionRecord
        The one position's readings (``layout`` "record"), times and case temperatures
        where given; the columns offered and the one read, where there was a choice.

    Raises
    ------
    UserError
        A line that is not a reading (its number), a record of angles rather than rates
        (``csv.record_of_angles``), a header's unit that is not ``unit``
        (``csv.unit_conflict``), a first column that is not rising times
        (``csv.not_a_record``), several columns of rates and none chosen
        (``csv.choose_column``), a chosen column the file does not have, no readings.
    """
    text = plain_text(file_text(text))
    columns: tuple[str, ...] = ()
    try:
        record = read_static_record(io.StringIO(text), column=column, guess=False, finite=False)
    except ColumnChoiceNeeded as choice:
        columns = tuple(choice.choices)
        if not columns:
            raise UserError(choice.key, **choice.params) from None
        if not suggest:
            raise UserError("csv.choose_column", columns=", ".join(columns)) from None
        column = columns[0]
        record = read_static_record(io.StringIO(text), column=column, guess=False, finite=False)
    if column is not None and not columns:  # chosen: the choice offered again
        try:
            read_static_record(io.StringIO(_head(text)), guess=False)
        except ColumnChoiceNeeded as choice:
            columns = tuple(choice.choices)
        except UserError:
            pass
    if record.times_s is not None and not bool(np.all(np.diff(record.times_s) > 0)):
        if not bool(np.all(np.diff(record.times_s) >= 0)) or np.unique(record.times_s).size < 2:
            # two columns that are not times and readings (two positions, say): no record
            raise UserError("csv.not_a_record")
        # a clock coarser than the readings (whole seconds at 10 Hz): spread over each tick
        record.times_s = spread_within_ticks(record.times_s)
    if record.angle is not None:
        raise UserError("csv.record_of_angles", unit=record.angle.unit)
    lost = _without_lost_readings(record)
    times = None if record.times_s is None else [record.times_s]
    temperatures = None if record.temperatures_c is None else [record.temperatures_c]
    check_named_unit(record.unit, unit)
    readings = Readings([record.values], None, times, "record", temperatures)
    left_out = tuple(note for note in record.notes if note["key"] in LEFT_OUT) + lost
    return OnePositionRecord(readings, columns, column if columns else None, left_out)


def _without_lost_readings(record) -> tuple[dict, ...]:
    """A logger's lost readings (NaN, ±inf) taken out of ``record``, and the note saying
    so: a position's mean needs no unbroken timeline, so they are left out, not mended."""
    lost = ~np.isfinite(record.values)
    if not lost.any():
        return ()
    if lost.all():
        raise UserError("readings.not_finite")
    kept = ~lost
    record.values = record.values[kept]
    if record.times_s is not None:
        record.times_s = record.times_s[kept]
    if record.temperatures_c is not None:
        record.temperatures_c = record.temperatures_c[kept]
    first = int(np.flatnonzero(lost)[0]) + 1
    return ({"key": "allan.note_lost_left_out", "params": {"n": int(lost.sum()), "first": first}},)


def _head(text: str, lines: int = 50) -> str:
    """The file's first lines: enough for its header and the width of its readings."""
    return "\n".join(text.splitlines()[:lines])
